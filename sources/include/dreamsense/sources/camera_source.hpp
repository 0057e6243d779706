#pragma once
// Live colour capture through OpenCV's VideoCapture: a V4L2 device ("0", "/dev/video2"), a
// GStreamer/FFmpeg URL, or a video file (played back at its own frame rate, so a file stands in
// for a camera in tests and dry runs).
//
// A capture thread grabs frames as the device delivers them and stamps each one with the
// monotonic clock at the grab, minus `clock_origin` (the steady-clock time of session stamp 0),
// so all live sources of the process share one clock. If the consumer falls behind, the oldest
// queued frames are dropped and counted: a live source never grows without bound and never
// blocks the device.
//
// Errors are Results: a device that does not open (kNotFound, with the device string), a
// requested size the device ignores is not an error (the actual size is reported by size()),
// a device that stops delivering frames ends the stream (kEndOfStream for a file, kIoError for
// a device that vanished).

#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

namespace dreamsense::sources {

struct CameraSourceOptions {
  SensorId sensor = "camera";
  std::string device = "0";  // all digits: V4L2 index; otherwise a path or URL
  int width = 0;             // requested size; 0 = the device's default
  int height = 0;
  double fps = 0;         // requested rate; 0 = the device's default
  size_t max_queued = 8;  // frames waiting for next(); older ones are dropped beyond this
  std::chrono::steady_clock::time_point clock_origin{};  // steady-clock time of stamp 0
  Status check() const;                                  // lists every bad field
};

struct CameraCaptureStats {
  uint64_t frames = 0;          // frames grabbed
  uint64_t dropped_frames = 0;  // frames dropped because next() was not called in time
};

class CameraSource : public Source {
 public:
  static Result<std::unique_ptr<CameraSource>> open(const CameraSourceOptions& options);
  ~CameraSource() override;
  CameraSource(const CameraSource&) = delete;
  CameraSource& operator=(const CameraSource&) = delete;

  // Blocks until the next frame. After stop() or the end of a file: the queued frames, then
  // kEndOfStream.
  Result<FramePtr> next() override;
  SourceInfo info() const override;
  void stop();  // thread-safe
  CameraCaptureStats stats() const;
  cv::Size size() const;  // the size frames actually have
  double fps() const;     // the device's reported rate (the requested one when it reports 0)

 private:
  struct Impl;
  explicit CameraSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sources
