#include "dreamsense/geometry/pnp.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

namespace dreamsense::geometry {

const char* to_string(PnpMethod method) {
  switch (method) {
    case PnpMethod::kRansacEpnp:
      return "ransac";
    case PnpMethod::kSeedDownsample:
      return "seed";
    case PnpMethod::kEpnpAll:
      return "all";
  }
  return "?";
}

Result<PnpMethod> parse_pnp_method(const std::string& name) {
  if (name == "ransac") return PnpMethod::kRansacEpnp;
  if (name == "seed") return PnpMethod::kSeedDownsample;
  if (name == "all") return PnpMethod::kEpnpAll;
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown PnP method '{}' (expected ransac, seed or all)", name);
}

Status PnpOptions::check() const {
  std::string bad;
  if (!(inlier_threshold_px > 0)) bad += " inlier_threshold_px must be > 0;";
  if (min_points < 4) bad += " min_points must be >= 4;";
  if (sample_size < 4) bad += " sample_size must be >= 4;";
  if (max_iterations < 1) bad += " max_iterations must be >= 1;";
  if (!(confidence > 0 && confidence < 1)) bad += " confidence must be in (0, 1);";
  if (!(seed_subsample_fraction > 0 && seed_subsample_fraction <= 1))
    bad += " seed_subsample_fraction must be in (0, 1];";
  if (!(seed_max_outlier_fraction >= 0 && seed_max_outlier_fraction < 1))
    bad += " seed_max_outlier_fraction must be in [0, 1);";
  if (seed_max_rounds < 1) bad += " seed_max_rounds must be >= 1;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "PnP options:{}", bad);
  return ok_status();
}

namespace {

struct Pose {
  cv::Matx33d R = cv::Matx33d::eye();
  cv::Vec3d t{0, 0, 0};
};

Pose pose_from(const cv::Mat& rvec, const cv::Mat& tvec) {
  Pose p;
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  p.R = cv::Matx33d(R);
  p.t = cv::Vec3d(tvec.reshape(1, 3));
  return p;
}

bool finite(const Pose& p) {
  for (double v : p.R.val)
    if (!std::isfinite(v)) return false;
  return std::isfinite(p.t[0]) && std::isfinite(p.t[1]) && std::isfinite(p.t[2]);
}

// Errors on undistorted pixels with an ideal pinhole K (fast path for the RANSAC loop).
void ideal_errors(const std::vector<cv::Point3d>& X, const std::vector<cv::Point2d>& x,
                  const cv::Matx33d& K, const Pose& p, std::vector<double>& out) {
  out.resize(X.size());
  for (size_t i = 0; i < X.size(); ++i) {
    const cv::Vec3d c = p.R * cv::Vec3d(X[i].x, X[i].y, X[i].z) + p.t;
    if (c[2] <= 1e-12) {
      out[i] = std::numeric_limits<double>::infinity();
      continue;
    }
    const double u = K(0, 0) * c[0] / c[2] + K(0, 1) * c[1] / c[2] + K(0, 2);
    const double v = K(1, 1) * c[1] / c[2] + K(1, 2);
    out[i] = std::hypot(u - x[i].x, v - x[i].y);
  }
}

template <typename T>
std::vector<T> pick(const std::vector<T>& v, const std::vector<int>& idx) {
  std::vector<T> out;
  out.reserve(idx.size());
  for (int i : idx) out.push_back(v[static_cast<size_t>(i)]);
  return out;
}

// True when the points are (nearly) coplanar: smallest spread < 1 % of the largest.
bool coplanar(const std::vector<cv::Point3d>& X) {
  cv::Point3d c(0, 0, 0);
  for (const auto& p : X) c += p;
  c *= 1.0 / static_cast<double>(X.size());
  cv::Matx33d C = cv::Matx33d::zeros();
  for (const auto& p : X) {
    const cv::Vec3d d(p.x - c.x, p.y - c.y, p.z - c.z);
    C += d * d.t();
  }
  cv::Vec3d w;
  cv::eigen(C, w);            // descending
  return w[2] < 1e-4 * w[0];  // variances: (1 %)^2
}

// EPnP hypothesis; OpenCV's EPnP degenerates on coplanar points, where IPPE (Collins & Bartoli
// 2014, also in OpenCV) is used instead.
bool epnp(const std::vector<cv::Point3d>& X, const std::vector<cv::Point2d>& x,
          const cv::Matx33d& K, Pose& out) {
  try {
    cv::Mat rvec, tvec;
    const int flag = coplanar(X) ? cv::SOLVEPNP_IPPE : cv::SOLVEPNP_EPNP;
    if (!cv::solvePnP(X, x, cv::Mat(K), cv::noArray(), rvec, tvec, false, flag)) return false;
    out = pose_from(rvec, tvec);
    return finite(out);
  } catch (const cv::Exception&) {
    return false;
  }
}

bool refine_lm(const std::vector<cv::Point3d>& X, const std::vector<cv::Point2d>& x,
               const cv::Matx33d& K, Pose& pose) {
  try {
    cv::Mat R(pose.R), rvec, tvec = cv::Mat(pose.t).clone();
    cv::Rodrigues(R, rvec);
    cv::solvePnPRefineLM(
        X, x, cv::Mat(K), cv::noArray(), rvec, tvec,
        cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-10));
    Pose p = pose_from(rvec, tvec);
    if (!finite(p)) return false;
    pose = p;
    return true;
  } catch (const cv::Exception&) {
    return false;
  }
}

std::vector<int> inliers_of(const std::vector<double>& err, double thr) {
  std::vector<int> idx;
  for (size_t i = 0; i < err.size(); ++i)
    if (err[i] < thr) idx.push_back(static_cast<int>(i));
  return idx;
}

double sum_capped(const std::vector<double>& err, double thr) {
  double s = 0;
  for (double e : err) s += std::min(e, thr);
  return s;
}

// Inlier refit (EPnP on the inliers, then LM) until the inlier set is stable.
void polish(const std::vector<cv::Point3d>& X, const std::vector<cv::Point2d>& x,
            const cv::Matx33d& K, const PnpOptions& o, bool use_all_points, Pose& pose) {
  std::vector<double> err;
  ideal_errors(X, x, K, pose, err);
  std::vector<int> inl =
      use_all_points ? std::vector<int>() : inliers_of(err, o.inlier_threshold_px);
  if (use_all_points) {
    inl.resize(X.size());
    std::iota(inl.begin(), inl.end(), 0);
  }
  for (int round = 0; round < 4; ++round) {
    if (static_cast<int>(inl.size()) < 4) return;
    const auto Xi = pick(X, inl);
    const auto xi = pick(x, inl);
    if (!use_all_points && static_cast<int>(inl.size()) > o.sample_size) {
      Pose refit;
      if (epnp(Xi, xi, K, refit)) {
        std::vector<double> e2;
        ideal_errors(X, x, K, refit, e2);
        if (inliers_of(e2, o.inlier_threshold_px).size() >= inl.size() &&
            sum_capped(e2, o.inlier_threshold_px) <= sum_capped(err, o.inlier_threshold_px))
          pose = refit;
      }
    }
    if (o.refine_lm) refine_lm(Xi, xi, K, pose);
    if (use_all_points) return;
    ideal_errors(X, x, K, pose, err);
    std::vector<int> next = inliers_of(err, o.inlier_threshold_px);
    if (next == inl) return;
    inl = std::move(next);
  }
}

}  // namespace

