#include "dreamsense/actions/normalization.hpp"

#include "dreamsense/core/skeleton_bones.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>

namespace dreamsense::actions {
namespace {

constexpr int J(JointId id) { return static_cast<int>(id); }

// The Kinect v1 skeleton tree (undirected edges), used to fill joints never seen in a window.
constexpr const auto& kBones = kSkeletonBones;

// Reference bone lengths (parent, child, length in body units = torso + shoulder width), in an
// order where every parent comes before its children (from the hip centre). Adult proportions
// (e.g. upper arm 0.28, forearm 0.25 of a unit of about 0.7 m).
struct RefBone {
  JointId parent, child;
  float length;
};
constexpr std::array<RefBone, 19> kReference = {{
    {JointId::kHipCenter, JointId::kSpine, 0.30f},
    {JointId::kSpine, JointId::kShoulderCenter, 0.30f},
    {JointId::kShoulderCenter, JointId::kHead, 0.22f},
    {JointId::kShoulderCenter, JointId::kShoulderLeft, 0.20f},
    {JointId::kShoulderLeft, JointId::kElbowLeft, 0.38f},
    {JointId::kElbowLeft, JointId::kWristLeft, 0.34f},
    {JointId::kWristLeft, JointId::kHandLeft, 0.10f},
    {JointId::kShoulderCenter, JointId::kShoulderRight, 0.20f},
    {JointId::kShoulderRight, JointId::kElbowRight, 0.38f},
    {JointId::kElbowRight, JointId::kWristRight, 0.34f},
    {JointId::kWristRight, JointId::kHandRight, 0.10f},
    {JointId::kHipCenter, JointId::kHipLeft, 0.13f},
    {JointId::kHipLeft, JointId::kKneeLeft, 0.55f},
    {JointId::kKneeLeft, JointId::kAnkleLeft, 0.52f},
    {JointId::kAnkleLeft, JointId::kFootLeft, 0.12f},
    {JointId::kHipCenter, JointId::kHipRight, 0.13f},
    {JointId::kHipRight, JointId::kKneeRight, 0.55f},
    {JointId::kKneeRight, JointId::kAnkleRight, 0.52f},
    {JointId::kAnkleRight, JointId::kFootRight, 0.12f},
}};

constexpr std::array<JointId, 7> kTorso = {
    JointId::kShoulderCenter, JointId::kSpine,   JointId::kHipCenter, JointId::kShoulderLeft,
    JointId::kShoulderRight,  JointId::kHipLeft, JointId::kHipRight};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}

}  // namespace

bool joint_usable(const JointObservation& j) {
  return j.confidence > 0.f && std::isfinite(j.position_m[0]) && std::isfinite(j.position_m[1]) &&
         std::isfinite(j.position_m[2]);
}

SkeletonFrame to_skeleton_frame(const SkeletonBody& body, int64_t stamp_ns) {
  SkeletonFrame f;
  f.stamp_ns = stamp_ns;
  f.joints = body.joints;
  return f;
}

Status BodyFrameOptions::check() const {
  const double n = cv::norm(up);
  if (!std::isfinite(n) || n < 1e-9)
    return make_error(ErrorCode::kInvalidArgument, "body frame: up must be a non-zero vector");
  if (!(min_confidence >= 0.f && min_confidence <= 1.f))
    return make_error(ErrorCode::kInvalidArgument,
                      "body frame: min_confidence must be in [0, 1] (got {})", min_confidence);
  if (!(default_body_size_m > 0))
    return make_error(ErrorCode::kInvalidArgument, "body frame: default_body_size_m must be > 0");
  return ok_status();
}

