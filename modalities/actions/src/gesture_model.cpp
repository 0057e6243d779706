#include "dreamsense/actions/gesture_model.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "model_file.hpp"

namespace dreamsense::actions {
namespace fs = std::filesystem;
namespace {

constexpr std::array<JointId, kGestureJoints> kArmJoints = {
    JointId::kElbowLeft,  JointId::kWristLeft,  JointId::kHandLeft,
    JointId::kElbowRight, JointId::kWristRight, JointId::kHandRight};

constexpr double kInf = std::numeric_limits<double>::infinity();

const ModelFileKind& gestures_file_kind() {
  static const ModelFileKind kind{"gestures model", GestureModel::kFormatName,
                                  GestureModel::kFormatVersion, "dreamsense train gestures"};
  return kind;
}

Error gestures_corrupt(const fs::path& path, const std::string& what) {
  return model_corrupt(gestures_file_kind(), path, what);
}

}  // namespace

Status GestureOptions::check() const {
  if (auto s = body.check(); !s) return s;
  if (samples < 4 || samples > 256)
    return make_error(ErrorCode::kInvalidArgument, "gestures: samples must be in [4, 256]");
  if (!(band > 0 && band <= 1))
    return make_error(ErrorCode::kInvalidArgument, "gestures: band must be in (0, 1]");
  if (!(history_factor >= 1 && history_factor <= 4))
    return make_error(ErrorCode::kInvalidArgument, "gestures: history_factor must be in [1, 4]");
  if (!(end_slack >= 0 && end_slack < 1))
    return make_error(ErrorCode::kInvalidArgument, "gestures: end_slack must be in [0, 1)");
  if (!(min_speed > 0 && min_speed <= 1 && max_speed >= 1 && max_speed <= 4))
    return make_error(ErrorCode::kInvalidArgument,
                      "gestures: need 0 < min_speed <= 1 <= max_speed <= 4");
  if (!(threshold_factor > 0) || !(min_threshold > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "gestures: threshold_factor and min_threshold must be > 0");
  if (!(min_duration_s > 0 && max_duration_s > min_duration_s))
    return make_error(ErrorCode::kInvalidArgument,
                      "gestures: need 0 < min_duration_s < max_duration_s");
  return ok_status();
}

std::vector<float> GestureModel::trajectory(std::span<const SkeletonFrame> frames) const {
  return resampled_trajectory(frames, options_.samples);
}

std::vector<float> GestureModel::resampled_trajectory(std::span<const SkeletonFrame> frames,
                                                      int n) const {
  const NormalizedWindow w = normalize_window(frames, options_.body);
  if (!w.usable) return {};
  const std::vector<cv::Vec3f> r = resample_positions(w, n);
  std::vector<float> out(static_cast<size_t>(n) * kGestureDims);
  for (int t = 0; t < n; ++t) {
    const cv::Vec3f* f = &r[static_cast<size_t>(t) * kJointCount];
    const cv::Vec3f centre = f[static_cast<int>(JointId::kShoulderCenter)];
    for (int j = 0; j < kGestureJoints; ++j) {
      const cv::Vec3f d = f[static_cast<int>(kArmJoints[static_cast<size_t>(j)])] - centre;
      for (int k = 0; k < 3; ++k)
        out[static_cast<size_t>(t) * kGestureDims + static_cast<size_t>(j) * 3 + k] = d[k];
    }
  }
  return out;
}

double GestureModel::dtw(const std::vector<float>& a, const std::vector<float>& b) const {
  const int n = static_cast<int>(a.size() / kGestureDims);
  const int m = static_cast<int>(b.size() / kGestureDims);
  if (n == 0 || m == 0) return kInf;
  const int band = std::max(1, static_cast<int>(std::lround(options_.band * std::max(n, m))));
  const double norm = 1.0 / std::sqrt(static_cast<double>(kGestureJoints));
  auto cost = [&](int i, int j) {
    double s = 0;
    const float* x = &a[static_cast<size_t>(i) * kGestureDims];
    const float* y = &b[static_cast<size_t>(j) * kGestureDims];
    for (int k = 0; k < kGestureDims; ++k) {
      const double e = static_cast<double>(x[k]) - y[k];
      s += e * e;
    }
    return std::sqrt(s) * norm;
  };
  // Symmetric DTW (diagonal steps weigh 2), normalised by n + m: the mean cost along the path.
  std::vector<double> prev(static_cast<size_t>(m), kInf), cur(static_cast<size_t>(m), kInf);
  for (int i = 0; i < n; ++i) {
    std::fill(cur.begin(), cur.end(), kInf);
    const int centre = m > 1 && n > 1 ? i * (m - 1) / (n - 1) : 0;
    const int j0 = std::max(0, centre - band), j1 = std::min(m - 1, centre + band);
    for (int j = j0; j <= j1; ++j) {
      const double c = cost(i, j);
      double best;
      if (i == 0 && j == 0) {
        best = 2 * c;
      } else {
        best = kInf;
        if (i > 0 && j > 0) best = std::min(best, prev[static_cast<size_t>(j - 1)] + 2 * c);
        if (i > 0) best = std::min(best, prev[static_cast<size_t>(j)] + c);
        if (j > 0) best = std::min(best, cur[static_cast<size_t>(j - 1)] + c);
      }
      cur[static_cast<size_t>(j)] = best;
    }
    std::swap(prev, cur);
  }
  return prev[static_cast<size_t>(m - 1)] / (n + m);
}

Result<GestureModel> GestureModel::train(const std::vector<LabelledSequence>& demos,
                                         const GestureOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  GestureModel g;
  g.options_ = o;
  if (demos.empty())
    return make_error(ErrorCode::kInvalidArgument, "gestures: no demonstrations given");
  for (const auto& d : demos) {
    if (d.label.empty() || d.label == "none")
      return make_error(ErrorCode::kInvalidArgument, "gestures: {}: '{}' is not a gesture label",
                        d.source, d.label);
    if (d.frames.size() < 3)
      return make_error(ErrorCode::kInvalidArgument,
                        "gestures: {}: only {} skeleton frames (need at least 3)", d.source,
                        d.frames.size());
    const double dur =
        static_cast<double>(d.frames.back().stamp_ns - d.frames.front().stamp_ns) * 1e-9;
    if (dur < o.min_duration_s || dur > o.max_duration_s)
      return make_error(ErrorCode::kInvalidArgument,
                        "gestures: {}: lasts {:.2f} s (accepted: {}-{} s)", d.source, dur,
                        o.min_duration_s, o.max_duration_s);
    GestureTemplate t;
    t.label = d.label;
    t.duration_s = dur;
    t.trajectory = g.trajectory(d.frames);
    if (t.trajectory.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "gestures: {}: no usable body (no torso joint tracked)", d.source);
    if (std::find(g.labels_.begin(), g.labels_.end(), d.label) == g.labels_.end())
      g.labels_.push_back(d.label);
    g.templates_.push_back(std::move(t));
  }
  for (const auto& label : g.labels_) {
    std::vector<const GestureTemplate*> mine;
    for (const auto& t : g.templates_)
      if (t.label == label) mine.push_back(&t);
    double worst = 0;
    for (size_t i = 0; i < mine.size(); ++i) {
      double nearest = kInf;
      for (size_t j = 0; j < mine.size(); ++j)
        if (i != j) nearest = std::min(nearest, g.dtw(mine[i]->trajectory, mine[j]->trajectory));
      if (std::isfinite(nearest)) worst = std::max(worst, nearest);
    }
    g.thresholds_.push_back(mine.size() < 2
                                ? 2 * o.min_threshold
                                : std::max(o.min_threshold, o.threshold_factor * worst));
  }
  return g;
}

double GestureModel::history_s() const {
  double longest = 0;
  for (const auto& t : templates_) longest = std::max(longest, t.duration_s);
  return longest * options_.history_factor;
}

double GestureModel::distance(std::span<const SkeletonFrame> window,
                              const GestureTemplate& t) const {
  return dtw(trajectory(window), t.trajectory);
}

// Open-begin subsequence DTW of template t (m samples) in history h (n samples at the same
// rate): the mean local cost along the cheapest path that ends in the last end_slack of the
// history and spans min_speed..max_speed times the template.
double GestureModel::subsequence_dtw(const std::vector<float>& h,
                                     const std::vector<float>& t) const {
  const int m = static_cast<int>(t.size() / kGestureDims);
  const int n = static_cast<int>(h.size() / kGestureDims);
  if (m == 0 || n == 0) return kInf;
  const double norm = 1.0 / std::sqrt(static_cast<double>(kGestureJoints));
  auto cost = [&](int i, int j) {
    double s = 0;
    const float* x = &t[static_cast<size_t>(i) * kGestureDims];
    const float* y = &h[static_cast<size_t>(j) * kGestureDims];
    for (int k = 0; k < kGestureDims; ++k) {
      const double e = static_cast<double>(x[k]) - y[k];
      s += e * e;
    }
    return std::sqrt(s) * norm;
  };
  // Step pattern with slopes 1/2..2 (Sakoe & Chiba's symmetric P = 1 without the intermediate
  // cells): predecessors (i-1, j-1), (i-1, j-2), (i-2, j-1); so a match spans m/2..2m samples.
  struct Cell {
    double cost = kInf;
    int length = 0, start = 0;
  };
  std::vector<Cell> d(static_cast<size_t>(m) * n);
  auto at = [&](int i, int j) -> Cell& { return d[static_cast<size_t>(i) * n + j]; };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) {
      const double c = cost(i, j);
      if (i == 0) {
        at(i, j) = {c, 1, j};  // open begin: the template may start anywhere in the history
        continue;
      }
      const Cell* from = nullptr;
      auto consider = [&](int pi, int pj) {
        if (pi < 0 || pj < 0) return;
        const Cell& p = at(pi, pj);
        if (std::isfinite(p.cost) && (!from || p.cost / p.length < from->cost / from->length))
          from = &p;
      };
      consider(i - 1, j - 1);
      consider(i - 1, j - 2);
      consider(i - 2, j - 1);
      if (from) at(i, j) = {from->cost + c, from->length + 1, from->start};
    }
  double out = kInf;
  const int first_end = std::max(0, n - 1 - static_cast<int>(std::lround(options_.end_slack * m)));
  for (int j = first_end; j < n; ++j) {
    const Cell& c = at(m - 1, j);
    if (c.length == 0) continue;
    const int span = j - c.start + 1;
    if (span < options_.min_speed * m || span > options_.max_speed * m) continue;
    out = std::min(out, c.cost / c.length);
  }
  return out;
}

GestureMatch GestureModel::match(std::span<const SkeletonFrame> history) const {
  GestureMatch out;
  out.distance = kInf;
  if (history.empty() || templates_.empty()) {
    out.no_data = true;
    return out;
  }
  const int64_t now = history.back().stamp_ns;
  std::map<int64_t, std::vector<float>> cache;  // template duration (ns) -> history trajectory
  std::vector<double> best(labels_.size(), kInf);
  for (const auto& t : templates_) {
    const size_t c =
        static_cast<size_t>(std::find(labels_.begin(), labels_.end(), t.label) - labels_.begin());
    const int64_t dur = static_cast<int64_t>(std::llround(t.duration_s * 1e9));
    auto it = cache.find(dur);
    if (it == cache.end()) {
      const int64_t len =
          static_cast<int64_t>(std::llround(t.duration_s * options_.history_factor * 1e9));
      size_t first = history.size() - 1;
      while (first > 0 && history[first - 1].stamp_ns >= now - len) --first;
      const std::span<const SkeletonFrame> w = history.subspan(first);
      const double span_ns = static_cast<double>(now - w.front().stamp_ns);
      std::vector<float> traj;
      // At least one template length of history, resampled at the template's rate.
      if (w.size() >= 3 && span_ns >= 0.95 * static_cast<double>(dur)) {
        const int n = std::max(3, static_cast<int>(std::lround(options_.samples * span_ns /
                                                               static_cast<double>(dur))));
        traj = resampled_trajectory(w, n);
      }
      it = cache.emplace(dur, std::move(traj)).first;
    }
    if (it->second.empty()) continue;
    best[c] = std::min(best[c], subsequence_dtw(it->second, t.trajectory));
  }
  double best_ratio = kInf;
  size_t best_class = 0;
  for (size_t c = 0; c < labels_.size(); ++c) {
    out.class_distance.emplace_back(labels_[c], best[c]);
    const double ratio = best[c] / thresholds_[c];
    if (ratio < best_ratio) {
      best_ratio = ratio;
      best_class = c;
      out.distance = best[c];
      out.threshold = thresholds_[c];
    }
  }
  if (!std::isfinite(best_ratio)) out.no_data = true;
  if (best_ratio <= 1) out.label = labels_[best_class];
  return out;
}

Status GestureModel::save(const fs::path& path) const {
  const fs::path tmp = path.string() + ".part";
  try {
    cv::FileStorage f(tmp.string(), cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!f.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
    const auto& o = options_;
    f << "format" << kFormatName << "version" << kFormatVersion;
    f << "body"
      << "{"
      << "up" << cv::Mat(o.body.up).reshape(1, 1) << "normalize_facing"
      << static_cast<int>(o.body.normalize_facing) << "normalize_scale"
      << static_cast<int>(o.body.normalize_scale) << "min_confidence" << o.body.min_confidence
      << "default_body_size_m" << o.body.default_body_size_m << "normalize_bones"
      << static_cast<int>(o.body.normalize_bones) << "}";
    f << "samples" << o.samples << "band" << o.band << "history_factor" << o.history_factor
      << "end_slack" << o.end_slack << "min_speed" << o.min_speed << "max_speed" << o.max_speed
      << "threshold_factor" << o.threshold_factor << "min_threshold" << o.min_threshold
      << "min_duration_s" << o.min_duration_s << "max_duration_s" << o.max_duration_s;
    f << "gestures"
      << "[";
    for (size_t c = 0; c < labels_.size(); ++c)
      f << "{"
        << "label" << labels_[c] << "threshold" << thresholds_[c] << "}";
    f << "]";
    f << "templates"
      << "[";
    for (const auto& t : templates_) {
      cv::Mat traj(static_cast<int>(t.trajectory.size() / kGestureDims), kGestureDims, CV_32F,
                   const_cast<float*>(t.trajectory.data()));
      f << "{"
        << "label" << t.label << "duration_s" << t.duration_s << "trajectory" << traj << "}";
    }
    f << "]";
    f.release();
  } catch (const cv::Exception& e) {
    return make_error(ErrorCode::kIoError, "{}: cannot write ({})", path.string(), e.msg);
  }
  return rename_model_file(tmp, path);
}

Result<GestureModel> GestureModel::load(const fs::path& path) {
  GestureModel g;
  try {
    DS_ASSIGN_OR_RETURN(cv::FileStorage f, open_model_file(gestures_file_kind(), path));
    auto need = [&](const cv::FileNode& parent, const char* key) -> cv::FileNode {
      cv::FileNode n = parent[key];
      if (n.empty()) throw std::runtime_error(std::string("missing key ") + key);
      return n;
    };
    auto& o = g.options_;
    const cv::FileNode body = need(f.root(), "body");
    cv::Mat up;
    need(body, "up") >> up;
    if (up.total() != 3)
      return tl::unexpected(gestures_corrupt(path, "body.up must have 3 numbers"));
    up.convertTo(up, CV_64F);
    o.body.up = cv::Vec3d(up.at<double>(0), up.at<double>(1), up.at<double>(2));
    o.body.normalize_facing = static_cast<int>(need(body, "normalize_facing")) != 0;
    o.body.normalize_scale = static_cast<int>(need(body, "normalize_scale")) != 0;
    o.body.min_confidence = static_cast<float>(need(body, "min_confidence"));
    o.body.default_body_size_m = static_cast<double>(need(body, "default_body_size_m"));
    o.body.normalize_bones = static_cast<int>(need(body, "normalize_bones")) != 0;
    o.samples = static_cast<int>(need(f.root(), "samples"));
    o.band = static_cast<double>(need(f.root(), "band"));
    o.history_factor = static_cast<double>(need(f.root(), "history_factor"));
    o.end_slack = static_cast<double>(need(f.root(), "end_slack"));
    o.min_speed = static_cast<double>(need(f.root(), "min_speed"));
    o.max_speed = static_cast<double>(need(f.root(), "max_speed"));
    o.threshold_factor = static_cast<double>(need(f.root(), "threshold_factor"));
    o.min_threshold = static_cast<double>(need(f.root(), "min_threshold"));
    o.min_duration_s = static_cast<double>(need(f.root(), "min_duration_s"));
    o.max_duration_s = static_cast<double>(need(f.root(), "max_duration_s"));
    if (auto s = o.check(); !s) return tl::unexpected(gestures_corrupt(path, s.error().message));
    const cv::FileNode gs = need(f.root(), "gestures");
    if (!gs.isSeq() || gs.size() == 0)
      return tl::unexpected(gestures_corrupt(path, "gestures is not a non-empty list"));
    for (const auto& n : gs) {
      g.labels_.push_back(static_cast<std::string>(need(n, "label")));
      g.thresholds_.push_back(static_cast<double>(need(n, "threshold")));
      if (!(g.thresholds_.back() > 0))
        return tl::unexpected(
            gestures_corrupt(path, "threshold of '" + g.labels_.back() + "' <= 0"));
    }
    const cv::FileNode ts = need(f.root(), "templates");
    if (!ts.isSeq()) return tl::unexpected(gestures_corrupt(path, "templates is not a list"));
    for (const auto& n : ts) {
      GestureTemplate t;
      t.label = static_cast<std::string>(need(n, "label"));
      t.duration_s = static_cast<double>(need(n, "duration_s"));
      cv::Mat traj;
      need(n, "trajectory") >> traj;
      if (traj.type() != CV_32F || traj.cols != kGestureDims || traj.rows != o.samples ||
          !traj.isContinuous())
        return tl::unexpected(
            gestures_corrupt(path, fmt::format("template of '{}': expected {} x {} floats", t.label,
                                               o.samples, kGestureDims)));
      if (std::find(g.labels_.begin(), g.labels_.end(), t.label) == g.labels_.end())
        return tl::unexpected(
            gestures_corrupt(path, "template of unknown gesture '" + t.label + "'"));
      if (!(t.duration_s > 0))
        return tl::unexpected(
            gestures_corrupt(path, "template of '" + t.label + "' has no duration"));
      t.trajectory.assign(traj.ptr<float>(0), traj.ptr<float>(0) + traj.total());
      g.templates_.push_back(std::move(t));
    }
  } catch (const cv::Exception& e) {
    return tl::unexpected(
        gestures_corrupt(path, "unreadable YAML, truncated or corrupt: " +
                                   (e.err.empty() ? std::string("parse error") : e.err)));
  } catch (const std::exception& e) {
    return tl::unexpected(gestures_corrupt(path, e.what()));
  }
  return g;
}

}  // namespace dreamsense::actions
