#include "dreamsense/head_pose/self_calibration.hpp"

#include "dreamsense/core/statistics.hpp"
#include "dreamsense/head_pose/head_pose_estimator.hpp"

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

namespace dreamsense::head_pose {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRadiansPerDegree = CV_PI / 180.0;

bool finite(const cv::Vec3d& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}
bool finite(const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

// Centroid of the finite landmarks [from, to] of 68 pixels; nullopt when any is missing.
std::optional<cv::Point2d> centroid_px(const std::vector<cv::Point2d>& p, int from, int to) {
  cv::Point2d s(0, 0);
  for (int i = from; i <= to; ++i) {
    if (!finite(p[static_cast<size_t>(i)])) return std::nullopt;
    s += p[static_cast<size_t>(i)];
  }
  return s * (1.0 / (to - from + 1));
}

struct View {
  const CameraModel* camera;
  const std::vector<cv::Point2d>* px;
  double interocular_px;
  cv::Vec3d centre;
  std::vector<cv::Vec3d> ray;  // per option point, world unit direction; NaN when missing
};

struct Solution {
  std::vector<cv::Vec3d> points;
  std::vector<double> view_rms_px;  // per kept view, over finite points
};

Solution solve(const std::vector<View>& views, const std::vector<size_t>& kept, size_t n_points,
               double min_cos_spread) {
  Solution s;
  s.points.assign(n_points, cv::Vec3d(kNaN, kNaN, kNaN));
  for (size_t k = 0; k < n_points; ++k) {
    cv::Matx33d A = cv::Matx33d::zeros();
    cv::Vec3d b(0, 0, 0);
    int n = 0;
    double min_cos = 1;
    for (size_t a = 0; a < kept.size(); ++a) {
      const View& v = views[kept[a]];
      const cv::Vec3d& d = v.ray[k];
      if (!finite(d)) continue;
      for (size_t c = 0; c < a; ++c) {
        const cv::Vec3d& e = views[kept[c]].ray[k];
        if (finite(e)) min_cos = std::min(min_cos, d.dot(e));
      }
      const cv::Matx33d P = cv::Matx33d::eye() - d * d.t();
      A += P;
      b += P * v.centre;
      ++n;
    }
    if (n < 2 || min_cos > min_cos_spread) continue;
    s.points[k] = A.solve(b, cv::DECOMP_SVD);
  }
  for (size_t idx : kept) {
    const View& v = views[idx];
    double ss = 0;
    int n = 0;
    for (size_t k = 0; k < n_points; ++k) {
      if (!finite(s.points[k]) || !finite(v.ray[k])) continue;
      const auto p = v.camera->project(s.points[k]);
      if (!p) {
        ss += 1e6;
        ++n;
        continue;
      }
      const cv::Point2d& q = (*v.px)[k];
      ss += (p->x - q.x) * (p->x - q.x) + (p->y - q.y) * (p->y - q.y);
      ++n;
    }
    s.view_rms_px.push_back(n > 0 ? std::sqrt(ss / n) : kNaN);
  }
  return s;
}

}  // namespace

Status FaceTriangulationOptions::check() const {
  std::string bad;
  std::set<int> seen;
  if (landmark_index.size() < 4) bad += " landmark_index needs >= 4 points;";
  for (int i : landmark_index)
    if (i < 0 || i >= 68 || !seen.insert(i).second) {
      bad += " landmark_index has an index out of [0, 68) or repeated;";
      break;
    }
  if (!(max_reprojection_per_interocular > 0)) bad += " max_reprojection_per_interocular > 0;";
  if (!(min_ray_angle_deg >= 0 && min_ray_angle_deg < 90)) bad += " min_ray_angle_deg in [0, 90);";
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "FaceTriangulationOptions:{}", bad);
  return ok_status();
}

