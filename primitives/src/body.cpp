#include "dreamsense/primitives/body.hpp"

#include "dreamsense/primitives/registry.hpp"

#include <cmath>

namespace dreamsense::primitives {

Status BodyPrimitiveOptions::check() const {
  if (!(track_hand_dt_s >= 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "BodyPrimitiveOptions: track_hand_dt_s must be >= 0");
  return ok_status();
}

namespace {
constexpr double kArmRadToDeg = 180.0 / M_PI;

cv::Vec3d unit_or_zero(const cv::Vec3d& v) {
  const double n = cv::norm(v);
  return n > 1e-9 ? v / n : cv::Vec3d(0, 0, 0);
}

std::optional<ArmAngle> upper_arm_angle(const SkeletonBody& b, JointId shoulder, JointId elbow,
                                        const cv::Vec3d& lateral, const cv::Vec3d& up,
                                        const cv::Vec3d& forward) {
  if (!b.joint(shoulder).valid() || !b.joint(elbow).valid()) return std::nullopt;
  const cv::Vec3d u = unit_or_zero(b.joint(elbow).position_m - b.joint(shoulder).position_m);
  if (cv::norm(u) == 0) return std::nullopt;
  ArmAngle a;
  a.elevation_deg = std::asin(std::clamp(u.dot(up), -1.0, 1.0)) * kArmRadToDeg;
  a.azimuth_deg = std::atan2(u.dot(forward), u.dot(lateral)) * kArmRadToDeg;
  return a;
}
}  // namespace

ArmAnglesValue arm_angles(const SkeletonBody& b) {
  ArmAnglesValue out;
  const auto& ls = b.joint(JointId::kShoulderLeft);
  const auto& rs = b.joint(JointId::kShoulderRight);
  const auto& sc = b.joint(JointId::kShoulderCenter);
  if (!ls.valid() || !rs.valid() || !sc.valid()) return out;
  const cv::Vec3d x = unit_or_zero(ls.position_m - rs.position_m);
  // "Up" from the spine when it is tracked; otherwise the hip centre.
  const JointObservation& low =
      b.joint(JointId::kSpine).valid() ? b.joint(JointId::kSpine) : b.joint(JointId::kHipCenter);
  if (!low.valid()) return out;
  cv::Vec3d y = sc.position_m - low.position_m;
  y = unit_or_zero(y - x * y.dot(x));
  if (cv::norm(y) == 0) return out;
  const cv::Vec3d z = x.cross(y);
  out.left = upper_arm_angle(b, JointId::kShoulderLeft, JointId::kElbowLeft, x, y, z);
  out.right = upper_arm_angle(b, JointId::kShoulderRight, JointId::kElbowRight, -x, y, z);
  return out;
}

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

HandsValue hands(const SkeletonBody& b) {
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
  const HandsValue now = hands(history.front().value->body);
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
    const HandsValue h = hands(e.value->body);
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

namespace {

// The child's body of this tick with the status of all body primitives.
struct BodyObservation {
  Observation<BodyState> obs;
  SensorId source;
};
BodyObservation observe_body(const PrimitiveContext& ctx) {
  BodyObservation b{ctx.observe(keys::kChildBody), {}};
  const auto& sensors = ctx.sensors_of(keys::kChildBody.name);
  if (!sensors.empty()) b.source = sensors.front();
  return b;
}

template <typename V>
Answer<V> start(const BodyObservation& b) {
  Answer<V> a = Answer<V>::from(b.obs);
  a.source = b.source;
  return a;
}

template <typename V>
void answer_ok(Answer<V>& a, const BodyObservation& b, V value) {
  a.value = std::move(value);
  a.confidence = b.obs.entry->confidence;
}

}  // namespace

Answer<ArmAnglesValue> get_arm_angle(const PrimitiveContext& ctx) {
  const BodyObservation b = observe_body(ctx);
  auto a = start<ArmAnglesValue>(b);
  if (a.status != PrimitiveStatus::kOk) return a;
  ArmAnglesValue v = arm_angles(b.obs.value().body);
  if (!v.left && !v.right) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  answer_ok(a, b, v);
  return a;
}

Answer<BodyValue> get_body(const PrimitiveContext& ctx) {
  const BodyObservation b = observe_body(ctx);
  auto a = start<BodyValue>(b);
  if (a.status != PrimitiveStatus::kOk) return a;
  const auto c = body_centre(b.obs.value().body);
  if (!c) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  answer_ok(a, b, BodyValue{*c, b.obs.value().bodies_in_view});
  return a;
}

Answer<BodyPoseValue> get_body_pose(const PrimitiveContext& ctx) {
  const BodyObservation b = observe_body(ctx);
  auto a = start<BodyPoseValue>(b);
  if (a.status != PrimitiveStatus::kOk) return a;
  answer_ok(a, b, BodyPoseValue{body_pose(b.obs.value().body)});
  return a;
}

Answer<HandsValue> get_hands(const PrimitiveContext& ctx) {
  const BodyObservation b = observe_body(ctx);
  auto a = start<HandsValue>(b);
  if (a.status != PrimitiveStatus::kOk) return a;
  HandsValue h = hands(b.obs.value().body);
  if (!h.left && !h.right) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  answer_ok(a, b, h);
  return a;
}

Answer<TrackValue> track_hand(const PrimitiveContext& ctx, const std::optional<TrackQuery>& query) {
  const BodyObservation b = observe_body(ctx);
  auto a = start<TrackValue>(b);
  if (a.status != PrimitiveStatus::kOk) return a;
  TrackQuery q;
  if (query) {
    q = *query;
  } else {
    const HandsValue h = hands(b.obs.value().body);
    const std::optional<cv::Vec3d> seed = h.right ? h.right : h.left;
    if (!seed) {
      a.status = PrimitiveStatus::kNoData;
      return a;
    }
    q = TrackQuery{*seed, ctx.family_options<BodyPrimitiveOptions>().track_hand_dt_s};
  }
  a.query = q;
  auto p = predict_hand(ctx.view().history(keys::kChildBody, 16), q.seed_m, q.dt_s);
  if (!p) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  TrackValue v;
  v.position_m = p->position_m;
  v.velocity_mps = p->velocity_mps;
  v.hand = p->left ? "left" : "right";
  v.samples = p->samples;
  answer_ok(a, b, v);
  return a;
}

// The rows of the body family: everything is answered from the child's skeleton.
void register_body_primitives(PrimitiveRegistry& r) {
  using P = PrimitiveId;
  const std::vector<std::string> body{keys::kChildBody.name};
  r.add(P::kGetArmAngle, body, get_arm_angle);
  r.add(P::kGetBody, body, get_body);
  r.add(P::kGetBodyPose, body, get_body_pose);
  r.add(P::kGetHands, body, get_hands);
  r.add(P::kTrackHand, body, [](const PrimitiveContext& c) { return track_hand(c); });
}

}  // namespace dreamsense::primitives