NormalizedWindow normalize_window(std::span<const SkeletonFrame> frames,
                                  const BodyFrameOptions& o) {
  NormalizedWindow w;
  const int n = static_cast<int>(frames.size());
  if (n == 0) return w;
  w.frames = n;
  w.t_s.resize(static_cast<size_t>(n));
  for (int f = 0; f < n; ++f)
    w.t_s[static_cast<size_t>(f)] =
        static_cast<double>(frames[static_cast<size_t>(f)].stamp_ns - frames[0].stamp_ns) * 1e-9;

  // Observed joints, in metres (sensor frame).
  const size_t total = static_cast<size_t>(n) * kJointCount;
  std::vector<cv::Vec3d> p(total);
  w.observed.assign(total, 0);
  auto idx = [](int f, int j) {
    return static_cast<size_t>(f) * kJointCount + static_cast<size_t>(j);
  };
  size_t observed = 0;
  for (int f = 0; f < n; ++f)
    for (int j = 0; j < kJointCount; ++j) {
      const JointObservation& obs = frames[static_cast<size_t>(f)].joints[static_cast<size_t>(j)];
      if (joint_usable(obs) && obs.confidence >= o.min_confidence) {
        p[idx(f, j)] = obs.position_m;
        w.observed[idx(f, j)] = 1;
        ++observed;
      }
    }
  w.observed_fraction = static_cast<double>(observed) / static_cast<double>(total);
  bool torso_seen = false;
  for (JointId t : kTorso)
    for (int f = 0; f < n && !torso_seen; ++f) torso_seen = w.observed[idx(f, J(t))] != 0;
  if (!torso_seen) return w;

  // 1. Fill in time: interpolate between the same joint's observations, hold at the ends.
  std::array<bool, kJointCount> ever{};
  for (int j = 0; j < kJointCount; ++j) {
    int prev = -1;
    for (int f = 0; f < n; ++f) {
      if (!w.observed[idx(f, j)]) continue;
      ever[static_cast<size_t>(j)] = true;
      if (prev < 0) {
        for (int g = 0; g < f; ++g) p[idx(g, j)] = p[idx(f, j)];
      } else if (f > prev + 1) {
        const double t0 = w.t_s[static_cast<size_t>(prev)], t1 = w.t_s[static_cast<size_t>(f)];
        for (int g = prev + 1; g < f; ++g) {
          const double a = t1 > t0 ? (w.t_s[static_cast<size_t>(g)] - t0) / (t1 - t0) : 0.5;
          p[idx(g, j)] = (1 - a) * p[idx(prev, j)] + a * p[idx(f, j)];
        }
      }
      prev = f;
    }
    if (prev >= 0)
      for (int g = prev + 1; g < n; ++g) p[idx(g, j)] = p[idx(prev, j)];
  }
  // 2. Joints never observed: their nearest observed neighbour along the tree (BFS order).
  std::deque<int> queue;
  std::array<bool, kJointCount> filled = ever;
  for (int j = 0; j < kJointCount; ++j)
    if (ever[static_cast<size_t>(j)]) queue.push_back(j);
  while (!queue.empty()) {
    const int a = queue.front();
    queue.pop_front();
    for (const auto& [u, v] : kBones) {
      int b = -1;
      if (J(u) == a) b = J(v);
      if (J(v) == a) b = J(u);
      if (b < 0 || filled[static_cast<size_t>(b)]) continue;
      for (int f = 0; f < n; ++f) p[idx(f, b)] = p[idx(f, a)];
      filled[static_cast<size_t>(b)] = true;
      queue.push_back(b);
    }
  }

  // 3. Body frame.
  const cv::Vec3d up = o.up / cv::norm(o.up);
  cv::Vec3d origin(0, 0, 0);
  for (int f = 0; f < n; ++f) origin += p[idx(f, J(JointId::kHipCenter))];
  origin /= n;
  cv::Vec3d lateral(0, 0, 0);
  std::vector<double> torso, shoulders;
  auto both = [&](int f, JointId a, JointId b) {
    return w.observed[idx(f, J(a))] && w.observed[idx(f, J(b))];
  };
  for (int f = 0; f < n; ++f) {
    if (both(f, JointId::kShoulderLeft, JointId::kShoulderRight)) {
      const cv::Vec3d d =
          p[idx(f, J(JointId::kShoulderLeft))] - p[idx(f, J(JointId::kShoulderRight))];
      lateral += d;
      shoulders.push_back(cv::norm(d));
    }
    if (both(f, JointId::kHipLeft, JointId::kHipRight))
      lateral += p[idx(f, J(JointId::kHipLeft))] - p[idx(f, J(JointId::kHipRight))];
    if (both(f, JointId::kShoulderCenter, JointId::kHipCenter))
      torso.push_back(
          cv::norm(p[idx(f, J(JointId::kShoulderCenter))] - p[idx(f, J(JointId::kHipCenter))]));
  }
  cv::Matx33d R = cv::Matx33d::eye();
  if (o.normalize_facing) {
    lateral -= up * lateral.dot(up);
    w.facing_known = cv::norm(lateral) > 1e-6;
    if (!w.facing_known) {
      lateral = cv::Vec3d(1, 0, 0) - up * up[0];
      if (cv::norm(lateral) < 1e-6) lateral = cv::Vec3d(0, 0, 1) - up * up[2];
    }
    lateral /= cv::norm(lateral);
    const cv::Vec3d forward = lateral.cross(up);
    R = cv::Matx33d(lateral[0], lateral[1], lateral[2], up[0], up[1], up[2], forward[0], forward[1],
                    forward[2]);
  }
  double size = 1.0;
  if (o.normalize_scale) {
    const double t = median(torso), s = median(shoulders);
    size = t > 0 && s > 0 ? t + s : t > 0 ? 2 * t : s > 0 ? 2 * s : o.default_body_size_m;
  }
  w.body_size_m = size;
  w.positions.resize(total);
  for (size_t i = 0; i < total; ++i) {
    const cv::Vec3d q = R * ((p[i] - origin) * (1.0 / size));
    w.positions[i] =
        cv::Vec3f(static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2]));
  }
  if (o.normalize_bones && o.normalize_scale) {
    for (int f = 0; f < n; ++f) {
      cv::Vec3f* q = &w.positions[static_cast<size_t>(f) * kJointCount];
      std::array<cv::Vec3f, kJointCount> out{};
      out[static_cast<size_t>(J(JointId::kHipCenter))] = q[J(JointId::kHipCenter)];
      for (const RefBone& b : kReference) {
        const cv::Vec3f d = q[J(b.child)] - q[J(b.parent)];
        const float len = static_cast<float>(cv::norm(d));
        out[static_cast<size_t>(J(b.child))] =
            out[static_cast<size_t>(J(b.parent))] + (len > 1e-6f ? d * (b.length / len) : d);
      }
      std::copy(out.begin(), out.end(), q);
    }
  }
  w.usable = true;
  return w;
}

