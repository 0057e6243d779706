#pragma once
// Dataset layouts for `dreamsense eval speech` (spec/cli.md): FSDD and Speech Commands.
// Loaders list the items and check every WAV header (rate, channels) up front, so a bad file
// fails before a long run with a message naming it; the audio itself is read per item.

#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::speech {

struct AudioItem {
  std::filesystem::path path;
  std::string label;    // FSDD: "0".."9"; Speech Commands: the class folder name
  std::string speaker;  // FSDD only
  int index = -1;       // FSDD take index (official split: 0-4 test, 5-49 train)
};

struct Audio {
  std::vector<int16_t> samples;  // mono
  int rate_hz = 0;
};

// Reads a WAV (any libsndfile format) that must be mono at `expected_rate_hz` (0 = any rate).
// Wrong rate/channels: kUnsupported naming the file, what it has and what the layout needs.
Result<Audio> read_mono_wav(const std::filesystem::path& path, int expected_rate_hz,
                            const std::string& layout = "audio");

// Free Spoken Digit Dataset: `DIR/recordings/D_SPEAKER_INDEX.wav` or `DIR/D_SPEAKER_INDEX.wav`,
// 8 kHz mono. `speakers` (empty = all) and `indices` [first, last] (e.g. 0-4, the official test
// split) select items. Other files are ignored; .wav files with another name pattern are an
// error (they would silently shrink the set). Sorted by speaker, digit, index.
struct FsddSelection {
  std::vector<std::string> speakers;
  int first_index = 0, last_index = 1 << 30;
};
Result<std::vector<AudioItem>> load_fsdd(const std::filesystem::path& dir,
                                         const FsddSelection& selection = {});

// Speech Commands test layout: class folders yes, no, up, down, left, right, on, off, stop, go,
// _unknown_, _silence_ of 16 kHz mono WAVs (all twelve must exist). Other word folders (the
// training-set layout: bed, bird, ...) are counted as _unknown_; folders starting with '_'
// other than the two above (e.g. _background_noise_) are ignored. Sorted by class, file name.
inline constexpr const char* kCommandWords[] = {"yes",   "no", "up",  "down", "left",
                                                "right", "on", "off", "stop", "go"};
inline constexpr const char* kUnknownLabel = "_unknown_";
inline constexpr const char* kSilenceLabel = "_silence_";
Result<std::vector<AudioItem>> load_speech_commands(const std::filesystem::path& dir);

// Utterance list (train speech, eval speech --dataset list): a text file, one utterance per line,
// "AUDIO WORDS..." with AUDIO relative to the list's folder (WAV/FLAC/... of any rate, mono or
// channel 0; or 16 kHz s16le .raw); '#' starts a comment, blank lines are skipped. For
// evaluation the single word "-" marks speech that must be rejected (out of grammar, noise).
// Missing audio, a line without words (or "-" where it is not allowed): "FILE:LINE: problem".
struct ListedUtterance {
  std::filesystem::path audio;
  std::string words;    // empty for "-"
  bool reject = false;  // "-": nothing in the grammar was said
  int line = 0;
};
Result<std::vector<ListedUtterance>> load_utterance_list(const std::filesystem::path& list,
                                                         bool allow_reject);

}  // namespace dreamsense::speech
