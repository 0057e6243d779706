#pragma once
// Enrolment and evaluation audio as labelled clips (first channel, read by audio::read_audio:
// WAV/FLAC/... and headerless 16 kHz s16le ".raw" files), and the one-folder-per-speaker layout
// that `train voices --dataset folders` and the demo's enrolment use.

#include "dreamsense/voice_id/voice_model.hpp"

#include <filesystem>
#include <vector>

namespace dreamsense::voice_id {

// Samples in [-1, 1] of the first channel; sample_rate set. Error names the file.
Result<LabelledAudio> read_audio_file(const std::filesystem::path& path,
                                      const std::string& speaker = {});

// DIR/<speaker>/<files>: every subfolder holding audio is one speaker (sorted by name), its
// recordings sorted by file name. `max_per_speaker` > 0 keeps only the first that many.
// Error: DIR missing, or no speaker folder with audio.
Result<std::vector<LabelledAudio>> read_speaker_folders(const std::filesystem::path& dir,
                                                        int max_per_speaker = 0);

// Every audio file under DIR, recursively (sorted by path), labelled "background".
Result<std::vector<LabelledAudio>> read_background(const std::filesystem::path& dir);

}  // namespace dreamsense::voice_id