Status SelfCalibrationOptions::check() const {
  if (auto s = triangulation.check(); !s) return s;
  std::string bad;
  if (min_points_per_frame < 4) bad += " min_points_per_frame must be >= 4;";
  if (min_frames < 3) bad += " min_frames must be >= 3;";
  if (rounds < 1) bad += " rounds must be >= 1;";
  if (!(max_frame_rms_m > 0)) bad += " max_frame_rms_m must be > 0;";
  if (!(max_median_rms_m > 0)) bad += " max_median_rms_m must be > 0;";
  if (!(min_interocular_m > 0 && max_interocular_m > min_interocular_m))
    bad += " need 0 < min_interocular_m < max_interocular_m;";
  if (!(max_pair_scale_spread > 0)) bad += " max_pair_scale_spread must be > 0;";
  if (min_pair_ticks < 1) bad += " min_pair_ticks must be >= 1;";
  if (fixation_target_world_m && !finite(*fixation_target_world_m))
    bad += " fixation_target_world_m must be finite;";
  if (!(fixation_max_yaw_deg > 0 && fixation_max_pitch_deg > 0))
    bad += " fixation_max_yaw_deg and fixation_max_pitch_deg must be > 0;";
  if (min_fixation_ticks < 1) bad += " min_fixation_ticks must be >= 1;";
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "SelfCalibrationOptions:{}", bad);
  return ok_status();
}

const char* to_string(SelfCalibrationStatus s) {
  switch (s) {
    case SelfCalibrationStatus::kConverged:
      return "converged";
    case SelfCalibrationStatus::kNoMultiView:
      return "no_multi_view";
    case SelfCalibrationStatus::kTooFewFrames:
      return "too_few_frames";
    case SelfCalibrationStatus::kInconsistent:
      return "inconsistent";
  }
  return "unknown";
}

bool align_points(const std::vector<cv::Vec3d>& src, const std::vector<cv::Vec3d>& dst,
                  bool with_scale, RigidTransform& out) {
  const size_t n = src.size();
  if (n < 3 || dst.size() != n) return false;
  cv::Vec3d ms(0, 0, 0), md(0, 0, 0);
  for (size_t i = 0; i < n; ++i) {
    ms += src[i];
    md += dst[i];
  }
  ms *= 1.0 / static_cast<double>(n);
  md *= 1.0 / static_cast<double>(n);
  cv::Matx33d C = cv::Matx33d::zeros();
  double var_src = 0;
  for (size_t i = 0; i < n; ++i) {
    const cv::Vec3d a = src[i] - ms, b = dst[i] - md;
    C += b * a.t();
    var_src += a.dot(a);
  }
  if (!(var_src > 1e-12)) return false;
  cv::Mat w, u, vt;
  cv::SVD::compute(cv::Mat(C), w, u, vt);
  cv::Matx33d U(u), Vt(vt);
  cv::Matx33d D = cv::Matx33d::eye();
  if (cv::determinant(U) * cv::determinant(Vt) < 0) D(2, 2) = -1;
  out.R = U * D * Vt;
  const cv::Vec3d sv(w.at<double>(0), w.at<double>(1), w.at<double>(2));
  out.scale = with_scale ? (sv[0] + sv[1] + D(2, 2) * sv[2]) / var_src : 1.0;
  out.t = md - out.scale * (out.R * ms);
  return true;
}

