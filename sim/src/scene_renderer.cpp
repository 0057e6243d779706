#include "dreamsense/sim/scene_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dreamsense::sim {
namespace {

constexpr double kNear = 0.02;  // metres

struct Pinhole {
  double fx, fy, cx, cy;
  explicit Pinhole(const CameraModel& c)
      : fx(c.K(0, 0)), fy(c.K(1, 1)), cx(c.K(0, 2)), cy(c.K(1, 2)) {}
  cv::Vec3d ray(int u, int v) const { return {(u - cx) / fx, (v - cy) / fy, 1.0}; }
};

cv::Vec3b to_bgr(const cv::Vec3f& c, double shade) {
  return cv::Vec3b(cv::saturate_cast<uchar>(c[0] * shade), cv::saturate_cast<uchar>(c[1] * shade),
                   cv::saturate_cast<uchar>(c[2] * shade));
}

// Bilinear texel fetch; returns alpha in [0, 255] (255 for 3-channel textures).
cv::Vec4f sample(const cv::Mat& tex, double x, double y) {
  x = std::clamp(x, 0.0, tex.cols - 1.0);
  y = std::clamp(y, 0.0, tex.rows - 1.0);
  const int x0 = std::min(static_cast<int>(x), tex.cols - 2 < 0 ? 0 : tex.cols - 2);
  const int y0 = std::min(static_cast<int>(y), tex.rows - 2 < 0 ? 0 : tex.rows - 2);
  const int x1 = std::min(x0 + 1, tex.cols - 1), y1 = std::min(y0 + 1, tex.rows - 1);
  const double fx = x - x0, fy = y - y0;
  cv::Vec4f out(0, 0, 0, 255);
  const int ch = tex.channels();
  const uchar* r0 = tex.ptr<uchar>(y0);
  const uchar* r1 = tex.ptr<uchar>(y1);
  for (int k = 0; k < ch; ++k) {
    const double a = r0[x0 * ch + k] * (1 - fx) + r0[x1 * ch + k] * fx;
    const double b = r1[x0 * ch + k] * (1 - fx) + r1[x1 * ch + k] * fx;
    out[k] = static_cast<float>(a * (1 - fy) + b * fy);
  }
  return out;
}

std::vector<cv::Vec3d> box_corners(const cv::Vec3d& lo, const cv::Vec3d& hi) {
  std::vector<cv::Vec3d> c;
  for (int i = 0; i < 8; ++i)
    c.emplace_back((i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]);
  return c;
}

template <typename Fn>
void for_pixels(const cv::Rect& r, Fn&& fn) {
  for (int v = r.y; v < r.y + r.height; ++v)
    for (int u = r.x; u < r.x + r.width; ++u) fn(u, v);
}

void render_quad(const CameraModel& cam, const Pinhole& ph, const Quad& q, const Lighting& light,
                 RenderTarget& t) {
  const cv::Vec3d o = cam.to_camera(q.origin);
  const cv::Vec3d eu = cam.R * q.edge_u, ev = cam.R * q.edge_v;
  const cv::Vec3d n = eu.cross(ev);
  if (cv::norm(n) < 1e-12) return;
  const cv::Vec3d du = ev.cross(n), dv = n.cross(eu);
  const double su = 1.0 / eu.dot(du), sv = 1.0 / ev.dot(dv);
  const double no = n.dot(o);
  const cv::Rect r = projected_bounds(
      cam, {q.origin, q.origin + q.edge_u, q.origin + q.edge_v, q.origin + q.edge_u + q.edge_v},
      t.bgr.size());
  const cv::Vec3d n_world = q.edge_u.cross(q.edge_v);
  const double shade = lambert_shade(n_world, q.origin - cam.centre_world(), light);
  const cv::Mat* tex = q.texture ? q.texture.get() : nullptr;
  for_pixels(r, [&](int u, int v) {
    const cv::Vec3d d = ph.ray(u, v);
    const double den = n.dot(d);
    if (std::abs(den) < 1e-12) return;
    const double z = no / den;
    float& zb = t.depth.at<float>(v, u);
    if (z <= kNear || z >= zb) return;
    const cv::Vec3d p = z * d - o;
    const double a = p.dot(du) * su, b = p.dot(dv) * sv;
    if (a < 0 || a > 1 || b < 0 || b > 1) return;
    if (tex) {
      const cv::Vec4f s = sample(*tex, a * tex->cols - 0.5, b * tex->rows - 0.5);
      if (s[3] < 128) return;
      t.bgr.at<cv::Vec3b>(v, u) = to_bgr(cv::Vec3f(s[0], s[1], s[2]), shade);
    } else {
      t.bgr.at<cv::Vec3b>(v, u) = to_bgr(q.bgr, shade);
    }
    zb = static_cast<float>(z);
  });
}

void render_capsule(const CameraModel& cam, const Pinhole& ph, const Capsule& c,
                    const Lighting& light, RenderTarget& t) {
  const cv::Vec3d pa = cam.to_camera(c.a), pb = cam.to_camera(c.b);
  const cv::Vec3d lo(std::min(c.a[0], c.b[0]) - c.radius, std::min(c.a[1], c.b[1]) - c.radius,
                     std::min(c.a[2], c.b[2]) - c.radius);
  const cv::Vec3d hi(std::max(c.a[0], c.b[0]) + c.radius, std::max(c.a[1], c.b[1]) + c.radius,
                     std::max(c.a[2], c.b[2]) + c.radius);
  const cv::Rect r = projected_bounds(cam, box_corners(lo, hi), t.bgr.size());
  const cv::Vec3d ba = pb - pa;
  const cv::Vec3d oa = -pa;
  const double baba = ba.dot(ba), baoa = ba.dot(oa), oaoa = oa.dot(oa);
  const double rr = c.radius * c.radius;
  const cv::Vec3d light_cam = cam.R * light.direction;
  // Cheap 2-D early out: distance from the pixel to the projected axis segment. The projected
  // outline of the capsule lies within a (conservative) pixel radius of that segment.
  const bool early_out = pa[2] - c.radius > kNear && pb[2] - c.radius > kNear;
  cv::Point2d a2, b2;
  double radius_px = 0;
  if (early_out) {
    a2 = {ph.fx * pa[0] / pa[2] + ph.cx, ph.fy * pa[1] / pa[2] + ph.cy};
    b2 = {ph.fx * pb[0] / pb[2] + ph.cx, ph.fy * pb[1] / pb[2] + ph.cy};
    radius_px = 1.5 * std::max(ph.fx, ph.fy) * c.radius / (std::min(pa[2], pb[2]) - c.radius) + 2;
  }
  // Row span of the projected stadium (hull of the two end discs and the band between them).
  auto row_span = [&](int v, int& u0, int& u1) {
    double lo = 1e18, hi = -1e18;
    for (const cv::Point2d& p : {a2, b2}) {
      const double dy = v - p.y;
      if (std::abs(dy) <= radius_px) {
        const double w = std::sqrt(radius_px * radius_px - dy * dy);
        lo = std::min(lo, p.x - w);
        hi = std::max(hi, p.x + w);
      }
    }
    const cv::Point2d d = b2 - a2;
    const double len = std::sqrt(d.dot(d));
    if (len > 1e-9) {
      // Constraints linear in u: |n . (p - a)| <= R and 0 <= t . (p - a) <= len (unit n, t).
      const cv::Point2d t(d.x / len, d.y / len), n(-t.y, t.x);
      double blo = -1e18, bhi = 1e18;
      auto clip = [&](double coef, double offset, double min_v, double max_v) {
        // min_v <= coef * u + offset <= max_v
        if (std::abs(coef) < 1e-12) {
          if (offset < min_v || offset > max_v) blo = 1e18;
          return;
        }
        double x0 = (min_v - offset) / coef, x1 = (max_v - offset) / coef;
        if (x0 > x1) std::swap(x0, x1);
        blo = std::max(blo, x0);
        bhi = std::min(bhi, x1);
      };
      const double dy = v - a2.y;
      clip(n.x, n.y * dy - n.x * a2.x, -radius_px, radius_px);
      clip(t.x, t.y * dy - t.x * a2.x, 0.0, len);
      if (blo <= bhi) {
        lo = std::min(lo, blo);
        hi = std::max(hi, bhi);
      }
    }
    if (lo > hi) {
      u0 = 1;
      u1 = 0;
      return;
    }
    u0 = std::max(r.x, static_cast<int>(std::floor(lo)));
    u1 = std::min(r.x + r.width - 1, static_cast<int>(std::ceil(hi)));
  };
  for (int v = r.y; v < r.y + r.height; ++v) {
    int u0 = r.x, u1 = r.x + r.width - 1;
    if (early_out) row_span(v, u0, u1);
    for (int u = u0; u <= u1; ++u) {
      cv::Vec3d rd = ph.ray(u, v);
      const double inv = 1.0 / cv::norm(rd);
      rd *= inv;
      const double bard = ba.dot(rd), rdoa = rd.dot(oa);
      const double qa = baba - bard * bard;
      double qb = baba * rdoa - baoa * bard;
      double qc = baba * oaoa - baoa * baoa - rr * baba;
      double h = qb * qb - qa * qc;
      if (h < 0) continue;
      double dist = -1;
      if (qa > 1e-12) {
        const double tt = (-qb - std::sqrt(h)) / qa;
        const double y = baoa + tt * bard;
        if (y > 0 && y < baba) dist = tt;
      }
      if (dist < 0) {
        // End caps: nearest of the two spheres.
        for (const cv::Vec3d& centre : {pa, pb}) {
          const cv::Vec3d oc = -centre;
          const double b2 = rd.dot(oc), c2 = oc.dot(oc) - rr;
          const double h2 = b2 * b2 - c2;
          if (h2 <= 0) continue;
          const double tt = -b2 - std::sqrt(h2);
          if (tt > 0 && (dist < 0 || tt < dist)) dist = tt;
        }
      }
      if (dist <= 0) continue;
      const cv::Vec3d p = dist * rd;
      const double z = p[2];
      float& zb = t.depth.at<float>(v, u);
      if (z <= kNear || z >= zb) continue;
      const double s = std::clamp((p - pa).dot(ba) / std::max(baba, 1e-12), 0.0, 1.0);
      const cv::Vec3d n = (p - (pa + s * ba)) / c.radius;
      const double shade =
          light.ambient + light.diffuse * std::max(0.0, -n.dot(light_cam) / cv::norm(light_cam));
      t.bgr.at<cv::Vec3b>(v, u) = to_bgr(c.bgr, shade);
      zb = static_cast<float>(z);
    }
  }
}

void render_ellipsoid(const CameraModel& cam, const Pinhole& ph, const Ellipsoid& e,
                      const Lighting& light, RenderTarget& t) {
  // Exact world-axis-aligned half extents of the rotated ellipsoid.
  cv::Vec3d half;
  for (int i = 0; i < 3; ++i)
    half[i] =
        std::sqrt(std::pow(e.axes(i, 0) * e.radii[0], 2) + std::pow(e.axes(i, 1) * e.radii[1], 2) +
                  std::pow(e.axes(i, 2) * e.radii[2], 2));
  const cv::Rect r =
      projected_bounds(cam, box_corners(e.centre - half, e.centre + half), t.bgr.size());
  // Local (unit sphere) coordinates: q = S^-1 * A^T * R^T * (x_cam - c_cam).
  const cv::Matx33d M =
      cv::Matx33d::diag(cv::Vec3d(1 / e.radii[0], 1 / e.radii[1], 1 / e.radii[2])) * e.axes.t() *
      cam.R.t();
  const cv::Vec3d ro = M * (-cam.to_camera(e.centre));
  const double roro = ro.dot(ro);
  const cv::Vec3d light_cam = cam.R * light.direction;
  const cv::Matx33d normal_to_cam =
      cam.R * e.axes * cv::Matx33d::diag(cv::Vec3d(1 / e.radii[0], 1 / e.radii[1], 1 / e.radii[2]));
  for_pixels(r, [&](int u, int v) {
    const cv::Vec3d d = ph.ray(u, v);
    const cv::Vec3d rd = M * d;
    const double a = rd.dot(rd), b = ro.dot(rd), c = roro - 1;
    const double h = b * b - a * c;
    if (h < 0) return;
    const double z = (-b - std::sqrt(h)) / a;  // d has unit z, so the ray parameter is z
    float& zb = t.depth.at<float>(v, u);
    if (z <= kNear || z >= zb) return;
    const cv::Vec3d q = ro + z * rd;
    cv::Vec3d n = normal_to_cam * q;
    n /= cv::norm(n);
    const double shade =
        light.ambient + light.diffuse * std::max(0.0, -n.dot(light_cam) / cv::norm(light_cam));
    t.bgr.at<cv::Vec3b>(v, u) = to_bgr(e.bgr, shade);
    zb = static_cast<float>(z);
  });
}

}  // namespace