std::vector<double> reprojection_errors(const std::vector<cv::Point3d>& world,
                                        const std::vector<cv::Point2d>& pixels,
                                        const cv::Matx33d& K, const cv::Mat& distortion,
                                        const cv::Matx33d& R, const cv::Vec3d& t) {
  std::vector<double> out(world.size(), std::numeric_limits<double>::infinity());
  if (world.empty()) return out;
  cv::Mat rvec;
  cv::Rodrigues(cv::Mat(R), rvec);
  std::vector<cv::Point2d> proj;
  cv::projectPoints(world, rvec, cv::Mat(t), cv::Mat(K), distortion, proj);
  for (size_t i = 0; i < world.size(); ++i) {
    const cv::Vec3d c = R * cv::Vec3d(world[i].x, world[i].y, world[i].z) + t;
    if (c[2] > 1e-12) out[i] = cv::norm(proj[i] - pixels[i]);
  }
  return out;
}

Status check_pnp_input(const std::vector<cv::Point3d>& world,
                       const std::vector<cv::Point2d>& pixels, int min_points) {
  if (world.size() != pixels.size())
    return make_error(ErrorCode::kInvalidArgument,
                      "PnP: {} 3-D points but {} pixels (they must pair up)", world.size(),
                      pixels.size());
  const int n = static_cast<int>(world.size());
  if (n < min_points)
    return make_error(ErrorCode::kInvalidArgument,
                      "PnP: {} correspondences, at least {} are needed (typically ~20)", n,
                      min_points);
  for (int i = 0; i < n; ++i) {
    const auto& X = world[static_cast<size_t>(i)];
    const auto& x = pixels[static_cast<size_t>(i)];
    if (!std::isfinite(X.x) || !std::isfinite(X.y) || !std::isfinite(X.z) || !std::isfinite(x.x) ||
        !std::isfinite(x.y))
      return make_error(ErrorCode::kInvalidArgument, "PnP: correspondence {} is not finite", i + 1);
  }
  // 3-D spread: singular values of the centred points.
  cv::Mat A(n, 3, CV_64F), B(n, 2, CV_64F);
  cv::Point3d c3(0, 0, 0);
  cv::Point2d c2(0, 0);
  for (int i = 0; i < n; ++i) {
    c3 += world[static_cast<size_t>(i)];
    c2 += pixels[static_cast<size_t>(i)];
  }
  c3 *= 1.0 / n;
  c2 *= 1.0 / n;
  for (int i = 0; i < n; ++i) {
    const auto d3 = world[static_cast<size_t>(i)] - c3;
    const auto d2 = pixels[static_cast<size_t>(i)] - c2;
    A.at<double>(i, 0) = d3.x;
    A.at<double>(i, 1) = d3.y;
    A.at<double>(i, 2) = d3.z;
    B.at<double>(i, 0) = d2.x;
    B.at<double>(i, 1) = d2.y;
  }
  cv::Mat w3, w2;
  cv::SVD::compute(A, w3, cv::SVD::NO_UV);
  cv::SVD::compute(B, w2, cv::SVD::NO_UV);
  if (w3.at<double>(0) <= 0 || w3.at<double>(1) < 1e-3 * w3.at<double>(0))
    return make_error(ErrorCode::kInvalidArgument,
                      "PnP: the {} 3-D points are collinear (or coincident): the pose is not "
                      "determined; pick points that span the scene",
                      n);
  const double rms_off_line = w2.at<double>(1) / std::sqrt(static_cast<double>(n));
  if (rms_off_line < 1.0)
    return make_error(ErrorCode::kInvalidArgument,
                      "PnP: the {} pixels are collinear (RMS {:.2f} px from one line): the "
                      "points lie on a plane through the camera centre; pick points that "
                      "spread over the image",
                      n, rms_off_line);
  return ok_status();
}

