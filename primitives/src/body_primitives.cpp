#include "dreamsense/primitives/body_primitives.hpp"

namespace dreamsense::primitives {

std::optional<cv::Vec3d> body_centre(const SkeletonBody& b) {
  if (b.joint(JointId::kSpine).valid()) return b.joint(JointId::kSpine).position_m;
  const auto& sc = b.joint(JointId::kShoulderCenter);
  const auto& hc = b.joint(JointId::kHipCenter);
  if (sc.valid() && hc.valid()) return (sc.position_m + hc.position_m) * 0.5;
  if (sc.valid()) return sc.position_m;
  return std::nullopt;
}

std::vector<JointPosition> body_pose(const SkeletonBody& b) {
  std::vector<JointPosition> out;
  for (int i = 0; i < kDreamJointCount; ++i) {
    const auto& j = b.joints[i];
    out.push_back(
        {static_cast<JointId>(i), j.valid() ? j.position_m : cv::Vec3d(0, 0, 0), j.confidence});
  }
  return out;
}

Hands hands(const SkeletonBody& b) {
  auto pick = [&](JointId hand, JointId wrist) -> std::optional<cv::Vec3d> {
    if (b.joint(hand).valid()) return b.joint(hand).position_m;
    if (b.joint(wrist).valid()) return b.joint(wrist).position_m;
    return std::nullopt;
  };
  return {pick(JointId::kHandLeft, JointId::kWristLeft),
          pick(JointId::kHandRight, JointId::kWristRight)};
}

std::optional<HandPrediction> predict_hand(const std::vector<Entry<BodyState>>& history,
                                           const cv::Vec3d& seed, double dt_s, double window_s) {
  if (history.empty() || !history.front().present()) return std::nullopt;
  const Hands now = hands(history.front().value->body);
  bool left;
  if (now.left && now.right)
    left = cv::norm(*now.left - seed) < cv::norm(*now.right - seed);
  else if (now.left || now.right)
    left = now.left.has_value();
  else
    return std::nullopt;
  // Least-squares line p(t) = p0 + v t over the recent samples (t relative to the newest).
  const Timestamp t0 = history.front().stamp;
  double st = 0, stt = 0;
  cv::Vec3d sp(0, 0, 0), stp(0, 0, 0);
  int n = 0;
  for (const auto& e : history) {
    if (!e.present()) break;
    const double t = (e.stamp - t0).seconds();
    if (-t > window_s) break;
    const Hands h = hands(e.value->body);
    const auto& p = left ? h.left : h.right;
    if (!p) break;
    st += t;
    stt += t * t;
    sp += *p;
    stp += *p * t;
    ++n;
  }
  HandPrediction out;
  out.left = left;
  out.samples = n;
  const double denom = n * stt - st * st;
  if (n >= 2 && denom > 1e-12) {
    out.velocity_mps = (stp * n - sp * st) / denom;
    const cv::Vec3d p0 = (sp - out.velocity_mps * st) / n;
    out.position_m = p0 + out.velocity_mps * dt_s;
  } else {
    out.velocity_mps = {0, 0, 0};
    out.position_m = *(left ? now.left : now.right);
  }
  return out;
}

}  // namespace dreamsense::primitives