RenderTarget RenderTarget::empty(const cv::Size& size) {
  return {cv::Mat(size, CV_8UC3, cv::Scalar::all(0)),
          cv::Mat(size, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()))};
}

double lambert_shade(const cv::Vec3d& normal, const cv::Vec3d& view_dir, const Lighting& lighting) {
  cv::Vec3d n = normal / std::max(cv::norm(normal), 1e-12);
  if (n.dot(view_dir) > 0) n = -n;  // the side facing the viewer
  const cv::Vec3d l = lighting.direction / std::max(cv::norm(lighting.direction), 1e-12);
  return lighting.ambient + lighting.diffuse * std::max(0.0, -n.dot(l));
}

cv::Rect projected_bounds(const CameraModel& camera, const std::vector<cv::Vec3d>& points,
                          const cv::Size& size, int margin) {
  const Pinhole ph(camera);
  double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
  for (const auto& p : points) {
    const cv::Vec3d c = camera.to_camera(p);
    if (c[2] < kNear) return cv::Rect(cv::Point(0, 0), size);
    const double u = ph.fx * c[0] / c[2] + ph.cx, v = ph.fy * c[1] / c[2] + ph.cy;
    u0 = std::min(u0, u);
    v0 = std::min(v0, v);
    u1 = std::max(u1, u);
    v1 = std::max(v1, v);
  }
  const double lim = 1e6;
  const int x0 = static_cast<int>(std::floor(std::clamp(u0, -lim, lim))) - margin;
  const int y0 = static_cast<int>(std::floor(std::clamp(v0, -lim, lim))) - margin;
  const int x1 = static_cast<int>(std::ceil(std::clamp(u1, -lim, lim))) + margin;
  const int y1 = static_cast<int>(std::ceil(std::clamp(v1, -lim, lim))) + margin;
  return cv::Rect(cv::Point(x0, y0), cv::Point(x1 + 1, y1 + 1)) & cv::Rect(cv::Point(0, 0), size);
}

void render_primitives(const CameraModel& camera, const std::vector<Primitive>& primitives,
                       const Lighting& lighting, RenderTarget& target) {
  DS_CHECK(target.bgr.type() == CV_8UC3 && target.depth.type() == CV_32F);
  DS_CHECK(target.bgr.size() == camera.image_size && target.depth.size() == camera.image_size);
  const Pinhole ph(camera);
  for (const auto& prim : primitives) {
    std::visit(
        [&](const auto& p) {
          using T = std::decay_t<decltype(p)>;
          if constexpr (std::is_same_v<T, Quad>) render_quad(camera, ph, p, lighting, target);
          if constexpr (std::is_same_v<T, Capsule>) render_capsule(camera, ph, p, lighting, target);
          if constexpr (std::is_same_v<T, Ellipsoid>)
            render_ellipsoid(camera, ph, p, lighting, target);
        },
        prim);
  }
}

}  // namespace dreamsense::sim
