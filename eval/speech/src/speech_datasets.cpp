#include "dreamsense/eval/speech_datasets.hpp"

#include "dreamsense/audio/audio_file.hpp"

#include <algorithm>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;

using WavHeader = audio::AudioFileInfo;

Result<WavHeader> wav_header(const fs::path& path) { return audio::audio_file_info(path); }

Status check_header(const fs::path& path, const WavHeader& h, int expected_rate_hz,
                    const std::string& layout) {
  if (h.channels != 1)
    return make_error(ErrorCode::kUnsupported, "{}: {} has {} channels; the {} layout needs mono",
                      path.string(), path.filename().string(), h.channels, layout);
  if (expected_rate_hz > 0 && h.sample_rate != expected_rate_hz)
    return make_error(ErrorCode::kUnsupported, "{}: sample rate {} Hz; the {} layout needs {} Hz",
                      path.string(), h.sample_rate, layout, expected_rate_hz);
  return ok_status();
}

std::vector<fs::path> wav_files(const fs::path& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".wav" && e.is_regular_file()) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

Result<Audio> read_mono_wav(const fs::path& path, int expected_rate_hz, const std::string& layout) {
  DS_ASSIGN_OR_RETURN(audio::AudioClip clip, audio::read_audio(path));
  const WavHeader h{clip.sample_rate, clip.channels, clip.frames()};
  DS_RETURN_IF_ERROR(check_header(path, h, expected_rate_hz, layout));
  Audio a;
  a.rate_hz = clip.sample_rate;
  a.samples = audio::to_pcm16(clip.samples);
  return a;
}

Result<std::vector<AudioItem>> load_fsdd(const fs::path& dir, const FsddSelection& sel) {
  if (!fs::is_directory(dir))
    return make_error(ErrorCode::kNotFound, "fsdd: {} is not a folder", dir.string());
  const fs::path rec = fs::is_directory(dir / "recordings") ? dir / "recordings" : dir;
  static const std::regex name_re(R"(^([0-9])_([A-Za-z0-9-]+)_([0-9]+)\.wav$)", std::regex::icase);
  std::vector<AudioItem> items;
  std::set<std::string> speakers_seen;
  for (const auto& p : wav_files(rec)) {
    std::smatch m;
    const std::string name = p.filename().string();
    if (!std::regex_match(name, m, name_re))
      return make_error(ErrorCode::kCorruptData,
                        "fsdd: {} does not follow the FSDD name pattern DIGIT_SPEAKER_INDEX.wav",
                        p.string());
    AudioItem it{p, m[1].str(), m[2].str(), std::stoi(m[3].str())};
    speakers_seen.insert(it.speaker);
    if (!sel.speakers.empty() &&
        std::find(sel.speakers.begin(), sel.speakers.end(), it.speaker) == sel.speakers.end())
      continue;
    if (it.index < sel.first_index || it.index > sel.last_index) continue;
    auto h = wav_header(p);
    if (!h) return tl::unexpected(h.error());
    if (auto st = check_header(p, *h, 8000, "fsdd"); !st) return tl::unexpected(st.error());
    items.push_back(std::move(it));
  }
  if (speakers_seen.empty())
    return make_error(ErrorCode::kNotFound,
                      "fsdd: no DIGIT_SPEAKER_INDEX.wav files in {} (nor in its recordings/)",
                      dir.string());
  for (const auto& s : sel.speakers)
    if (!speakers_seen.count(s)) {
      std::string have;
      for (const auto& x : speakers_seen) have += (have.empty() ? "" : ", ") + x;
      return make_error(ErrorCode::kNotFound, "fsdd: speaker {} not in {} (has {})", s,
                        rec.string(), have);
    }
  if (items.empty())
    return make_error(ErrorCode::kNotFound, "fsdd: the selection leaves no items in {}",
                      rec.string());
  std::sort(items.begin(), items.end(), [](const AudioItem& a, const AudioItem& b) {
    return std::tie(a.speaker, a.label, a.index) < std::tie(b.speaker, b.label, b.index);
  });
  return items;
}

Result<std::vector<AudioItem>> load_speech_commands(const fs::path& dir) {
  if (!fs::is_directory(dir))
    return make_error(ErrorCode::kNotFound, "speech-commands: {} is not a folder", dir.string());
  std::vector<std::string> required(std::begin(kCommandWords), std::end(kCommandWords));
  required.push_back(kUnknownLabel);
  required.push_back(kSilenceLabel);
  std::string missing;
  for (const auto& r : required)
    if (!fs::is_directory(dir / r)) missing += (missing.empty() ? "" : ", ") + r;
  if (!missing.empty())
    return make_error(ErrorCode::kNotFound,
                      "speech-commands: {} lacks the class folder(s) {} (needs yes, no, up, "
                      "down, left, right, on, off, stop, go, _unknown_, _silence_)",
                      dir.string(), missing);
  std::vector<fs::path> folders;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory()) folders.push_back(e.path());
  std::sort(folders.begin(), folders.end());
  std::vector<AudioItem> items;
  for (const auto& f : folders) {
    const std::string name = f.filename().string();
    std::string label;
    if (std::find(required.begin(), required.end(), name) != required.end())
      label = name;
    else if (!name.empty() && name[0] != '_' && name[0] != '.')
      label = kUnknownLabel;  // another word (training-set layout)
    else
      continue;
    for (const auto& p : wav_files(f)) {
      auto h = wav_header(p);
      if (!h) return tl::unexpected(h.error());
      if (auto st = check_header(p, *h, 16000, "speech-commands"); !st)
        return tl::unexpected(st.error());
      items.push_back({p, label, "", -1});
    }
  }
  if (items.empty())
    return make_error(ErrorCode::kNotFound,
                      "speech-commands: no .wav files in the class folders of {}", dir.string());
  std::stable_sort(items.begin(), items.end(),
                   [](const AudioItem& a, const AudioItem& b) { return a.label < b.label; });
  return items;
}

Result<std::vector<ListedUtterance>> load_utterance_list(const std::filesystem::path& list,
                                                         bool allow_reject) {
  std::ifstream in(list);
  if (!in || std::filesystem::is_directory(list))
    return make_error(ErrorCode::kNotFound, "cannot read the utterance list {}", list.string());
  std::vector<ListedUtterance> out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream ls(line);
    std::string audio, word;
    if (!(ls >> audio)) continue;
    ListedUtterance u;
    u.line = number;
    u.audio = list.parent_path() / audio;
    while (ls >> word) u.words += (u.words.empty() ? "" : " ") + word;
    if (u.words == "-" && allow_reject) {
      u.words.clear();
      u.reject = true;
    } else if (u.words.empty() || u.words == "-") {
      return make_error(ErrorCode::kInvalidArgument,
                        "{}:{}: expected an audio file and the words said in it{}", list.string(),
                        number, allow_reject ? " (or - for speech that must be rejected)" : "");
    }
    if (!std::filesystem::is_regular_file(u.audio))
      return make_error(ErrorCode::kNotFound, "{}:{}: audio file {} not found", list.string(),
                        number, u.audio.string());
    out.push_back(std::move(u));
  }
  if (out.empty())
    return make_error(ErrorCode::kInvalidArgument, "{}: no utterances listed", list.string());
  return out;
}

}  // namespace dreamsense::speech
