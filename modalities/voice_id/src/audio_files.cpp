#include "dreamsense/voice_id/audio_files.hpp"

#include "dreamsense/audio/audio_file.hpp"

#include <algorithm>
#include <system_error>

namespace dreamsense::voice_id {
namespace fs = std::filesystem;

Result<LabelledAudio> read_audio_file(const fs::path& path, const std::string& speaker) {
  audio::ReadAudioOptions ro;
  ro.channel = 0;
  DS_ASSIGN_OR_RETURN(audio::AudioClip clip, audio::read_audio(path, ro));
  LabelledAudio a;
  a.speaker = speaker;
  a.source = path.string();
  a.samples = std::move(clip.samples);
  a.sample_rate = clip.sample_rate;
  return a;
}

Result<std::vector<LabelledAudio>> read_speaker_folders(const fs::path& dir, int max_per_speaker) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: folder missing", dir.string());
  std::vector<fs::path> speakers;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_directory() && !audio::audio_files_in(e.path()).empty()) speakers.push_back(e.path());
  std::sort(speakers.begin(), speakers.end());
  if (speakers.empty())
    return make_error(ErrorCode::kNotFound,
                      "{}: no speaker folders with audio (expected DIR/<speaker>/*.wav)",
                      dir.string());
  std::vector<LabelledAudio> out;
  for (const auto& s : speakers) {
    auto files = audio::audio_files_in(s);
    if (max_per_speaker > 0 && static_cast<int>(files.size()) > max_per_speaker)
      files.resize(static_cast<size_t>(max_per_speaker));
    for (const auto& f : files) {
      auto a = read_audio_file(f, s.filename().string());
      if (!a) return tl::unexpected(a.error());
      out.push_back(std::move(*a));
    }
  }
  return out;
}

Result<std::vector<LabelledAudio>> read_background(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: background folder missing", dir.string());
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec))
    if (e.is_regular_file() && audio::is_audio_file(e.path())) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  if (files.empty())
    return make_error(ErrorCode::kNotFound, "{}: no audio files for the background model",
                      dir.string());
  std::vector<LabelledAudio> out;
  for (const auto& f : files) {
    auto a = read_audio_file(f, "background");
    if (!a) return tl::unexpected(a.error());
    out.push_back(std::move(*a));
  }
  return out;
}

}  // namespace dreamsense::voice_id
