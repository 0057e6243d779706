#pragma once
// Live audio capture from an ALSA PCM device (libasound2): any device name ("default",
// "hw:1,0", "plughw:CARD=Audio,DEV=0", "null"), any channel count, interleaved int16 at the
// requested rate (no hidden ALSA resampling unless the device name asks for a plug layer).
//
// A capture thread reads whole chunks (blocking reads of chunk_s) and queues them; next() hands
// them out as AudioChunk frames (float = int16 / 32768). Stamps come from the sample count: the
// first sample of the stream is anchored once to the monotonic clock (CLOCK_MONOTONIC at the
// first read, minus the audio already buffered), and sample k is at anchor + k / rate. So stamps
// never jitter with thread scheduling. After an overrun (samples lost in ALSA) the capture
// recovers, counts the overrun and re-anchors to the clock (the lost span is a gap in the stamps,
// never a silent shift). If the consumer falls behind, the oldest queued chunks are dropped and
// counted (a live source must not grow without bound).
//
// Stamps are on the session clock: monotonic ns minus `clock_origin` (the steady-clock time of
// session stamp 0; default: the steady clock's epoch, so stamps are CLOCK_MONOTONIC ns and all
// live sources of the process agree).
//
// Errors are Results: no such device (kNotFound, names the device and how to list devices),
// device busy or unsupported format/rate/channels (kUnsupported / kIoError, with ALSA's reason),
// a device that disappears while capturing (kIoError from next()). A build without ALSA returns
// kUnsupported from open().

#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::sources {

struct AlsaAudioSourceOptions {
  SensorId sensor = "mic_array";
  std::string device = "default";
  int sample_rate = 16000;
  int channels = 4;
  double chunk_s = 0.04;   // samples per delivered chunk (ALSA period), 40 ms = one 25 Hz tick
  double buffer_s = 0.5;   // ALSA ring buffer
  size_t max_queued = 50;  // chunks waiting for next(); older ones are dropped beyond this
  std::chrono::steady_clock::time_point clock_origin{};  // steady-clock time of stamp 0
  Status check() const;                                  // lists every bad field
};

struct AlsaCaptureStats {
  uint64_t chunks = 0;          // chunks captured
  uint64_t overruns = 0;        // ALSA overruns recovered (samples lost in the device)
  uint64_t dropped_chunks = 0;  // chunks dropped because next() was not called in time
};

class AlsaAudioSource : public Source {
 public:
  // Opens and configures the device and starts capturing.
  static Result<std::unique_ptr<AlsaAudioSource>> open(const AlsaAudioSourceOptions& options);
  // Stops the capture thread and closes the device.
  ~AlsaAudioSource() override;
  AlsaAudioSource(const AlsaAudioSource&) = delete;
  AlsaAudioSource& operator=(const AlsaAudioSource&) = delete;

  // Blocks until the next chunk. After stop(): the queued chunks, then kEndOfStream. A capture
  // failure is returned once the chunks before it have been delivered.
  Result<FramePtr> next() override;
  SourceInfo info() const override;
  // Ends the capture (thread-safe; next() then drains the queue and reports end of stream).
  void stop();
  AlsaCaptureStats stats() const;

  // True when ALSA lists at least one capture-capable sound card (for tests and `live` checks).
  static bool has_capture_card();

 private:
  struct Impl;
  explicit AlsaAudioSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sources