std::optional<TriangulatedFace> triangulate_face(const MultiViewLandmarks& frame,
                                                 const FaceTriangulationOptions& options) {
  const size_t n_points = options.landmark_index.size();
  std::vector<View> views;
  for (const CameraLandmarks& cl : frame.views) {
    if (cl.camera == nullptr || cl.landmarks_px.size() != 68) continue;
    const auto r = centroid_px(cl.landmarks_px, 36, 41), l = centroid_px(cl.landmarks_px, 42, 47);
    if (!r || !l) continue;
    View v{cl.camera, &cl.landmarks_px, cv::norm(*l - *r), cl.camera->centre_world(), {}};
    if (!(v.interocular_px > 2)) continue;
    v.ray.assign(n_points, cv::Vec3d(kNaN, kNaN, kNaN));
    std::vector<cv::Point2d> px, normalised;
    std::vector<size_t> which;
    for (size_t k = 0; k < n_points; ++k) {
      const cv::Point2d& p = cl.landmarks_px[static_cast<size_t>(options.landmark_index[k])];
      if (!finite(p)) continue;
      px.push_back(p);
      which.push_back(k);
    }
    if (px.empty()) continue;
    cv::undistortPoints(px, normalised, cv::Mat(cl.camera->K), cl.camera->distortion);
    for (size_t j = 0; j < px.size(); ++j) {
      const cv::Vec3d d = cl.camera->R.t() * cv::Vec3d(normalised[j].x, normalised[j].y, 1);
      v.ray[which[j]] = d / cv::norm(d);
    }
    views.push_back(std::move(v));
  }
  if (views.size() < 2) return std::nullopt;
  // solve() indexes landmarks through the view's pixel list: keep them in option order.
  std::vector<std::vector<cv::Point2d>> selected(views.size());
  for (size_t a = 0; a < views.size(); ++a) {
    for (size_t k = 0; k < n_points; ++k)
      selected[a].push_back((*views[a].px)[static_cast<size_t>(options.landmark_index[k])]);
    views[a].px = &selected[a];
  }
  const double min_cos = std::cos(options.min_ray_angle_deg * kRadiansPerDegree);
  std::vector<size_t> kept(views.size());
  for (size_t a = 0; a < kept.size(); ++a) kept[a] = a;
  // With three or more cameras, every pair triangulates the eyes on its own: a calibration that
  // disagrees along a baseline changes the pair's scale without any reprojection error, so the
  // pairs' eye distances are compared (relative spread, (max - min) / median) before any camera
  // is dropped.
  double pair_scale_spread = 0;
  std::vector<TriangulatedFace::PairInterocular> pair_iod;
  if (kept.size() >= 3) {
    std::vector<size_t> eye_k[2];
    for (size_t k = 0; k < n_points; ++k) {
      const int i = options.landmark_index[k];
      if (i >= 36 && i <= 41) eye_k[0].push_back(k);
      if (i >= 42 && i <= 47) eye_k[1].push_back(k);
    }
    std::vector<double> iod;
    for (size_t a = 0; a < kept.size() && eye_k[0].size() == 6 && eye_k[1].size() == 6; ++a)
      for (size_t b = a + 1; b < kept.size(); ++b) {
        const Solution p = solve(views, {kept[a], kept[b]}, n_points, min_cos);
        cv::Vec3d c[2] = {{0, 0, 0}, {0, 0, 0}};
        bool ok = true;
        for (int e = 0; e < 2; ++e)
          for (size_t k : eye_k[e]) {
            ok = ok && finite(p.points[k]);
            c[e] += p.points[k] * (1.0 / 6);
          }
        if (!ok) continue;
        iod.push_back(cv::norm(c[1] - c[0]));
        const CameraModel *ca = views[kept[a]].camera, *cb = views[kept[b]].camera;
        pair_iod.push_back({std::min(ca, cb), std::max(ca, cb), iod.back()});
      }
    if (iod.size() >= 2) {
      const auto [lo, hi] = std::minmax_element(iod.begin(), iod.end());
      pair_scale_spread = (*hi - *lo) / upper_median(iod);
    }
  }
  Solution s = solve(views, kept, n_points, min_cos);
  while (kept.size() >= 3) {
    size_t worst = 0;
    double worst_ratio = -1;
    for (size_t a = 0; a < kept.size(); ++a) {
      const double ratio = s.view_rms_px[a] / views[kept[a]].interocular_px;
      if (!(ratio <= worst_ratio)) {
        worst_ratio = std::isfinite(ratio) ? ratio : 1e9;
        worst = a;
      }
    }
    if (worst_ratio <= options.max_reprojection_per_interocular) break;
    kept.erase(kept.begin() + static_cast<std::ptrdiff_t>(worst));
    s = solve(views, kept, n_points, min_cos);
  }
  // A tick whose cameras still disagree (two cameras left, or a calibration that does not fit
  // the others) is not used: two-view triangulation absorbs much of an error into a wrong shape.
  for (size_t a = 0; a < kept.size(); ++a)
    if (!(s.view_rms_px[a] <=
          options.max_reprojection_per_interocular * views[kept[a]].interocular_px))
      return std::nullopt;
  // Points that still reproject badly in a kept camera are left out.
  TriangulatedFace out;
  out.cameras_dropped = static_cast<int>(views.size() - kept.size());
  out.pair_scale_spread = pair_scale_spread;
  out.pair_interocular = std::move(pair_iod);
  out.points_world = s.points;
  out.cameras = static_cast<int>(kept.size());
  double ss = 0;
  int n = 0;
  for (size_t k = 0; k < n_points; ++k) {
    if (!finite(out.points_world[k])) continue;
    bool bad = false;
    double pss = 0;
    int pn = 0;
    for (size_t idx : kept) {
      const View& v = views[idx];
      if (!finite(v.ray[k])) continue;
      const auto p = v.camera->project(out.points_world[k]);
      const double e = p ? cv::norm(*p - (*v.px)[k]) : 1e9;
      if (e > options.max_reprojection_per_interocular * v.interocular_px * 2) bad = true;
      pss += e * e;
      ++pn;
    }
    if (bad) {
      out.points_world[k] = cv::Vec3d(kNaN, kNaN, kNaN);
      continue;
    }
    ss += pss;
    n += pn;
    ++out.points;
  }
  if (out.points < 4) return std::nullopt;
  out.rms_px = std::sqrt(ss / std::max(n, 1));
  return out;
}

