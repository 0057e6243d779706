#pragma once
// The one audio-file reader of the tree (libsndfile): WAV, FLAC, Ogg, ... and headerless ".raw"
// files (16-bit little-endian PCM, mono, the pocketsphinx test data's format), which libsndfile
// reads as SF_FORMAT_RAW. Samples come as floats in [-1, 1] (16-bit PCM x / 32768, exactly), one
// channel or all of them interleaved, at the file's rate or resampled (libsoxr, very high
// quality). Errors are one line naming the file.

#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace dreamsense::audio {

struct AudioFileInfo {
  int sample_rate = 0;
  int channels = 0;
  int64_t frames = 0;
};

struct ReadAudioOptions {
  int channel = -1;             // -1: every channel, interleaved; c >= 0: channel c only
  int resample_to_hz = 0;       // 0: the file's rate; otherwise converted to this rate
  int raw_sample_rate = 16000;  // rate of headerless .raw files
  // Checks (kUnsupported "FILE: expected mono 16000 Hz, got 2 channels 44100 Hz"):
  bool require_mono = false;
  int expected_sample_rate = 0;  // 0 = any; checked before resampling
};

struct AudioClip {
  int sample_rate = 0;
  int channels = 0;            // of `samples` (1 when one channel was asked for)
  std::vector<float> samples;  // interleaved, in [-1, 1]
  int64_t frames() const {
    return channels > 0 ? static_cast<int64_t>(samples.size()) / channels : 0;
  }
};

// The header only (rate, channels, length); cheap.
Result<AudioFileInfo> audio_file_info(const std::filesystem::path& path,
                                      int raw_sample_rate = 16000);
Result<AudioClip> read_audio(const std::filesystem::path& path,
                             const ReadAudioOptions& options = {});

// Float samples in [-1, 1] to 16-bit PCM (x 32768, rounded, clipped): exact for audio that was
// 16-bit PCM.
std::vector<int16_t> to_pcm16(std::span<const float> samples);

// One-shot rate conversion of 16-bit PCM mono (the decoders' input), deterministic:
// kSoxr = libsoxr very high quality, linear phase, no dither; kSinc = a Kaiser-windowed sinc
// (32 zero crossings, beta 8), the dependency-free reference. Same rate or empty: a copy.
enum class Pcm16Resampler { kSoxr, kSinc };
std::vector<int16_t> resample_pcm16(std::span<const int16_t> in, int from_hz, int to_hz,
                                    Pcm16Resampler method = Pcm16Resampler::kSoxr);

// Audio files (.wav, .flac, .ogg, .raw; any case) directly under `dir`, sorted by path.
bool is_audio_file(const std::filesystem::path& path);
std::vector<std::filesystem::path> audio_files_in(const std::filesystem::path& dir);

}  // namespace dreamsense::audio
