#include "dreamsense/voice_id/audio_files.hpp"

#include <sndfile.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <system_error>

namespace dreamsense::voice_id {
namespace fs = std::filesystem;

namespace {
bool is_audio(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e == ".wav" || e == ".flac" || e == ".ogg" || e == ".raw";
}
}  // namespace

Result<LabelledAudio> read_audio_file(const fs::path& path, const std::string& speaker) {
  LabelledAudio a;
  a.speaker = speaker;
  a.source = path.string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    return make_error(ErrorCode::kNotFound, "{}: audio file missing", path.string());
  if (path.extension() == ".raw") {  // pocketsphinx test data: s16le mono 16 kHz
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    a.samples.resize(bytes.size() / 2);
    for (size_t i = 0; i < a.samples.size(); ++i) {
      const auto lo = static_cast<uint8_t>(bytes[2 * i]),
                 hi = static_cast<uint8_t>(bytes[2 * i + 1]);
      a.samples[i] = static_cast<int16_t>(static_cast<uint16_t>(lo | (hi << 8))) / 32768.0f;
    }
    a.sample_rate = 16000;
    return a;
  }
  SF_INFO info{};
  SNDFILE* f = sf_open(path.string().c_str(), SFM_READ, &info);
  if (!f)
    return make_error(ErrorCode::kCorruptData, "{}: cannot read audio ({})", path.string(),
                      sf_strerror(nullptr));
  std::vector<float> all(static_cast<size_t>(info.frames) * static_cast<size_t>(info.channels));
  const sf_count_t got = sf_readf_float(f, all.data(), info.frames);
  sf_close(f);
  if (info.channels <= 0 || info.samplerate <= 0)
    return make_error(ErrorCode::kCorruptData, "{}: no audio channels", path.string());
  a.samples.resize(static_cast<size_t>(std::max<sf_count_t>(got, 0)));
  for (size_t i = 0; i < a.samples.size(); ++i)
    a.samples[i] = all[i * static_cast<size_t>(info.channels)];
  a.sample_rate = info.samplerate;
  return a;
}

std::vector<fs::path> audio_files_in(const fs::path& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && is_audio(e.path())) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

Result<std::vector<LabelledAudio>> read_speaker_folders(const fs::path& dir, int max_per_speaker) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: folder missing", dir.string());
  std::vector<fs::path> speakers;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_directory() && !audio_files_in(e.path()).empty()) speakers.push_back(e.path());
  std::sort(speakers.begin(), speakers.end());
  if (speakers.empty())
    return make_error(ErrorCode::kNotFound,
                      "{}: no speaker folders with audio (expected DIR/<speaker>/*.wav)",
                      dir.string());
  std::vector<LabelledAudio> out;
  for (const auto& s : speakers) {
    auto files = audio_files_in(s);
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
    if (e.is_regular_file() && is_audio(e.path())) files.push_back(e.path());
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
