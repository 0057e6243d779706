#include "dreamsense/eval/dream_gestures.hpp"

#include "dreamsense/eval/classification.hpp"
#include "dreamsense/sim/demo_session.hpp"
#include "dreamsense/sources/session.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>

namespace dreamsense::eval::actions {
namespace fs = std::filesystem;
using dreamsense::actions::ActionModel;
using dreamsense::actions::GestureModel;
using dreamsense::actions::LabelledSequence;
using dreamsense::actions::OnlineActionClassifier;
using dreamsense::actions::SkeletonFrame;
using dreamsense::actions::SkeletonSequence;

namespace {
const std::vector<std::string> kDreamLabels = {"none", "wave",      "cover_eyes", "hands_on_head",
                                               "fly",  "drive_car", "drink"};
}  // namespace

Result<std::vector<uint64_t>> parse_seeds(const std::string& spec) {
  std::vector<uint64_t> out;
  static const std::regex kRange(R"(\s*(\d{1,9})\s*(?:-\s*(\d{1,9}))?\s*)");
  size_t start = 0;
  while (start <= spec.size()) {
    const size_t comma = spec.find(',', start);
    const std::string part =
        spec.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    std::smatch m;
    if (!std::regex_match(part, m, kRange))
      return make_error(ErrorCode::kInvalidArgument,
                        "seeds '{}': expected A-B or A,B,C (non-negative integers)", spec);
    const uint64_t a = std::stoull(m[1].str());
    const uint64_t b = m[2].matched ? std::stoull(m[2].str()) : a;
    if (b < a || b - a > 100000)
      return make_error(ErrorCode::kInvalidArgument, "seeds '{}': bad range {}-{}", spec, a, b);
    for (uint64_t s = a; s <= b; ++s) out.push_back(s);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

sim::DemoScriptOptions DemoGestureData::dream_script() {
  sim::DemoScriptOptions o;
  o.gestures = sim::DemoScriptOptions::GestureSet::kDream;
  return o;
}

DemoRecording demo_recording(uint64_t seed, const DemoGestureData& data) {
  DemoRecording r;
  r.seed = seed;
  const sim::DemoScript script(seed, data.duration_s, sim::DemoGeometry{}, data.script);
  const int64_t n = static_cast<int64_t>(std::ceil(data.duration_s * data.rate_hz - 1e-9));
  r.frames.reserve(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) {
    const int64_t stamp = sim::demo_stamp_ns(k, data.rate_hz);
    const SkeletonBody body = sim::demo_skeleton_body(
        script, seed, "front.skeleton", static_cast<uint64_t>(k), stamp, data.joint_noise_m);
    r.frames.push_back(dreamsense::actions::to_skeleton_frame(body, stamp));
  }
  for (const auto& s : script.actions())
    r.truth.push_back({s.start_s, s.end_s, script.segment_label(s)});
  return r;
}

Status DreamTrainOptions::check() const {
  if (seeds.empty()) return make_error(ErrorCode::kInvalidArgument, "train dream: no seeds");
  if (!(window_s >= 0.2 && window_s <= 5))
    return make_error(ErrorCode::kInvalidArgument, "train dream: window_s must be in [0.2, 5]");
  if (!(hop_s >= 0.02 && hop_s <= 5))
    return make_error(ErrorCode::kInvalidArgument, "train dream: hop_s must be in [0.02, 5]");
  if (!(settle_s >= 0 && settle_s < 2))
    return make_error(ErrorCode::kInvalidArgument, "train dream: settle_s must be in [0, 2)");
  if (!(data.duration_s > window_s && data.duration_s <= 600))
    return make_error(ErrorCode::kInvalidArgument,
                      "train dream: duration must exceed the window and be <= 600 s");
  return method.options.check();
}

namespace {

const TruthSpan* span_at(const std::vector<TruthSpan>& truth, double t) {
  for (const auto& s : truth)
    if (t >= s.start_s && t < s.end_s) return &s;
  return truth.empty() ? nullptr : &truth.back();
}

// Sliding training windows over one recording (views into its frames).
void add_windows(const DemoRecording& r, const DreamTrainOptions& o,
                 std::vector<ActionModel::WindowRef>& out) {
  const auto& f = r.frames;
  const int64_t window = static_cast<int64_t>(std::llround(o.window_s * 1e9));
  size_t first = 0;
  const std::string subject = "seed" + std::to_string(r.seed);
  for (double end = o.window_s; end <= o.data.duration_s + 1e-9; end += o.hop_s) {
    const int64_t end_ns = static_cast<int64_t>(std::llround(end * 1e9));
    size_t last = first;
    while (last < f.size() && f[last].stamp_ns <= end_ns) ++last;  // one past
    while (first < last && f[first].stamp_ns < end_ns - window) ++first;
    if (last - first < 3) continue;
    const double t = static_cast<double>(f[last - 1].stamp_ns) * 1e-9;
    const TruthSpan* s = span_at(r.truth, t);
    if (!s || t - s->start_s < o.settle_s) continue;
    out.push_back(
        {std::span<const SkeletonFrame>(f).subspan(first, last - first), s->label, subject});
  }
}

}  // namespace

Result<ActionModel> train_dream_model(const DreamTrainOptions& o,
                                      const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  std::vector<DemoRecording> recordings;
  recordings.reserve(o.seeds.size());
  std::vector<ActionModel::WindowRef> windows;
  for (size_t i = 0; i < o.seeds.size(); ++i) {
    recordings.push_back(demo_recording(o.seeds[i], o.data));
    if (progress) progress(0.2 * static_cast<double>(i + 1) / o.seeds.size());
  }
  for (const auto& r : recordings) add_windows(r, o, windows);
  auto options = o.method.options;
  options.window_s = o.window_s;
  auto m = ActionModel::train(windows, options, [&](double f) {
    if (progress) progress(0.2 + 0.8 * f);
  });
  if (!m) return tl::unexpected(m.error());
  m->description =
      o.description.empty()
          ? fmt::format(
                "DREAM gestures from the demo generator: seeds {}-{} ({} seeds, {} s each, "
                "{} windows of {} s every {} s), method {}",
                o.seeds.front(), o.seeds.back(), o.seeds.size(), o.data.duration_s, windows.size(),
                o.window_s, o.hop_s, o.method.name)
          : o.description;
  return m;
}

Status DreamEvalOptions::check() const {
  if (seeds.empty()) return make_error(ErrorCode::kInvalidArgument, "eval dream: no test seeds");
  if (!(tolerance_s >= 0 && tolerance_s <= 2))
    return make_error(ErrorCode::kInvalidArgument, "eval dream: tolerance_s must be in [0, 2]");
  if (auto s = online.check(); !s) return s;
  if (model.empty()) {
    if (train_seeds.empty() || methods.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "eval dream: without --model, training seeds and methods are needed");
    for (uint64_t s : seeds)
      if (std::binary_search(train_seeds.begin(), train_seeds.end(), s))
        return make_error(ErrorCode::kInvalidArgument,
                          "eval dream: seed {} is both a training and a test seed", s);
  }
  return ok_status();
}

namespace {

struct TickScore {
  size_t ticks = 0, correct = 0, raw_correct = 0;
  size_t rest_ticks = 0, rest_gesture = 0;
  std::unique_ptr<ConfusionMatrix> confusion;
  Stopwatch timing;
};

TickScore score_model(std::shared_ptr<const ActionModel> model,
                      const std::vector<DemoRecording>& recordings, const DreamEvalOptions& o,
                      const std::vector<std::string>& labels) {
  TickScore s;
  s.confusion = std::make_unique<ConfusionMatrix>(labels, "other");
  for (const auto& r : recordings) {
    auto c = OnlineActionClassifier::create(model, nullptr, o.online);
    if (!c) continue;
    for (const auto& f : r.frames) {
      s.timing.start();
      const auto answer = c->push(f);
      s.timing.stop();
      const double t = static_cast<double>(f.stamp_ns) * 1e-9;
      const TruthSpan* span = span_at(r.truth, t);
      if (!span) continue;
      ++s.ticks;
      const bool exact = answer.label == span->label;
      s.raw_correct += exact;
      // Tolerance zone: within tolerance_s of the boundary before or after t.
      const TruthSpan* before = span_at(r.truth, t - o.tolerance_s);
      const TruthSpan* after = span_at(r.truth, t + o.tolerance_s);
      const bool edge = before != span || after != span;
      const bool ok = exact || (edge && ((before && answer.label == before->label) ||
                                         (after && answer.label == after->label)));
      s.correct += ok;
      if (!edge) {
        s.confusion->add(span->label, answer.label);
        if (span->label == dreamsense::actions::kNoneLabel) {
          ++s.rest_ticks;
          s.rest_gesture += answer.label != dreamsense::actions::kNoneLabel;
        }
      }
    }
  }
  return s;
}

nlohmann::json tick_json(const TickScore& s) {
  nlohmann::json j;
  j["action_accuracy"] = s.ticks ? static_cast<double>(s.correct) / s.ticks : 0.0;
  j["raw_accuracy"] = s.ticks ? static_cast<double>(s.raw_correct) / s.ticks : 0.0;
  j["rest_false_positive_rate"] =
      s.rest_ticks ? static_cast<double>(s.rest_gesture) / s.rest_ticks : 0.0;
  j["ticks"] = s.ticks;
  if (auto ms = s.timing.median_ms()) j["ms_per_window_median"] = *ms;
  j["per_class"] = s.confusion->per_class_json();
  return j;
}

}  // namespace

Result<EvalReport> run_dream_eval(const DreamEvalOptions& o,
                                  const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  std::vector<std::pair<std::string, std::shared_ptr<const ActionModel>>> models;
  std::string trained_note;
  if (!o.model.empty()) {
    auto m = ActionModel::load(o.model);
    if (!m) return tl::unexpected(m.error());
    models.emplace_back("model", std::make_shared<const ActionModel>(std::move(*m)));
  } else {
    for (size_t k = 0; k < o.methods.size(); ++k) {
      DreamTrainOptions t;
      t.seeds = o.train_seeds;
      t.data = o.data;
      t.method = o.methods[k];
      t.hop_s = o.train_hop_s;
      auto m = train_dream_model(t, [&](double f) {
        if (progress) progress(0.6 * (k + f) / o.methods.size());
      });
      if (!m) return tl::unexpected(m.error());
      models.emplace_back(o.methods[k].name, std::make_shared<const ActionModel>(std::move(*m)));
    }
    trained_note = fmt::format("methods trained on seeds {}-{} ({} seeds)", o.train_seeds.front(),
                               o.train_seeds.back(), o.train_seeds.size());
  }
  std::vector<DemoRecording> recordings;
  for (uint64_t seed : o.seeds) recordings.push_back(demo_recording(seed, o.data));
  std::vector<std::string> labels = kDreamLabels;
  for (const auto& r : recordings)
    for (const auto& s : r.truth)
      if (std::find(labels.begin(), labels.end(), s.label) == labels.end())
        labels.push_back(s.label);

  EvalReport report;
  report.task = "actions";
  report.dataset = "demo-gestures";
  report.protocol = fmt::format(
      "online sliding window over the demo generator's skeleton stream (DREAM gesture set) of "
      "seeds {}-{} ({} seeds x {} s at {} Hz, {} mm joint noise); every frame is a tick scored "
      "against the truth label at its time; within {} s of a segment boundary either neighbouring "
      "label counts; rest_false_positive_rate = rest ticks (outside those zones) answered with a "
      "gesture{}",
      o.seeds.front(), o.seeds.back(), o.seeds.size(), o.data.duration_s, o.data.rate_hz,
      o.data.joint_noise_m * 1e3, o.tolerance_s, trained_note.empty() ? "" : "; " + trained_note);
  nlohmann::json methods = nlohmann::json::object();
  TickScore main;
  for (size_t k = 0; k < models.size(); ++k) {
    TickScore s = score_model(models[k].second, recordings, o, labels);
    methods[models[k].first] = tick_json(s);
    if (k + 1 == models.size()) main = std::move(s);
    if (progress) progress(0.6 + 0.4 * (k + 1) / models.size());
  }
  report.items = main.ticks;
  const nlohmann::json mj = tick_json(main);
  report.metrics["accuracy"] = mj["action_accuracy"];
  report.metrics["action_accuracy"] = mj["action_accuracy"];
  report.metrics["raw_accuracy"] = mj["raw_accuracy"];
  report.metrics["rest_false_positive_rate"] = mj["rest_false_positive_rate"];
  report.metrics["method"] = models.back().first;
  report.metrics["confusion"] = main.confusion->confusion_json();
  if (models.size() > 1) report.metrics["methods"] = methods;
  report.per_class = main.confusion->per_class_json();
  if (auto ms = main.timing.median_ms()) report.timing["ms_per_window_median"] = *ms;
  report.extra["tolerance_s"] = o.tolerance_s;
  report.extra["seeds"] = o.seeds;
  if (!o.model.empty())
    report.extra["model"] = {{"file", o.model.string()},
                             {"description", models[0].second->description}};
  return report;
}

// ---- custom gestures ----

Result<std::vector<GestureSegment>> read_gesture_segments(const fs::path& file) {
  std::ifstream in(file);
  if (!in)
    return make_error(ErrorCode::kNotFound, "{}: cannot open the segments file", file.string());
  static const std::regex kLine(
      R"(\s*([-+]?[0-9]*\.?[0-9]+)\s+([-+]?[0-9]*\.?[0-9]+)\s+([A-Za-z0-9_-]+)\s*)");
  std::vector<GestureSegment> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    std::smatch m;
    if (!std::regex_match(line, m, kLine))
      return make_error(ErrorCode::kCorruptData, "{}:{}: expected 'start_s end_s label', got '{}'",
                        file.string(), n, line);
    GestureSegment s{std::stod(m[1].str()), std::stod(m[2].str()), m[3].str(), n};
    if (!(s.end_s > s.start_s) || s.start_s < 0)
      return make_error(ErrorCode::kCorruptData, "{}:{}: end ({}) must be after start ({}) >= 0",
                        file.string(), n, s.end_s, s.start_s);
    out.push_back(std::move(s));
  }
  if (out.empty())
    return make_error(ErrorCode::kCorruptData, "{}: no segment lines", file.string());
  return out;
}

Result<SkeletonSequence> read_session_skeleton(const fs::path& dir, const std::string& stream) {
  auto manifest = sources::read_manifest(dir);
  if (!manifest) return tl::unexpected(manifest.error());
  std::string id = stream;
  if (id.empty()) {
    for (const auto& s : manifest->streams)
      if (s.kind == SensorKind::kSkeleton) {
        id = s.id;
        break;
      }
    if (id.empty())
      return make_error(ErrorCode::kNotFound, "{}: the session has no skeleton stream",
                        dir.string());
  } else if (const auto* s = manifest->find(id); !s || s->kind != SensorKind::kSkeleton) {
    return make_error(ErrorCode::kNotFound, "{}: no skeleton stream '{}'", dir.string(), id);
  }
  sources::SessionReaderOptions ro;
  ro.only = {id};
  ro.decode_threads = 0;
  auto reader = sources::SessionReader::open(dir, ro);
  if (!reader) return tl::unexpected(reader.error());
  SkeletonSequence out;
  std::optional<cv::Vec3d> previous;
  const cv::Vec3d seat(0, 0, 1.1);
  auto anchor = [](const SkeletonBody& b) -> std::optional<cv::Vec3d> {
    for (JointId id : {JointId::kShoulderCenter, JointId::kHead, JointId::kSpine})
      if (dreamsense::actions::joint_usable(b.joint(id))) return b.joint(id).position_m;
    return std::nullopt;
  };
  while (true) {
    auto frame = (*reader)->next();
    if (!frame) {
      if (is_end_of_stream(frame.error())) break;
      return tl::unexpected(frame.error());
    }
    const auto* sk = (*frame)->as<Skeleton>();
    if (!sk) continue;
    SkeletonFrame f;
    f.stamp_ns = (*frame)->stamp.ns();
    const SkeletonBody* best = nullptr;
    double best_d = 1e30;
    for (const auto& b : sk->bodies) {
      const auto a = anchor(b);
      if (!a) continue;
      const double d = cv::norm(*a - (previous ? *previous : seat));
      if (d < best_d) {
        best_d = d;
        best = &b;
      }
    }
    if (best) {
      f = dreamsense::actions::to_skeleton_frame(*best, f.stamp_ns);
      previous = anchor(*best);
    }
    if (!out.empty() && f.stamp_ns <= out.back().stamp_ns) continue;
    out.push_back(f);
  }
  if (out.empty())
    return make_error(ErrorCode::kNotFound, "{}: skeleton stream '{}' has no frames", dir.string(),
                      id);
  return out;
}

Result<GestureTrainReport> train_gestures_from_session(
    const fs::path& dir, const fs::path& segments_file,
    const dreamsense::actions::GestureOptions& options, const std::string& stream) {
  auto segments = read_gesture_segments(segments_file);
  if (!segments) return tl::unexpected(segments.error());
  auto frames = read_session_skeleton(dir, stream);
  if (!frames) return tl::unexpected(frames.error());
  std::vector<LabelledSequence> demos;
  for (const auto& s : *segments) {
    LabelledSequence d;
    d.label = s.label;
    d.source = fmt::format("{}:{} ({:.2f}-{:.2f} s)", segments_file.filename().string(), s.line,
                           s.start_s, s.end_s);
    for (const auto& f : *frames) {
      const double t = static_cast<double>(f.stamp_ns) * 1e-9;
      if (t >= s.start_s && t <= s.end_s) d.frames.push_back(f);
    }
    demos.push_back(std::move(d));
  }
  auto model = GestureModel::train(demos, options);
  if (!model) return tl::unexpected(model.error());
  GestureTrainReport r{std::move(*model), {}};
  for (size_t c = 0; c < r.model.labels().size(); ++c) {
    int n = 0;
    for (const auto& t : r.model.templates()) n += t.label == r.model.labels()[c];
    r.lines.push_back(fmt::format(
        "{}: {} example(s), threshold {:.3f}{}", r.model.labels()[c], n, r.model.thresholds()[c],
        n < 3 ? " (fewer than 3 examples: the threshold is a guess)" : ""));
  }
  return r;
}

}  // namespace dreamsense::eval::actions
