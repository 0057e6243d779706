#include "dreamsense/eval/voice_eval.hpp"

#include "dreamsense/voice_id/audio_files.hpp"

#include <algorithm>
#include <chrono>
#include <regex>
#include <set>
#include <tuple>

namespace dreamsense::voice_id {
namespace fs = std::filesystem;
using nlohmann::json;

size_t VoiceDataset::recordings() const {
  size_t n = 0;
  for (const auto& [id, list] : speakers) n += list.size();
  return n;
}

namespace {

Result<VoiceDataset> load_fsdd(const fs::path& dir_in) {
  fs::path dir = dir_in;
  std::error_code ec;
  if (fs::is_directory(dir / "recordings", ec)) dir = dir / "recordings";
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: fsdd folder missing", dir_in.string());
  static const std::regex kName(R"((\d+)_([A-Za-z0-9]+)_(\d+)\.wav)");
  struct Item {
    int index, digit;
    fs::path path;
  };
  std::map<std::string, std::vector<Item>> items;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::smatch m;
    const std::string name = e.path().filename().string();
    if (!e.is_regular_file() || !std::regex_match(name, m, kName)) continue;
    items[m[2].str()].push_back({std::stoi(m[3].str()), std::stoi(m[1].str()), e.path()});
  }
  if (items.empty())
    return make_error(ErrorCode::kNotFound,
                      "{}: no FSDD recordings (digit_speaker_index.wav) in this folder",
                      dir.string());
  VoiceDataset d;
  d.name = "fsdd";
  d.dir = dir_in;
  for (auto& [speaker, list] : items) {
    std::sort(list.begin(), list.end(), [](const Item& a, const Item& b) {
      return std::tie(a.index, a.digit) < std::tie(b.index, b.digit);
    });
    for (const auto& it : list) {
      auto a = read_audio_file(it.path, speaker);
      if (!a) return tl::unexpected(a.error());
      d.speakers[speaker].push_back(std::move(*a));
    }
  }
  return d;
}

Result<VoiceDataset> load_folders(const fs::path& dir) {
  auto all = read_speaker_folders(dir);
  if (!all) return tl::unexpected(all.error());
  VoiceDataset d;
  d.name = "folders";
  d.dir = dir;
  for (auto& a : *all) d.speakers[a.speaker].push_back(std::move(a));
  return d;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

Result<VoiceDataset> load_voice_dataset(const std::string& name, const fs::path& dir,
                                        const std::vector<std::string>& only) {
  Result<VoiceDataset> d = make_error(
      ErrorCode::kInvalidArgument, "voices: dataset '{}' is not supported (fsdd, folders)", name);
  if (name == "fsdd") d = load_fsdd(dir);
  if (name == "folders") d = load_folders(dir);
  if (!d || only.empty()) return d;
  std::map<std::string, std::vector<LabelledAudio>> kept;
  for (const auto& s : only) {
    auto it = d->speakers.find(s);
    if (it == d->speakers.end()) {
      std::string have;
      for (const auto& [id, list] : d->speakers) have += (have.empty() ? "" : ", ") + id;
      return make_error(ErrorCode::kNotFound, "{}: no speaker '{}' (speakers: {})", dir.string(), s,
                        have);
    }
    kept[s] = std::move(it->second);
  }
  d->speakers = std::move(kept);
  return d;
}

Status VoiceTrainRunOptions::check() const {
  if (dir.empty())
    return make_error(ErrorCode::kInvalidArgument, "train voices: no dataset folder");
  if (enroll < 0)
    return make_error(ErrorCode::kInvalidArgument, "train voices: --enroll must be >= 0");
  return train.check();
}

namespace {
Result<std::vector<LabelledAudio>> background_audio(const fs::path& dir) {
  if (dir.empty()) return std::vector<LabelledAudio>{};
  return read_background(dir);
}
}  // namespace

Result<VoiceModel> run_voice_train(const VoiceTrainRunOptions& o,
                                   const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto d = load_voice_dataset(o.dataset, o.dir, o.speakers);
  if (!d) return tl::unexpected(d.error());
  std::vector<LabelledAudio> enrol;
  for (auto& [id, list] : d->speakers)
    for (size_t i = 0; i < list.size() && (o.enroll == 0 || static_cast<int>(i) < o.enroll); ++i)
      enrol.push_back(std::move(list[i]));
  auto bg = background_audio(o.background);
  if (!bg) return tl::unexpected(bg.error());
  return train_voice_model(
      enrol, *bg, o.train,
      o.background.empty() ? std::string()
                           : fmt::format("{} ({} recordings)", o.background.string(), bg->size()),
      progress);
}

Status VoiceEvalOptions::check() const {
  if (dir.empty()) return make_error(ErrorCode::kInvalidArgument, "eval voices: no dataset folder");
  if (enroll < 0)
    return make_error(ErrorCode::kInvalidArgument, "eval voices: --enroll must be >= 0");
  if (model.empty() && enroll == 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "eval voices: --enroll must be >= 1 without --model");
  return train.check();
}

Result<eval::EvalReport> run_voice_eval(const VoiceEvalOptions& o,
                                        const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  std::vector<std::string> wanted = o.speakers;
  if (!wanted.empty())
    for (const auto& u : o.unknown)
      if (std::find(wanted.begin(), wanted.end(), u) == wanted.end()) wanted.push_back(u);
  auto d = load_voice_dataset(o.dataset, o.dir, wanted);
  if (!d) return tl::unexpected(d.error());
  const std::set<std::string> unknown(o.unknown.begin(), o.unknown.end());
  for (const auto& u : unknown)
    if (!d->speakers.count(u))
      return make_error(ErrorCode::kNotFound, "{}: no speaker '{}' to hold out", o.dir.string(), u);

  const auto t_train = std::chrono::steady_clock::now();
  VoiceModel model;
  std::set<std::string> known;
  struct Test {
    const LabelledAudio* audio;
    bool is_known;
  };
  std::vector<Test> tests;
  json per_class = json::object();
  if (!o.model.empty()) {
    auto m = VoiceModel::load(o.model);
    if (!m) return tl::unexpected(m.error());
    model = std::move(*m);
    for (const auto& s : model.speakers) known.insert(s.id);
    for (const auto& u : unknown) known.erase(u);
  } else {
    std::vector<LabelledAudio> enrol;
    for (const auto& [id, list] : d->speakers) {
      if (unknown.count(id)) continue;
      if (static_cast<int>(list.size()) <= o.enroll)
        return make_error(ErrorCode::kInvalidArgument,
                          "eval voices: speaker '{}' has {} recordings, not more than --enroll {}",
                          id, list.size(), o.enroll);
      for (int i = 0; i < o.enroll; ++i) enrol.push_back(list[static_cast<size_t>(i)]);
      known.insert(id);
    }
    if (known.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "eval voices: every speaker is held out as unknown");
    auto bg = background_audio(o.background);
    if (!bg) return tl::unexpected(bg.error());
    auto m = train_voice_model(enrol, *bg, o.train, {}, [&](double f) {
      if (progress) progress(0.3 * f);
    });
    if (!m) return tl::unexpected(m.error());
    model = std::move(*m);
  }
  const double train_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_train).count();
  for (const auto& [id, list] : d->speakers) {
    const bool is_known = known.count(id) > 0;
    // Unknown speakers: every recording is a test (none was enrolled).
    const size_t first = !is_known && o.model.empty() ? 0 : static_cast<size_t>(o.enroll);
    for (size_t i = first; i < list.size(); ++i) tests.push_back({&list[i], is_known});
  }
  if (tests.empty() && !o.model.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "eval voices: no test recordings left (with --model the first --enroll {} "
                      "recordings of each speaker are skipped; --enroll 0 tests all of them)",
                      o.enroll);
  if (tests.empty())
    return make_error(ErrorCode::kInvalidArgument, "eval voices: no test recordings left");

  std::map<std::string, std::map<std::string, int>> confusion;
  std::map<std::string, std::pair<int, int>> recall;  // id -> (right, total)
  int known_total = 0, closed_right = 0, open_right = 0, false_reject = 0;
  int unknown_total = 0, unknown_rejected = 0;
  std::vector<double> ms;
  json items = json::array();
  for (size_t i = 0; i < tests.size(); ++i) {
    const auto& t = tests[i];
    const auto t0 = std::chrono::steady_clock::now();
    auto r = identify(model, t.audio->samples, t.audio->sample_rate);
    if (!r) return make_error(r.error().code, "{}: {}", t.audio->source, r.error().message);
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const std::string& truth = t.audio->speaker;
    if (t.is_known) {
      ++known_total;
      const bool right = r->best_id == truth;
      closed_right += right;
      open_right += r->speaker_id == truth;
      false_reject += r->unknown();
      recall[truth].first += right;
      recall[truth].second++;
      confusion[truth][r->best_id.empty() ? kUnknownSpeaker : r->best_id]++;
    } else {
      ++unknown_total;
      unknown_rejected += r->unknown();
      recall[truth].first += r->unknown();
      recall[truth].second++;
      confusion[truth][r->speaker_id]++;
    }
    items.push_back({{"file", fs::path(t.audio->source).filename().string()},
                     {"truth", t.is_known ? truth : std::string(kUnknownSpeaker)},
                     {"speaker_id", r->speaker_id},
                     {"best", r->best_id},
                     {"llr", r->llr},
                     {"frames", r->frames}});
    if (progress) progress(0.3 + 0.7 * static_cast<double>(i + 1) / tests.size());
  }
  json metrics = json::object();
  metrics["accuracy"] =
      known_total ? json(static_cast<double>(closed_right) / known_total) : json(nullptr);
  metrics["open_set_accuracy"] =
      known_total ? json(static_cast<double>(open_right) / known_total) : json(nullptr);
  metrics["false_reject_rate"] =
      known_total ? json(static_cast<double>(false_reject) / known_total) : json(nullptr);
  if (unknown_total > 0)
    metrics["unknown_reject_rate"] = static_cast<double>(unknown_rejected) / unknown_total;
  for (const auto& [id, rc] : recall)
    per_class[id] = {{"recall", rc.second ? static_cast<double>(rc.first) / rc.second : 0.0},
                     {"tests", rc.second},
                     {"role", known.count(id) ? "enrolled" : "unknown"}};
  std::string speakers_list, unknown_list;
  for (const auto& k : known) speakers_list += (speakers_list.empty() ? "" : ",") + k;
  for (const auto& u : unknown) unknown_list += (unknown_list.empty() ? "" : ",") + u;
  eval::EvalReport out;
  out.task = "voices";
  out.dataset = d->name;
  out.items = tests.size();
  out.extra["dataset_dir"] = o.dir.string();
  out.protocol =
      o.model.empty()
          ? fmt::format(
                "GMM-UBM ({} components, MAP relevance {}{}); first {} recordings of each "
                "enrolled speaker ({}) enrol, the rest are tests{}; UBM on {}",
                model.ubm.components(), model.map.relevance,
                model.map.adapt_weights || model.map.adapt_variances ? ", full adaptation"
                                                                     : ", means only",
                o.enroll, speakers_list,
                unknown.empty() ? std::string() : "; held out as unknown: " + unknown_list,
                model.background)
          : fmt::format("model {} ({}); first {} recordings of each speaker skipped",
                        o.model.string(), speakers_list, o.enroll);
  out.metrics = metrics;
  out.timing = {{"ms_per_utterance_median", median(ms)}, {"train_s", train_s}};
  out.per_class = per_class;
  out.extra["confusion"] = confusion;
  out.extra["model"] = {{"components", model.ubm.components()},
                        {"dimension", model.ubm.dimension()},
                        {"threshold", model.threshold},
                        {"background", model.background}};
  out.extra["items"] = items;
  return out;
}

}  // namespace dreamsense::voice_id