void mirror_left_right(NormalizedWindow& w) {
  static constexpr std::array<std::pair<JointId, JointId>, 8> kPairs = {{
      {JointId::kShoulderLeft, JointId::kShoulderRight},
      {JointId::kElbowLeft, JointId::kElbowRight},
      {JointId::kWristLeft, JointId::kWristRight},
      {JointId::kHandLeft, JointId::kHandRight},
      {JointId::kHipLeft, JointId::kHipRight},
      {JointId::kKneeLeft, JointId::kKneeRight},
      {JointId::kAnkleLeft, JointId::kAnkleRight},
      {JointId::kFootLeft, JointId::kFootRight},
  }};
  for (int f = 0; f < w.frames; ++f) {
    const size_t base = static_cast<size_t>(f) * kJointCount;
    for (int j = 0; j < kJointCount; ++j) w.positions[base + static_cast<size_t>(j)][0] *= -1.f;
    for (const auto& [l, r] : kPairs) {
      std::swap(w.positions[base + static_cast<size_t>(l)],
                w.positions[base + static_cast<size_t>(r)]);
      std::swap(w.observed[base + static_cast<size_t>(l)],
                w.observed[base + static_cast<size_t>(r)]);
    }
  }
}

std::vector<cv::Vec3f> resample_positions(const NormalizedWindow& w, int n) {
  std::vector<cv::Vec3f> out(static_cast<size_t>(std::max(n, 0)) * kJointCount);
  if (n <= 0 || w.frames == 0) return out;
  const double duration = w.t_s.back();
  int k = 0;  // w.t_s[k] <= t < w.t_s[k + 1]
  for (int i = 0; i < n; ++i) {
    const double t = n > 1 ? duration * i / (n - 1) : 0.0;
    while (k + 1 < w.frames - 1 && w.t_s[static_cast<size_t>(k + 1)] <= t) ++k;
    int a = k, b = std::min(k + 1, w.frames - 1);
    double u = 0;
    if (b != a) {
      const double t0 = w.t_s[static_cast<size_t>(a)], t1 = w.t_s[static_cast<size_t>(b)];
      u = t1 > t0 ? std::clamp((t - t0) / (t1 - t0), 0.0, 1.0) : 0.0;
    }
    const float uf = static_cast<float>(u);
    for (int j = 0; j < kJointCount; ++j)
      out[static_cast<size_t>(i) * kJointCount + static_cast<size_t>(j)] =
          (1.f - uf) * w.at(a, j) + uf * w.at(b, j);
  }
  return out;
}

}  // namespace dreamsense::actions