Result<PnpResult> estimate_pose(const std::vector<cv::Point3d>& world,
                                const std::vector<cv::Point2d>& pixels, const cv::Matx33d& K,
                                const cv::Mat& distortion, const PnpOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (auto s = check_pnp_input(world, pixels, o.min_points); !s) return tl::unexpected(s.error());
  const int n = static_cast<int>(world.size());

  // Work on undistorted pixels with an ideal K; final errors use the full model.
  std::vector<cv::Point2d> ideal = pixels;
  const bool distorted = !distortion.empty() && cv::countNonZero(distortion != 0) > 0;
  if (distorted)
    cv::undistortPoints(pixels, ideal, cv::Mat(K), distortion, cv::noArray(), cv::Mat(K));

  std::mt19937_64 rng(o.seed);
  Pose best;
  int best_count = -1;
  double best_cost = std::numeric_limits<double>::infinity();
  int iterations = 0;
  std::vector<double> err;
  std::vector<int> idx(static_cast<size_t>(n));
  std::iota(idx.begin(), idx.end(), 0);
  auto consider = [&](const Pose& p) {
    ideal_errors(world, ideal, K, p, err);
    const int count = static_cast<int>(inliers_of(err, o.inlier_threshold_px).size());
    const double cost = sum_capped(err, o.inlier_threshold_px);
    if (count > best_count || (count == best_count && cost < best_cost)) {
      best = p;
      best_count = count;
      best_cost = cost;
    }
    return count;
  };
  auto shuffle_prefix = [&](int k) {
    for (int i = 0; i < k; ++i) {
      std::uniform_int_distribution<int> d(i, n - 1);
      std::swap(idx[static_cast<size_t>(i)], idx[static_cast<size_t>(d(rng))]);
    }
    return std::vector<int>(idx.begin(), idx.begin() + k);
  };

  if (o.method == PnpMethod::kRansacEpnp) {
    const int s = std::min(o.sample_size, n);
    int needed = o.max_iterations;
    for (; iterations < needed; ++iterations) {
      const auto sample = shuffle_prefix(s);
      Pose p;
      if (!epnp(pick(world, sample), pick(ideal, sample), K, p)) continue;
      consider(p);
      const double w = static_cast<double>(best_count) / n;
      const double p_clean = std::pow(w, s);
      if (p_clean >= 1.0) {
        needed = iterations + 1;
      } else if (p_clean > 0) {
        const double k = std::log(1 - o.confidence) / std::log(1 - p_clean);
        needed = std::min(o.max_iterations, static_cast<int>(std::ceil(k)));
      }
    }
  } else if (o.method == PnpMethod::kSeedDownsample) {
    const int k = std::max(4, static_cast<int>(std::ceil(o.seed_subsample_fraction * n)));
    for (; iterations < o.seed_max_rounds;) {
      const auto subset = iterations == 0 ? idx : shuffle_prefix(k);
      ++iterations;
      Pose p;
      if (!epnp(pick(world, subset), pick(ideal, subset), K, p)) continue;
      const int count = consider(p);
      if (static_cast<double>(n - count) / n <= o.seed_max_outlier_fraction) {
        best = p;  // the seed stops at the first pose that is good enough
        break;
      }
    }
  } else {
    iterations = 1;
    Pose p;
    if (epnp(world, ideal, K, p)) consider(p);
  }
  if (best_count < 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "PnP: EPnP found no pose from the {} correspondences", n);
  polish(world, ideal, K, o, o.method == PnpMethod::kEpnpAll, best);

  PnpResult r;
  r.R = best.R;
  r.t = best.t;
  r.iterations = iterations;
  r.errors_px = reprojection_errors(world, pixels, K, distortion, best.R, best.t);
  r.inliers.resize(static_cast<size_t>(n));
  double sq = 0;
  for (int i = 0; i < n; ++i) {
    const double e = r.errors_px[static_cast<size_t>(i)];
    r.inliers[static_cast<size_t>(i)] = e < o.inlier_threshold_px;
    if (e < o.inlier_threshold_px) {
      ++r.inlier_count;
      sq += e * e;
    }
  }
  r.rms_px = r.inlier_count > 0 ? std::sqrt(sq / r.inlier_count) : 0;
  const int needed = std::max(4, std::min(o.sample_size, o.min_points));
  if (o.require_consensus && r.inlier_count < needed)
    return make_error(ErrorCode::kInvalidArgument,
                      "PnP: no consistent pose: only {} of {} correspondences agree within "
                      "{:.1f} px (at least {} needed); check the pairs and the intrinsics",
                      r.inlier_count, n, o.inlier_threshold_px, needed);
  return r;
}

}  // namespace dreamsense::geometry
