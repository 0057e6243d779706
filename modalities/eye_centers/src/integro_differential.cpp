// The improved integro-differential operator (D4.2 eq. (2)) and Daugman's original operator.
// Both compute ring means L_k at radii k * dr around a candidate centre and the same derivative-
// of-Gaussian over radius; they differ in the contour (two horizontal cones vs. full circles) and
// in how the ring means are obtained (precomputed integer-offset tables vs. brute-force bilinear
// sampling per candidate).

#include <opencv2/imgproc.hpp>

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

// extra_ring: one ring beyond n_max + J, for best_edge's local-maximum test.
RadialFilter make_radial_filter(double r_min, double r_max, double dr, double sigma,
                                bool extra_ring = false) {
  RadialFilter f;
  f.dr = dr;
  const std::vector<double> g = detail::gaussian_taps(sigma, dr, f.half);
  const int J = f.half;
  f.n_min = std::max(1, static_cast<int>(std::ceil(r_min / dr + 0.5)));
  f.n_max = std::max(f.n_min, static_cast<int>(std::floor(r_max / dr + 0.5)));
  f.k_max = f.n_max + J + (extra_ring ? 1 : 0);
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
// local_max_only: also only edges n <= n_hi.
Edge best_edge(const RadialFilter& f, const double* L, bool dark_inside_only,
               bool local_max_only = false, int n_hi = 0) {
  Edge e;
  const int J = f.half;
  auto at = [&](int n) {
    double d = 0;
    for (int m = -J; m <= J + 1; ++m) d += f.h[m + J] * L[std::abs(n - m)];
    d /= f.g0;
    return dark_inside_only ? d : std::abs(d);
  };
  if (!local_max_only) {
    for (int n = f.n_min; n <= f.n_max; ++n)
      if (const double d = at(n); d > e.step) {
        e.step = d;
        e.n = n;
      }
    return e;
  }
  // Only edges that peak inside the radius range (needs rings up to n_max + 1 + J): a response
  // still rising at the largest radius is the tail of a stronger edge outside the range.
  double prev = at(f.n_min - 1), cur = at(f.n_min);
  for (int n = f.n_min; n <= std::min(f.n_max, n_hi); ++n) {
    const double next = at(n + 1);
    if (cur >= prev && cur >= next && cur > e.step) {
      e.step = cur;
      e.n = n;
    }
    prev = cur;
    cur = next;
  }
  return e;
}

// Eq. (2)'s samples I[k dr cos(m dtheta) + x0, k dr sin(m dtheta) + y0] on two opposing cones of
// +-half_deg around the horizontal (90: full circles), with their bilinear weights splatted onto
// integer offsets and divided by the sample count, so that L_k = sum of (weight * pixel) over the
// offsets of ring k. Offsets of all rings are merged into one table ordered by offset.
struct RingTable {
  struct Tap {
    int offset, ring;
    float w;
  };
  std::vector<Tap> taps;
  int rings = 0;
  int reach = 0;  // largest |dx| or |dy| of a tap
};

RingTable make_ring_table(const RadialFilter& f, double half_deg, double arc_step, int stride) {
  RingTable t;
  const int R = static_cast<int>(std::ceil(f.k_max * f.dr)) + 2, side = 2 * R + 1;
  t.rings = f.k_max + 1;
  std::vector<double> dense(static_cast<size_t>(t.rings) * side * side, 0.0);
  auto splat = [&](int k, double x, double y, double w) {
    const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
    const double fx = x - ix, fy = y - iy;
    double* d = &dense[static_cast<size_t>(k) * side * side];
    d[(iy + R) * side + ix + R] += w * (1 - fx) * (1 - fy);
    d[(iy + R) * side + ix + 1 + R] += w * fx * (1 - fy);
    d[(iy + 1 + R) * side + ix + R] += w * (1 - fx) * fy;
    d[(iy + 1 + R) * side + ix + 1 + R] += w * fx * fy;
  };
  const double half = half_deg * std::numbers::pi / 180;
  splat(0, 0, 0, 1);
  for (int k = 1; k < t.rings; ++k) {
    const double rho = k * f.dr;
    const int m = std::max(1, static_cast<int>(std::ceil(2 * half * rho / arc_step)));
    for (int cone = 0; cone < 2; ++cone)
      for (int i = 0; i < m; ++i) {
        const double th = cone * std::numbers::pi - half + (i + 0.5) * (2 * half / m);
        splat(k, rho * std::cos(th), rho * std::sin(th), 1.0 / (2 * m));
      }
  }
  for (int dy = -R; dy <= R; ++dy)
    for (int dx = -R; dx <= R; ++dx)
      for (int k = 0; k < t.rings; ++k) {
        const double w = dense[static_cast<size_t>(k) * side * side + (dy + R) * side + dx + R];
        if (w > 1e-9) {
          t.taps.push_back({dy * stride + dx, k, static_cast<float>(w)});
          t.reach = std::max({t.reach, std::abs(dx), std::abs(dy)});
        }
      }
  return t;
}

// Where the second (pupil) stage may look: edges that peak inside the radius range, on rings
// that stay inside the limbus circle (centre, radius) by `margin`.
struct Inside {
  cv::Point2d centre;
  double radius = 0, margin = 0;
};

// score / best_n (CV_64F / CV_32S, rect's size): the best edge of the centres of `rect` (the
// candidates grown by one pixel). step 1: every centre. step s > 1, coarse to fine: every s-th
// centre, then every centre within s + 1 pixels of the best of those (so that the peak and its
// neighbours for the sub-pixel parabola are all evaluated); the others score -inf. The score
// maps are smooth on the scale of the Gaussian over radius, so a 2-pixel grid does not step over
// the limbus or pupil peak.
void score_candidates(const cv::Mat& grey, const cv::Rect& rect, const RingTable& t,
                      const RadialFilter& f, bool dark_inside_only, const Inside* inside, int step,
                      cv::Mat& score, cv::Mat& best_n) {
  score.create(rect.size(), CV_64F);
  score.setTo(-1e300);
  best_n.create(rect.size(), CV_32S);
  best_n.setTo(0);
  std::vector<double> L(static_cast<size_t>(t.rings));
  const float* base = grey.ptr<float>(0);
  const int stride = grey.cols;
  auto eval = [&](int x, int y) {
    const float* c = base + (rect.y + y) * stride + rect.x + x;
    std::fill(L.begin(), L.end(), 0.0);
    for (const RingTable::Tap& tap : t.taps) L[tap.ring] += tap.w * c[tap.offset];
    int n_hi = f.n_max;
    if (inside) {  // edge radius (n - 1/2) dr <= limbus radius - distance - margin
      const double d = std::hypot(rect.x + x - inside->centre.x, rect.y + y - inside->centre.y);
      n_hi = static_cast<int>(std::floor((inside->radius - d - inside->margin) / f.dr + 0.5));
    }
    const Edge e = best_edge(f, L.data(), dark_inside_only, inside != nullptr, n_hi);
    score.at<double>(y, x) = e.step;
    best_n.at<int>(y, x) = e.n;
  };
  if (step <= 1 || rect.width <= 2 * step + 3 || rect.height <= 2 * step + 3) {
    for (int y = 0; y < rect.height; ++y)
      for (int x = 0; x < rect.width; ++x) eval(x, y);
    return;
  }
  int bx = 1, by = 1;
  double best = -1e300;
  for (int y = 1; y < rect.height - 1; y += step)
    for (int x = 1; x < rect.width - 1; x += step) {
      eval(x, y);
      if (score.at<double>(y, x) > best) best = score.at<double>(y, x), bx = x, by = y;
    }
  for (int y = std::max(0, by - step - 1); y <= std::min(rect.height - 1, by + step + 1); ++y)
    for (int x = std::max(0, bx - step - 1); x <= std::min(rect.width - 1, bx + step + 1); ++x)
      if (score.at<double>(y, x) == -1e300) eval(x, y);
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
  loc.iris_center_px = loc.center_px;
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
  if (!(min_step_of_range >= 0) || !(min_step_of_range < 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "ImprovedIntegroDifferentialOptions: min_step_of_range must be in [0, 1)");
  if (coarse_step < 1 || coarse_step > 4)
    return make_error(ErrorCode::kInvalidArgument,
                      "ImprovedIntegroDifferentialOptions: coarse_step must be in [1, 4]");
  return pupil.check();
}

Status PupilOptions::check() const {
  if (!(min_radius_ratio > 0) || !(max_radius_ratio > min_radius_ratio) ||
      !(max_radius_ratio < 1) || !(min_radius_px >= 0.5))
    return make_error(ErrorCode::kInvalidArgument,
                      "PupilOptions: need 0 < min_radius_ratio < max_radius_ratio < 1 and "
                      "min_radius_px >= 0.5");
  if (!(target_iris_radius_px >= 4) || !(target_iris_radius_px <= 64))
    return make_error(ErrorCode::kInvalidArgument,
                      "PupilOptions: target_iris_radius_px must be in [4, 64]");
  if (!(max_offset_ratio >= 0) || !(max_offset_ratio <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "PupilOptions: max_offset_ratio must be in [0, 1]");
  if (!(cone_half_angle_deg > 0) || !(cone_half_angle_deg <= 90) || !(sigma_px > 0) ||
      !(sigma_px <= 5))
    return make_error(ErrorCode::kInvalidArgument,
                      "PupilOptions: need cone_half_angle_deg in (0, 90] and sigma_px in (0, 5]");
  if (!(min_step >= 0) || !(min_step_ratio >= 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "PupilOptions: need min_step >= 0 and min_step_ratio >= 0");
  if (!(clip_percentile >= 50) || !(clip_percentile <= 100))
    return make_error(ErrorCode::kInvalidArgument,
                      "PupilOptions: clip_percentile must be in [50, 100]");
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

  // Stage 1, the limbus: eq. (2) on the two horizontal cones over the whole candidate window.
  const RadialFilter f = make_radial_filter(p.r_min, p.r_max, o.radius_step_px, o.sigma_px);
  const RingTable table = make_ring_table(f, o.cone_half_angle_deg, o.arc_step_px, p.grey.cols);
  const cv::Rect grown(p.candidates.x - 1, p.candidates.y - 1, p.candidates.width + 2,
                       p.candidates.height + 2);
  cv::Mat score, best_n;
  score_candidates(p.grey, grown, table, f, o.dark_inside_only, nullptr, o.coarse_step, score,
                   best_n);
  EyeLocation loc = finish(p, score, best_n, f, std::max(o.min_step, o.min_step_of_range * p.range),
                           o.full_confidence_step);
  if (!loc.found) return loc;
  loc.iris_center_px = loc.center_px;
  if (!o.pupil.enabled) return loc;

  // Stage 2, the pupil: the same operator, dark inside, on the pupil radii (a fraction of the
  // limbus radius) around centres near the limbus centre, on rings that stay inside the limbus.
  // The pupil is the eye centre proper (what BioID and the session truth mark); the limbus
  // centre differs from it when the iris is seen obliquely and the pupil is not in the limbus
  // plane, or when the lids cut the iris. A pupil is only a few pixels wide, so this stage works
  // on the limbus neighbourhood resampled `up` times finer (limbus radius ~target_iris_radius_px),
  // which removes the pixel locking of a small circle on the integer candidate grid.
  const detail::Peak limbus = detail::find_peak(score, p.candidates);
  const double r_iris = (best_n.at<int>(limbus.best) - 0.5) * f.dr;
  const PupilOptions& po = o.pupil;
  const double up = std::clamp(std::ceil(po.target_iris_radius_px / r_iris), 1.0, 4.0);
  const double ru = r_iris * up;  // limbus radius on the fine grid
  const double rp_min = std::max(po.min_radius_px * up, po.min_radius_ratio * ru);
  const double rp_max = po.max_radius_ratio * ru;
  if (!(rp_max > rp_min)) return loc;  // the iris is too small to resolve a pupil in it
  const RadialFilter fp = make_radial_filter(rp_min, rp_max, o.radius_step_px, po.sigma_px, true);
  const double reach = po.max_offset_ratio * ru;
  const int kernel = static_cast<int>(std::ceil(fp.k_max * fp.dr)) + 2;
  const int half = static_cast<int>(std::ceil(reach)) + kernel + 3;
  const cv::Point2d anchor(std::round(limbus.refined.x), std::round(limbus.refined.y));
  // fine (i, j) -> patch anchor + ((i, j) - half) / up
  const cv::Matx23d patch_from_fine(1 / up, 0, anchor.x - half / up, 0, 1 / up,
                                    anchor.y - half / up);
  cv::Mat fine;
  cv::warpAffine(p.grey, fine, cv::Mat(patch_from_fine), cv::Size(2 * half + 1, 2 * half + 1),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  const RingTable ptable = make_ring_table(fp, po.cone_half_angle_deg, o.arc_step_px, fine.cols);
  const cv::Point2d lc = (limbus.refined - anchor) * up + cv::Point2d(half, half);
  // Grey levels above clip_percentile of the iris disc (0.8 x limbus radius) are clipped.
  if (po.clip_percentile < 100) {
    std::vector<float> disc;
    const double rr = 0.8 * ru;
    for (int y = std::max(0, static_cast<int>(lc.y - rr));
         y <= std::min(fine.rows - 1, static_cast<int>(lc.y + rr)); ++y)
      for (int x = std::max(0, static_cast<int>(lc.x - rr));
           x <= std::min(fine.cols - 1, static_cast<int>(lc.x + rr)); ++x)
        if ((x - lc.x) * (x - lc.x) + (y - lc.y) * (y - lc.y) <= rr * rr)
          disc.push_back(fine.at<float>(y, x));
    if (!disc.empty()) {
      const auto k = static_cast<size_t>(po.clip_percentile / 100 * (disc.size() - 1));
      std::nth_element(disc.begin(), disc.begin() + static_cast<std::ptrdiff_t>(k), disc.end());
      cv::min(fine, disc[k], fine);
    }
  }
  const int lo = ptable.reach + 2, hi = fine.cols - 3 - ptable.reach;
  const int x0 = std::max(lo, static_cast<int>(std::ceil(lc.x - reach)));
  const int x1 = std::min(hi, static_cast<int>(std::floor(lc.x + reach)));
  const int y0 = std::max(lo, static_cast<int>(std::ceil(lc.y - reach)));
  const int y1 = std::min(hi, static_cast<int>(std::floor(lc.y + reach)));
  if (x0 > x1 || y0 > y1) return loc;
  const cv::Rect pc(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  const cv::Rect pgrown(pc.x - 1, pc.y - 1, pc.width + 2, pc.height + 2);
  cv::Mat pscore, pbest;
  const Inside inside{lc, ru, 2 * po.sigma_px + o.radius_step_px};
  score_candidates(fine, pgrown, ptable, fp, true, &inside, o.coarse_step, pscore, pbest);
  const detail::Peak pupil = detail::find_peak(pscore, pc);
  loc.pupil_score = pupil.value;
  if (!(pupil.value >= po.min_step) || !(pupil.value >= po.min_step_ratio * loc.score)) return loc;
  loc.pupil_found = true;
  loc.pupil_radius_px = (pbest.at<int>(pupil.best) - 0.5) * fp.dr / (up * p.scale);
  const cv::Point2d q = pupil.refined;
  loc.center_px = detail::to_image(p, {patch_from_fine(0, 0) * q.x + patch_from_fine(0, 2),
                                       patch_from_fine(1, 1) * q.y + patch_from_fine(1, 2)});
  return loc;
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
