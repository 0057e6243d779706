// One-pass evaluation of trackers (see the header for the protocol).

#include "dreamsense/eval/tracking_eval.hpp"

#include "dreamsense/objects/tracker.hpp"

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cmath>
#include <numeric>

namespace dreamsense::eval {
namespace {

double mean_of(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

std::vector<std::string> expand(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const auto& n : names) {
    if (n == "all") {
      for (const auto& k : objects::tracker_names())
        if (std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
    } else if (std::find(out.begin(), out.end(), n) == out.end()) {
      out.push_back(n);
    }
  }
  return out;
}

nlohmann::json scores_json(const TrackScores& s) {
  return {{"auc", s.auc},
          {"precision20", s.precision20},
          {"mean_iou", s.mean_iou},
          {"mean_center_error_px", s.mean_center_error_px},
          {"fps", s.fps}};
}

}  // namespace

Status TrackingEvalOptions::check() const {
  if (dataset != "otb" && dataset != "mil")
    return make_error(ErrorCode::kInvalidArgument,
                      "eval tracking: dataset '{}' is not supported (supported: otb, mil)",
                      dataset);
  if (trackers.empty())
    return make_error(ErrorCode::kInvalidArgument, "eval tracking: no tracker given");
  for (const auto& n : trackers) {
    if (n == "all") continue;
    if (auto t = objects::make_tracker(n); !t)
      return make_error(ErrorCode::kInvalidArgument, "eval tracking: {}", t.error().message);
  }
  if (max_frames < 0 || start_frame < 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "eval tracking: max_frames and start_frame must be >= 0");
  return ok_status();
}

const std::vector<double>& success_thresholds() {
  static const std::vector<double> t = [] {
    std::vector<double> v;
    for (int i = 0; i <= 20; ++i) v.push_back(0.05 * i);
    return v;
  }();
  return t;
}

TrackScores score_run(const TrackRun& run) {
  TrackScores s;
  const auto& th = success_thresholds();
  s.success.assign(th.size(), 0.0);
  if (!run.iou.empty()) {
    for (size_t k = 0; k < th.size(); ++k) {
      size_t n = 0;
      for (double v : run.iou) n += v > th[k] + 1e-12 ? 1 : 0;
      s.success[k] = static_cast<double>(n) / static_cast<double>(run.iou.size());
    }
    s.auc = mean_of(s.success);
    size_t close = 0;
    for (double e : run.centre_error) close += e <= 20.0 ? 1 : 0;
    s.precision20 = static_cast<double>(close) / static_cast<double>(run.centre_error.size());
    s.mean_iou = mean_of(run.iou);
    s.mean_center_error_px = mean_of(run.centre_error);
  }
  s.fps = run.seconds > 0 ? static_cast<double>(run.frames) / run.seconds : 0.0;
  return s;
}

Result<TrackRun> run_tracker(std::string_view name, const std::vector<cv::Mat>& frames,
                             const std::vector<std::optional<cv::Rect2d>>& truth) {
  DS_CHECK_EQ(frames.size(), truth.size());
  size_t first = 0;
  while (first < truth.size() && !truth[first]) ++first;
  if (first == truth.size())
    return make_error(ErrorCode::kInvalidArgument, "no labelled frame to start from");
  auto tracker = objects::make_tracker(name);
  if (!tracker) return tl::unexpected(tracker.error());
  TrackRun run;
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (auto s = (*tracker)->init(frames[first], *truth[first]); !s)
    return make_error(s.error().code, "{} (frame {})", s.error().message, first + 1);
  double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  run.frames = 1;
  for (size_t i = first + 1; i < frames.size(); ++i) {
    const auto t1 = Clock::now();
    auto u = (*tracker)->update(frames[i]);
    seconds += std::chrono::duration<double>(Clock::now() - t1).count();
    if (!u) return make_error(u.error().code, "{} (frame {})", u.error().message, i + 1);
    ++run.frames;
    if (!u->found) ++run.lost;
    if (!truth[i]) continue;
    run.iou.push_back(objects::iou(u->box, *truth[i]));
    const cv::Point2d d = objects::box_centre(u->box) - objects::box_centre(*truth[i]);
    run.centre_error.push_back(std::hypot(d.x, d.y));
  }
  run.seconds = seconds;
  return run;
}

Result<EvalReport> run_tracking_eval(const TrackingEvalOptions& o,
                                     const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto sequences = read_tracking_dataset(o.dataset, o.dir, o.start_frame);
  if (!sequences) return tl::unexpected(sequences.error());
  const std::vector<std::string> names = expand(o.trackers);
  EvalReport report;
  report.task = "tracking";
  report.dataset = o.dataset;
  report.protocol =
      "one-pass evaluation (OPE) from the first labelled box, no re-initialisation; scored: "
      "labelled frames after the first; success AUC over IoU thresholds 0:0.05:1 (IoU > t), "
      "precision at 20 px centre error; fps over init+update with frames decoded beforehand; "
      "several sequences: metrics averaged per sequence";
  std::map<std::string, std::vector<TrackScores>> per_tracker;
  std::map<std::string, std::pair<size_t, double>> speed;  // frames, seconds
  std::map<std::string, size_t> lost;
  nlohmann::json per_sequence = nlohmann::json::object();
  nlohmann::json warnings = nlohmann::json::array();
  const double total = static_cast<double>(sequences->size() * names.size());
  size_t done = 0;
  for (const auto& seq : *sequences) {
    for (const auto& w : seq.warnings) warnings.push_back(w);
    size_t n = seq.frames.size();
    if (o.max_frames > 0) n = std::min(n, static_cast<size_t>(o.max_frames));
    std::vector<cv::Mat> frames;
    std::vector<std::optional<cv::Rect2d>> truth(seq.truth.begin(),
                                                 seq.truth.begin() + static_cast<long>(n));
    frames.reserve(n);
    for (size_t i = 0; i < n; ++i) {
      cv::Mat img = cv::imread(seq.frames[i].string(), cv::IMREAD_COLOR);
      if (img.empty())
        return make_error(ErrorCode::kCorruptData, "{}: cannot decode image",
                          seq.frames[i].string());
      if (!frames.empty() && img.size() != frames.front().size())
        return make_error(ErrorCode::kCorruptData, "{}: size {}x{} differs from the first frame's",
                          seq.frames[i].string(), img.cols, img.rows);
      frames.push_back(std::move(img));
    }
    size_t first = 0;
    while (first < n && !truth[first]) ++first;
    size_t scored = 0;
    for (size_t i = first + 1; i < n; ++i) scored += truth[i] ? 1 : 0;
    report.items += scored;
    nlohmann::json js = {
        {"frames", n},
        {"scored_frames", scored},
        {"image_size", {frames.empty() ? 0 : frames[0].cols, frames.empty() ? 0 : frames[0].rows}}};
    for (const auto& name : names) {
      auto run = run_tracker(name, frames, truth);
      if (!run)
        return make_error(run.error().code, "{}: {}: {}", seq.name, name, run.error().message);
      const TrackScores s = score_run(*run);
      per_tracker[name].push_back(s);
      speed[name].first += run->frames;
      speed[name].second += run->seconds;
      lost[name] += run->lost;
      js["metrics"][name] = scores_json(s);
      js["metrics"][name]["lost_frames"] = run->lost;
      if (progress) progress(static_cast<double>(++done) / total);
    }
    per_sequence[seq.name] = js;
  }
  nlohmann::json curves = nlohmann::json::object();
  for (const auto& name : names) {
    const auto& v = per_tracker[name];
    TrackScores m;
    m.success.assign(success_thresholds().size(), 0.0);
    for (const auto& s : v) {
      m.auc += s.auc / static_cast<double>(v.size());
      m.precision20 += s.precision20 / static_cast<double>(v.size());
      m.mean_iou += s.mean_iou / static_cast<double>(v.size());
      m.mean_center_error_px += s.mean_center_error_px / static_cast<double>(v.size());
      for (size_t k = 0; k < m.success.size(); ++k)
        m.success[k] += s.success[k] / static_cast<double>(v.size());
    }
    m.fps =
        speed[name].second > 0 ? static_cast<double>(speed[name].first) / speed[name].second : 0;
    report.metrics[name] = scores_json(m);
    report.timing[name] = {
        {"frames", speed[name].first},
        {"seconds", speed[name].second},
        {"ms_per_frame", speed[name].first
                             ? 1000.0 * speed[name].second / static_cast<double>(speed[name].first)
                             : 0.0}};
    curves[name] = m.success;
  }
  report.extra["trackers"] = names;
  report.extra["sequences"] = per_sequence;
  report.extra["success_curve"] = {{"thresholds", success_thresholds()}, {"success", curves}};
  if (!warnings.empty()) report.extra["warnings"] = warnings;
  return report;
}

}  // namespace dreamsense::eval
