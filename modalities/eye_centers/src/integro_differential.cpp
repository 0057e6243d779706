// The improved integro-differential operator (D4.2 eq. (2)) and Daugman's original operator.
// Both compute ring means L_k at radii k * dr around a candidate centre and the same derivative-
// of-Gaussian over radius; they differ in the contour (two horizontal cones vs. full circles) and
// in how the ring means are obtained (precomputed integer-offset tables vs. brute-force bilinear
// sampling per candidate).

#include <algorithm>
#include <cmath>
#include <numbers>

#include "eye_patch.hpp"

namespace dreamsense::eye_centers {
namespace {

using detail::EyePatch;

// D_n = sum_m h_m L_|n-m|, h_m = g_m - g_(m-1) (m = -J..J+1): the Gaussian-smoothed ring means'
// backward difference, i.e. the edge between rings n-1 and n, at radius (n - 1/2) dr. Divided by
// g_0 it is the height of an ideal step edge in grey levels.
struct RadialFilter {
  double dr = 0.5;
  int n_min = 0, n_max = 0, k_max = 0, half = 0;
  std::vector<double> h;  // h[m + half], m = -half .. half + 1
  double g0 = 1;
};

RadialFilter make_radial_filter(double r_min, double r_max, double dr, double sigma) {
  RadialFilter f;
  f.dr = dr;
  const std::vector<double> g = detail::gaussian_taps(sigma, dr, f.half);
  const int J = f.half;
  f.n_min = std::max(1, static_cast<int>(std::ceil(r_min / dr + 0.5)));
  f.n_max = std::max(f.n_min, static_cast<int>(std::floor(r_max / dr + 0.5)));
  f.k_max = f.n_max + J;
  f.h.resize(2 * J + 2);
  auto gm = [&](int m) { return m < -J || m > J ? 0.0 : g[m + J]; };
  for (int m = -J; m <= J + 1; ++m) f.h[m + J] = gm(m) - gm(m - 1);
  f.g0 = g[J];
  return f;
}

// Best edge for one candidate: returns step (signed or absolute) and the edge index n.
struct Edge {
  double step = -1e300;
  int n = 0;
};
Edge best_edge(const RadialFilter& f, const double* L, bool dark_inside_only) {
  Edge e;
  const int J = f.half;
  for (int n = f.n_min; n <= f.n_max; ++n) {
    double d = 0;
    for (int m = -J; m <= J + 1; ++m) d += f.h[m + J] * L[std::abs(n - m)];
    d /= f.g0;
    if (!dark_inside_only) d = std::abs(d);
    if (d > e.step) {
      e.step = d;
      e.n = n;
    }
  }
  return e;
}

EyeLocation finish(const EyePatch& p, const cv::Mat& score, const cv::Mat& best_n,
                   const RadialFilter& f, double min_step, double full_confidence_step) {
  const detail::Peak pk = detail::find_peak(score, p.candidates);
  EyeLocation loc;
  loc.score = pk.value;
  loc.radius_px = (best_n.at<int>(pk.best) - 0.5) * f.dr / p.scale;
  if (!(pk.value >= min_step)) {
    loc.rejection = EyeRejection::kNoEdge;
    return loc;
  }
  loc.found = true;
  loc.center_px = detail::to_image(p, pk.refined);
  loc.confidence = std::clamp(pk.value / full_confidence_step, 0.0, 1.0);
  return loc;
}

EyeLocation rejected(EyeRejection r) {
  EyeLocation loc;
  loc.rejection = r;
  return loc;
}

}  // namespace

Status ImprovedIntegroDifferentialOptions::check() const {
  if (!(radius_step_px > 0.05) || !(radius_step_px <= 2) || !(sigma_px > 0) || !(sigma_px <= 5))
    return make_error(ErrorCode::kInvalidArgument,
                      "ImprovedIntegroDifferentialOptions: need radius_step_px in (0.05, 2] and "
                      "sigma_px in (0, 5]");
  if (!(cone_half_angle_deg > 0) || !(cone_half_angle_deg <= 90))
    return make_error(ErrorCode::kInvalidArgument,
                      "ImprovedIntegroDifferentialOptions: cone_half_angle_deg must be in (0, 90]");
  if (!(arc_step_px > 0.05) || !(arc_step_px <= 2))
    return make_error(ErrorCode::kInvalidArgument,
                      "ImprovedIntegroDifferentialOptions: arc_step_px must be in (0.05, 2]");
  if (!(min_step >= 0) || !(full_confidence_step > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "ImprovedIntegroDifferentialOptions: need min_step >= 0 and "
                      "full_confidence_step > 0");
  return ok_status();
}

Status DaugmanOptions::check() const {
  if (!(radius_step_px > 0.05) || !(radius_step_px <= 2) || !(sigma_px > 0) || !(sigma_px <= 5))
    return make_error(ErrorCode::kInvalidArgument,
                      "DaugmanOptions: need radius_step_px in (0.05, 2] and sigma_px in (0, 5]");
  if (!(arc_step_px > 0.05) || !(arc_step_px <= 2))
    return make_error(ErrorCode::kInvalidArgument,
                      "DaugmanOptions: arc_step_px must be in (0.05, 2]");
  if (!(min_step >= 0) || !(full_confidence_step > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "DaugmanOptions: need min_step >= 0 and full_confidence_step > 0");
  return ok_status();
}

Result<EyeLocation> locate_improved_integro_differential(
    const cv::Mat& image, std::span<const cv::Point2d> contour, const EyeRegionOptions& region,
    const ImprovedIntegroDifferentialOptions& o) {
  auto patch =
      detail::make_eye_patch(image, contour, region, 3 * o.sigma_px + 2 * o.radius_step_px + 3);
  if (!patch) return tl::unexpected(patch.error());
  const EyePatch& p = *patch;
  if (p.rejection != EyeRejection::kNone) return rejected(p.rejection);
  const RadialFilter f = make_radial_filter(p.r_min, p.r_max, o.radius_step_px, o.sigma_px);

  // Ring tables: eq. (2)'s samples I[k dr cos(m dtheta) + x0, k dr sin(m dtheta) + y0] on the two
  // cones, bilinear weights splatted onto integer offsets and divided by the sample count, so
  // that L_k = sum of (weight * pixel) over the offsets of ring k. Offsets of all rings are merged
  // into one table ordered by offset.
  const int R = static_cast<int>(std::ceil(f.k_max * f.dr)) + 2, side = 2 * R + 1;
  const int rings = f.k_max + 1;
  std::vector<double> dense(static_cast<size_t>(rings) * side * side, 0.0);
  auto splat = [&](int k, double x, double y, double w) {
    const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
    const double fx = x - ix, fy = y - iy;
    double* d = &dense[static_cast<size_t>(k) * side * side];
    d[(iy + R) * side + ix + R] += w * (1 - fx) * (1 - fy);
    d[(iy + R) * side + ix + 1 + R] += w * fx * (1 - fy);
    d[(iy + 1 + R) * side + ix + R] += w * (1 - fx) * fy;
    d[(iy + 1 + R) * side + ix + 1 + R] += w * fx * fy;
  };
  const double half = o.cone_half_angle_deg * std::numbers::pi / 180;
  splat(0, 0, 0, 1);
  for (int k = 1; k < rings; ++k) {
    const double rho = k * f.dr;
    const int m = std::max(1, static_cast<int>(std::ceil(2 * half * rho / o.arc_step_px)));
    for (int cone = 0; cone < 2; ++cone)
      for (int i = 0; i < m; ++i) {
        const double th = cone * std::numbers::pi - half + (i + 0.5) * (2 * half / m);
        splat(k, rho * std::cos(th), rho * std::sin(th), 1.0 / (2 * m));
      }
  }
  struct Tap {
    int offset, ring;
    float w;
  };
  std::vector<Tap> taps;
  const int stride = p.grey.cols;
  for (int dy = -R; dy <= R; ++dy)
    for (int dx = -R; dx <= R; ++dx)
      for (int k = 0; k < rings; ++k) {
        const double w = dense[static_cast<size_t>(k) * side * side + (dy + R) * side + dx + R];
        if (w > 1e-9) taps.push_back({dy * stride + dx, k, static_cast<float>(w)});
      }

  const cv::Rect grown(p.candidates.x - 1, p.candidates.y - 1, p.candidates.width + 2,
                       p.candidates.height + 2);
  cv::Mat score(grown.size(), CV_64F), best_n(grown.size(), CV_32S);
  std::vector<double> L(rings);
  const float* base = p.grey.ptr<float>(0);
  for (int y = 0; y < grown.height; ++y)
    for (int x = 0; x < grown.width; ++x) {
      const float* c = base + (grown.y + y) * stride + grown.x + x;
      std::fill(L.begin(), L.end(), 0.0);
      for (const Tap& t : taps) L[t.ring] += t.w * c[t.offset];
      const Edge e = best_edge(f, L.data(), o.dark_inside_only);
      score.at<double>(y, x) = e.step;
      best_n.at<int>(y, x) = e.n;
    }
  return finish(p, score, best_n, f, o.min_step, o.full_confidence_step);
}

Result<EyeLocation> locate_daugman(const cv::Mat& image, std::span<const cv::Point2d> contour,
                                   const EyeRegionOptions& region, const DaugmanOptions& o) {
  auto patch =
      detail::make_eye_patch(image, contour, region, 3 * o.sigma_px + 2 * o.radius_step_px + 3);
  if (!patch) return tl::unexpected(patch.error());
  const EyePatch& p = *patch;
  if (p.rejection != EyeRejection::kNone) return rejected(p.rejection);
  const RadialFilter f = make_radial_filter(p.r_min, p.r_max, o.radius_step_px, o.sigma_px);
  const int rings = f.k_max + 1;
  // Full circles, about one sample per arc_step_px (at least 8); unit-circle tables per ring.
  std::vector<std::vector<cv::Point2d>> circle(rings);
  circle[0] = {cv::Point2d(0, 0)};
  for (int k = 1; k < rings; ++k) {
    const double rho = k * f.dr;
    const int m =
        std::max(8, static_cast<int>(std::ceil(2 * std::numbers::pi * rho / o.arc_step_px)));
    for (int i = 0; i < m; ++i) {
      const double th = 2 * std::numbers::pi * i / m;
      circle[k].emplace_back(rho * std::cos(th), rho * std::sin(th));
    }
  }
  const cv::Rect grown(p.candidates.x - 1, p.candidates.y - 1, p.candidates.width + 2,
                       p.candidates.height + 2);
  cv::Mat score(grown.size(), CV_64F), best_n(grown.size(), CV_32S);
  std::vector<double> L(rings);
  const int stride = p.grey.cols;
  const float* base = p.grey.ptr<float>(0);
  for (int y = 0; y < grown.height; ++y)
    for (int x = 0; x < grown.width; ++x) {
      const double cx = grown.x + x, cy = grown.y + y;
      for (int k = 0; k < rings; ++k) {
        double sum = 0;
        for (const cv::Point2d& d : circle[k]) {
          const double sx = cx + d.x, sy = cy + d.y;
          const int ix = static_cast<int>(std::floor(sx)), iy = static_cast<int>(std::floor(sy));
          const double fx = sx - ix, fy = sy - iy;
          const float* q = base + iy * stride + ix;
          sum += (1 - fy) * ((1 - fx) * q[0] + fx * q[1]) +
                 fy * ((1 - fx) * q[stride] + fx * q[stride + 1]);
        }
        L[k] = sum / static_cast<double>(circle[k].size());
      }
      const Edge e = best_edge(f, L.data(), o.dark_inside_only);
      score.at<double>(y, x) = e.step;
      best_n.at<int>(y, x) = e.n;
    }
  return finish(p, score, best_n, f, o.min_step, o.full_confidence_step);
}

}  // namespace dreamsense::eye_centers
