#pragma once
// Sample-count <-> time arithmetic shared by the audio front end. Every stamp in audio/ is
// computed from a sample count and an anchor stamp (never from a clock), exactly, in int64 ns.

#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/timestamp.hpp"

#include <cstdint>
#include <vector>

namespace dreamsense::audio {

// Duration of `frames` samples at `rate` Hz, rounded down to the nanosecond, without overflow
// for any realistic stream (the product is split so that frames * 1e9 never overflows).
constexpr Duration frames_to_duration(int64_t frames, int rate) {
  const int64_t whole = frames / rate, rest = frames % rate;
  return Duration::from_ns(whole * 1'000'000'000LL + rest * 1'000'000'000LL / rate);
}

// Number of whole samples at `rate` Hz in `d` (rounded to the nearest sample).
constexpr int64_t duration_to_frames(Duration d, int rate) {
  const int64_t ns = d.ns();
  const int64_t whole = ns / 1'000'000'000LL, rest = ns % 1'000'000'000LL;
  return whole * rate +
         (rest * rate + (rest >= 0 ? 500'000'000LL : -500'000'000LL)) / 1'000'000'000LL;
}

// A block of interleaved audio and the stamp of its first sample.
struct StampedAudio {
  Timestamp stamp;
  AudioChunk audio;
  Timestamp end() const { return stamp + frames_to_duration(audio.frames(), audio.sample_rate); }
};

}  // namespace dreamsense::audio
