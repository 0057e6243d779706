#pragma once
// A Source wrapper that converts audio streams to the analysers' sample rate (e.g. a 48 kHz
// USB array or a 44.1 kHz recording to 16 kHz) with audio::Resampler (libsoxr): every other
// frame passes through unchanged.
//
// Stamps come from sample counts (Resampler), so a resampled stream is exactly as continuous as
// its input; a gap in the input stamps is a gap in the output. Order: frames of one stream stay
// in order; across streams, a resampled chunk can come out after a frame of another stream that
// is up to the resampler's latency (a few ms) later than it, which the synchroniser tolerates.
// At the end of the wrapped source the resamplers are flushed (the tails come out) before
// kEndOfStream. info() reports the converted rates.

#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"

#include <memory>
#include <vector>

namespace dreamsense::sources {

struct ResamplingSourceOptions {
  int sample_rate = 16000;        // output rate of every converted stream
  std::vector<SensorId> streams;  // audio streams to convert; empty = every audio stream
  // audio::ResamplerQuality as an int: 0 quick .. 3 high (default) .. 4 very high.
  int quality = 3;
  Status check() const;
};

class ResamplingSource : public Source {
 public:
  // Fails if a listed stream is not an audio stream of `inner`.
  static Result<std::unique_ptr<ResamplingSource>> wrap(std::unique_ptr<Source> inner,
                                                        const ResamplingSourceOptions& options);
  ~ResamplingSource() override;
  Result<FramePtr> next() override;
  SourceInfo info() const override;
  Source& inner() { return *inner_; }

 private:
  struct Impl;
  ResamplingSource(std::unique_ptr<Source> inner, std::unique_ptr<Impl> impl);
  std::unique_ptr<Source> inner_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sources