SelfCalibration self_calibrate_face(const std::vector<MultiViewLandmarks>& frames,
                                    const SelfCalibrationOptions& options) {
  SelfCalibration out;
  out.frames_offered = static_cast<int>(frames.size());
  if (auto s = options.check(); !s) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = s.error().message;
    return out;
  }
  const std::vector<int>& index = options.triangulation.landmark_index;
  const size_t n_points = index.size();
  int multi_view = 0, views_dropped = 0;
  std::vector<double> spreads;
  std::map<std::pair<const CameraModel*, const CameraModel*>, std::vector<double>> pair_iods;
  std::vector<TriangulatedFace> shapes;
  for (const MultiViewLandmarks& f : frames) {
    int with_landmarks = 0;
    for (const auto& v : f.views)
      if (v.camera != nullptr && v.landmarks_px.size() == 68) ++with_landmarks;
    if (with_landmarks >= 2) ++multi_view;
    auto t = triangulate_face(f, options.triangulation);
    if (t && t->points >= options.min_points_per_frame) {
      views_dropped += t->cameras_dropped;
      if (t->pair_scale_spread > 0) spreads.push_back(t->pair_scale_spread);
      for (const auto& p : t->pair_interocular) pair_iods[{p.a, p.b}].push_back(p.interocular_m);
      shapes.push_back(std::move(*t));
    }
  }
  out.frames_triangulated = static_cast<int>(shapes.size());
  out.frames_multi_view = multi_view;
  out.views_dropped = views_dropped;
  if (multi_view == 0) {
    out.status = SelfCalibrationStatus::kNoMultiView;
    out.reason = fmt::format(
        "no tick where two calibrated cameras both fitted the face ({} ticks searched): one "
        "camera only, a face too small for landmarks, or the child never faced two cameras",
        frames.size());
    return out;
  }
  if (shapes.empty()) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = fmt::format(
        "{} ticks with the face in two or more cameras, none triangulated consistently "
        "(reprojection > {:.0f}% of the inter-ocular distance): camera calibrations that "
        "disagree, or failed landmark fits",
        multi_view, 100 * options.triangulation.max_reprojection_per_interocular);
    return out;
  }
  if (out.frames_triangulated < options.min_frames) {
    out.status = SelfCalibrationStatus::kTooFewFrames;
    out.reason =
        fmt::format("{} ticks triangulated of {} searched ({} with two cameras); need {}",
                    out.frames_triangulated, frames.size(), multi_view, options.min_frames);
    return out;
  }

  out.median_pair_scale_spread = spreads.empty() ? 0.0 : upper_median(spreads);
  std::vector<double> pair_medians;
  for (auto& [pair, iods] : pair_iods)
    if (static_cast<int>(iods.size()) >= options.min_pair_ticks)
      pair_medians.push_back(upper_median(iods));
  if (pair_medians.size() >= 2) {
    const auto [lo, hi] = std::minmax_element(pair_medians.begin(), pair_medians.end());
    out.pair_median_scale_spread = (*hi - *lo) / upper_median(pair_medians);
  }
  if (out.pair_median_scale_spread > options.max_pair_scale_spread) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = fmt::format(
        "the camera pairs disagree on the size of the face by {:.0f}% (their median eye "
        "distances over {} ticks, limit {:.0f}%): camera calibrations that disagree",
        100 * out.pair_median_scale_spread, spreads.size(), 100 * options.max_pair_scale_spread);
    return out;
  }
  // Generalised Procrustes: reference = the tick with the most points.
  size_t ref = 0;
  for (size_t f = 1; f < shapes.size(); ++f)
    if (shapes[f].points > shapes[ref].points) ref = f;
  std::vector<cv::Vec3d> mean = shapes[ref].points_world;
  std::vector<std::vector<cv::Vec3d>> aligned(shapes.size());
  std::vector<double> frame_rms(shapes.size(), kNaN);
  std::vector<char> used(shapes.size(), 0);
  std::vector<cv::Matx33d> mean_from_world(shapes.size(), cv::Matx33d::eye());
  std::vector<cv::Vec3d> mean_from_world_t(shapes.size(), cv::Vec3d(0, 0, 0));
  for (int round = 0; round < options.rounds; ++round) {
    for (size_t f = 0; f < shapes.size(); ++f) {
      const auto& pts = shapes[f].points_world;
      std::vector<size_t> common;
      for (size_t k = 0; k < n_points; ++k)
        if (finite(pts[k]) && finite(mean[k])) common.push_back(k);
      std::vector<cv::Vec3d> a, b;
      for (size_t k : common) {
        a.push_back(pts[k]);
        b.push_back(mean[k]);
      }
      RigidTransform T;
      frame_rms[f] = kNaN;
      aligned[f].assign(n_points, cv::Vec3d(kNaN, kNaN, kNaN));
      if (!align_points(a, b, false, T)) continue;
      // Second pass without the points farthest from the mean (a bad landmark).
      std::vector<double> res;
      for (size_t j = 0; j < a.size(); ++j) res.push_back(cv::norm(T.apply(a[j]) - b[j]));
      const double cut = std::max(3 * upper_median(res), 0.001);
      std::vector<cv::Vec3d> a2, b2;
      for (size_t j = 0; j < a.size(); ++j)
        if (res[j] <= cut) {
          a2.push_back(a[j]);
          b2.push_back(b[j]);
        }
      if (a2.size() >= 4) align_points(a2, b2, false, T);
      double ss = 0;
      for (size_t j = 0; j < a2.size(); ++j) ss += std::pow(cv::norm(T.apply(a2[j]) - b2[j]), 2);
      frame_rms[f] = a2.empty() ? kNaN : std::sqrt(ss / static_cast<double>(a2.size()));
      mean_from_world[f] = T.R;
      mean_from_world_t[f] = T.t;
      for (size_t k = 0; k < n_points; ++k)
        if (finite(pts[k])) aligned[f][k] = T.apply(pts[k]);
    }
    std::vector<double> rms;
    for (double r : frame_rms)
      if (std::isfinite(r)) rms.push_back(r);
    const double med = upper_median(rms);
    std::vector<double> dev;
    for (double r : rms) dev.push_back(std::abs(r - med));
    const double cut = std::max(options.max_frame_rms_m, med + 3 * 1.4826 * upper_median(dev));
    for (size_t f = 0; f < shapes.size(); ++f)
      used[f] = std::isfinite(frame_rms[f]) && frame_rms[f] <= cut;
    // New mean: per coordinate median of the used ticks, without points beyond 3 robust sigmas.
    for (size_t k = 0; k < n_points; ++k) {
      std::vector<cv::Vec3d> obs;
      for (size_t f = 0; f < shapes.size(); ++f)
        if (used[f] && finite(aligned[f][k])) obs.push_back(aligned[f][k]);
      if (obs.size() < 3) {
        mean[k] = cv::Vec3d(kNaN, kNaN, kNaN);
        continue;
      }
      cv::Vec3d m;
      for (int c = 0; c < 3; ++c) {
        std::vector<double> v;
        for (const auto& o : obs) v.push_back(o[c]);
        m[c] = upper_median(v);
      }
      std::vector<double> d;
      for (const auto& o : obs) d.push_back(cv::norm(o - m));
      const double dcut = std::max(3 * 1.4826 * upper_median(d), 0.0005);
      cv::Vec3d sum(0, 0, 0);
      int n = 0;
      for (const auto& o : obs)
        if (cv::norm(o - m) <= dcut) {
          sum += o;
          ++n;
        }
      mean[k] = n > 0 ? sum * (1.0 / n) : m;
    }
  }
  std::vector<double> rms, reproj;
  for (size_t f = 0; f < shapes.size(); ++f)
    if (used[f]) {
      rms.push_back(frame_rms[f]);
      reproj.push_back(shapes[f].rms_px);
      ++out.frames_used;
    }
  out.median_rms_m = upper_median(rms);
  out.median_reprojection_px = upper_median(reproj);
  if (out.frames_used < options.min_frames) {
    out.status = SelfCalibrationStatus::kTooFewFrames;
    out.reason = fmt::format("{} consistent ticks of {} triangulated; need {}", out.frames_used,
                             out.frames_triangulated, options.min_frames);
    return out;
  }
  if (!(out.median_rms_m <= options.max_median_rms_m)) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = fmt::format(
        "the triangulated faces disagree by {:.1f} mm RMS after alignment (limit {:.1f}): camera "
        "calibrations that disagree, or unstable landmarks",
        1000 * out.median_rms_m, 1000 * options.max_median_rms_m);
    return out;
  }
  // Head frame: origin between the eye-opening centroids, orientation of the generic face.
  auto centroid = [&](int from, int to) -> std::optional<cv::Vec3d> {
    cv::Vec3d s(0, 0, 0);
    for (int i = from; i <= to; ++i) {
      const auto it = std::find(index.begin(), index.end(), i);
      if (it == index.end()) return std::nullopt;
      const cv::Vec3d& p = mean[static_cast<size_t>(it - index.begin())];
      if (!finite(p)) return std::nullopt;
      s += p;
    }
    return s * (1.0 / (to - from + 1));
  };
  const auto right_eye = centroid(36, 41), left_eye = centroid(42, 47);
  if (!right_eye || !left_eye) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = "the eye landmarks (36-47) did not triangulate consistently";
    return out;
  }
  out.interocular_m = cv::norm(*left_eye - *right_eye);
  if (out.interocular_m < options.min_interocular_m ||
      out.interocular_m > options.max_interocular_m) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = fmt::format(
        "the triangulated eyes are {:.1f} mm apart (plausible {:.0f}-{:.0f}): camera "
        "calibrations in other units or that disagree",
        1000 * out.interocular_m, 1000 * options.min_interocular_m,
        1000 * options.max_interocular_m);
    return out;
  }
  const cv::Vec3d origin = 0.5 * (*left_eye + *right_eye);
  const FaceModel3d generic = generic_face_model(true);
  std::vector<cv::Vec3d> src, dst;
  for (size_t k = 0; k < n_points; ++k) {
    if (!finite(mean[k])) continue;
    const auto it =
        std::find(generic.landmark_index.begin(), generic.landmark_index.end(), index[k]);
    if (it == generic.landmark_index.end()) continue;
    const cv::Point3d& g =
        generic.points_m[static_cast<size_t>(it - generic.landmark_index.begin())];
    src.push_back(mean[k] - origin);
    dst.emplace_back(g.x, g.y, g.z);
  }
  RigidTransform G;
  if (!align_points(src, dst, true, G)) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = "the mean shape could not be aligned with the generic face";
    return out;
  }
  // x through the eye-opening centroids; pitch from the generic face's forward direction.
  const cv::Vec3d ex = cv::normalize(cv::Vec3d(G.R * (*left_eye - *right_eye)));
  cv::Vec3d ez = cv::Vec3d(0, 0, 1) - ex[2] * ex;
  ez = cv::normalize(ez);
  const cv::Vec3d ey = ez.cross(ex);
  const cv::Matx33d head_from_generic(ex[0], ex[1], ex[2], ey[0], ey[1], ey[2], ez[0], ez[1],
                                      ez[2]);
  cv::Matx33d head_from_world = head_from_generic * G.R;
  if (options.frontal == FrontalReference::kMeanShape2d ||
      options.frontal == FrontalReference::kMeanWorldPitch) {
    // 1-D search of the pitch (about x) whose orthographic view best matches the mean frontal
    // shape in 2-D (similarity: scale, rotation, translation).
    double best = std::numeric_limits<double>::infinity(), best_deg = 0;
    for (double deg = -30; deg <= 30.0001; deg += 0.25) {
      const cv::Matx33d P = rotation_from_ypr_deg(0, deg, 0) * head_from_world;
      std::vector<cv::Vec3d> a, b;
      for (size_t j = 0; j < src.size(); ++j) {
        const cv::Vec3d q = P * src[j];
        a.emplace_back(q[0], q[1], 0);
        b.emplace_back(dst[j][0], dst[j][1], 0);
      }
      RigidTransform T;
      if (!align_points(a, b, true, T)) continue;
      double ss = 0;
      for (size_t j = 0; j < a.size(); ++j) ss += std::pow(cv::norm(T.apply(a[j]) - b[j]), 2);
      if (ss < best) {
        best = ss;
        best_deg = deg;
      }
    }
    head_from_world = rotation_from_ypr_deg(0, best_deg, 0) * head_from_world;
  }
  // Upright: the eye-line frame's roll (and with kMeanWorldPitch its pitch) relative to the
  // calibrated world's vertical, per used tick (world_from_head = mean_from_world^T
  // head_from_mean^T); the median over the ticks is taken as upright (level). Turning the frame
  // by -m about its own x (pitch) or z (roll) axis shifts every tick's angle by -m (exactly for
  // roll, to second order for pitch: two passes).
  auto angles = [&](int k) {
    std::vector<double> v;
    for (size_t f = 0; f < shapes.size(); ++f)
      if (used[f])
        v.push_back(ypr_deg_from_rotation(mean_from_world[f].t() * head_from_world.t())[k]);
    return v;
  };
  auto robust_spread = [&](const std::vector<double>& v, double m) {
    std::vector<double> dev;
    for (double r : v) dev.push_back(std::abs(r - m));
    return 1.4826 * upper_median(dev);
  };
  for (int pass = 0; pass < 2; ++pass) {
    if (options.frontal == FrontalReference::kMeanWorldPitch) {
      const auto pitches = angles(1);
      const double m = upper_median(pitches);
      out.pitch_spread_deg = robust_spread(pitches, m);
      if (std::isfinite(m) && out.pitch_spread_deg <= options.max_roll_spread_deg) {
        head_from_world = rotation_from_ypr_deg(0, m, 0) * head_from_world;
        out.level_pitch_correction_deg -= m;
      }
    }
    const auto rolls = angles(2);
    const double m = upper_median(rolls);
    out.roll_spread_deg = robust_spread(rolls, m);
    if (options.upright == UprightReference::kMeanWorldRoll && std::isfinite(m) &&
        out.roll_spread_deg <= options.max_roll_spread_deg) {
      head_from_world = rotation_from_ypr_deg(0, 0, m) * head_from_world;
      out.upright = "mean_world_roll";
      out.upright_roll_correction_deg -= m;
    }
  }
  out.level = options.frontal == FrontalReference::kGenericFace3d ? "generic_face"
              : options.frontal == FrontalReference::kMeanShape2d ? "mean_shape"
                                                                  : "world_pitch";
  if (options.frontal == FrontalReference::kMeanWorldPitch && options.fixation_target_world_m) {
    // Per used tick: the target's direction in the head frame (forward = -z, y down), as a yaw
    // and a pitch offset; turning the frame by c about its x axis adds c to every pitch offset.
    std::vector<std::pair<double, double>> offsets;  // (yaw, pitch) in degrees
    for (size_t f = 0; f < shapes.size(); ++f) {
      if (!used[f]) continue;
      const cv::Matx33d world_from_mean = mean_from_world[f].t();
      const cv::Vec3d head_world = world_from_mean * (origin - mean_from_world_t[f]);
      const cv::Vec3d d =
          head_from_world * (mean_from_world[f] * (*options.fixation_target_world_m - head_world));
      if (!(cv::norm(d) > 0)) continue;
      offsets.emplace_back(std::atan2(d[0], -d[2]) / kRadiansPerDegree,
                           std::atan2(d[1], -d[2]) / kRadiansPerDegree);
    }
    double c = 0;
    std::vector<double> facing;
    for (int round = 0; round < 4; ++round) {
      facing.clear();
      for (const auto& [yaw, pitch] : offsets)
        if (std::abs(yaw) <= options.fixation_max_yaw_deg &&
            std::abs(pitch + c) <= options.fixation_max_pitch_deg)
          facing.push_back(pitch + c);
      if (static_cast<int>(facing.size()) < options.min_fixation_ticks) break;
      c -= upper_median(facing);
    }
    out.fixation_ticks = static_cast<int>(facing.size());
    if (out.fixation_ticks >= options.min_fixation_ticks) {
      head_from_world = rotation_from_ypr_deg(0, c, 0) * head_from_world;
      out.fixation_correction_deg = c;
      out.level_pitch_correction_deg += c;
      out.level = "target_fixations";
    }
  }
  out.model.name = fmt::format("self_{}", n_points);
  for (size_t k = 0; k < n_points; ++k) {
    if (!finite(mean[k])) continue;
    const cv::Vec3d p = head_from_world * (mean[k] - origin);
    out.model.landmark_index.push_back(index[k]);
    out.model.points_m.emplace_back(p[0], p[1], p[2]);
  }
  if (auto s = out.model.check(); !s) {
    out.status = SelfCalibrationStatus::kInconsistent;
    out.reason = s.error().message;
    out.model = {};
    return out;
  }
  out.status = SelfCalibrationStatus::kConverged;
  out.reason = fmt::format(
      "{} of {} ticks used ({} with two or more cameras, {} triangulated consistently), {} "
      "points, residual {:.2f} mm RMS, reprojection {:.2f} px, eyes {:.1f} mm apart, upright "
      "{} (roll {:+.1f} deg, ticks' roll spread {:.1f} deg), level {} ({:+.1f} deg{})",
      out.frames_used, out.frames_offered, out.frames_multi_view, out.frames_triangulated,
      out.model.points_m.size(), 1000 * out.median_rms_m, out.median_reprojection_px,
      1000 * out.interocular_m, out.upright, out.upright_roll_correction_deg, out.roll_spread_deg,
      out.level, out.level_pitch_correction_deg,
      options.fixation_target_world_m
          ? fmt::format(", {} ticks facing the fixation target", out.fixation_ticks)
          : std::string());
  if (out.views_dropped > 0)
    out.reason += fmt::format(
        "; {} camera views dropped as disagreeing with the others (a failed landmark fit or a "
        "calibration that does not fit)",
        out.views_dropped);
  return out;
}

}  // namespace dreamsense::head_pose
