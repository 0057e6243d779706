#include "dreamsense/sim/demo_scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "sim_math.hpp"

namespace dreamsense::sim {
namespace {

constexpr double kTwoPi = 2.0 * CV_PI;
constexpr double kUpperArm = 0.21, kForearm = 0.19, kHand = 0.07;
constexpr double kTransitionS = 0.5;
constexpr double kHeadLagS = 0.06;  // the head starts turning after the eyes

using detail::uniform;

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

using detail::normalized;

// Two-bone inverse kinematics: elbow and (reachable) wrist for a wrist target, the elbow bending
// towards `pole`.
std::pair<cv::Vec3d, cv::Vec3d> solve_arm(const cv::Vec3d& shoulder, cv::Vec3d wrist,
                                          const cv::Vec3d& pole) {
  cv::Vec3d sw = wrist - shoulder;
  double d = cv::norm(sw);
  const double reach = kUpperArm + kForearm - 1e-3;
  const cv::Vec3d e = normalized(sw);
  if (d > reach) {
    d = reach;
    wrist = shoulder + e * d;
  }
  d = std::max(d, std::abs(kUpperArm - kForearm) + 1e-3);
  const double a = (kUpperArm * kUpperArm - kForearm * kForearm + d * d) / (2 * d);
  const double h = std::sqrt(std::max(0.0, kUpperArm * kUpperArm - a * a));
  cv::Vec3d q = pole - pole.dot(e) * e;
  q = normalized(q);
  return {shoulder + a * e + h * q, wrist};
}

}  // namespace

uint64_t sub_seed(uint64_t seed, std::string_view tag, uint64_t index) {
  uint64_t h = 1469598103934665603ULL;  // FNV-1a of the tag
  for (char c : tag) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (h ^ (index * 0xD1B54A32D192ED03ULL) ^ 0x5bd1e995ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

std::string_view action_label(DemoAction action) {
  switch (action) {
    case DemoAction::kNone:
      return "none";
    case DemoAction::kWave:
      return "wave";
    case DemoAction::kFly:
      return "fly";
    case DemoAction::kHandsOnHead:
      return "hands_on_head";
    case DemoAction::kCoverEyes:
      return "cover_eyes";
    case DemoAction::kDriveCar:
      return "drive_car";
    case DemoAction::kDrink:
      return "drink";
    case DemoAction::kCustom:
      return "custom";
  }
  return "none";
}

std::string_view gaze_target_label(GazeTargetKind kind) {
  switch (kind) {
    case GazeTargetKind::kRobot:
      return "robot";
    case GazeTargetKind::kObject:
      return "object";
    case GazeTargetKind::kTherapist:
      return "therapist";
    case GazeTargetKind::kTable:
      return "table";
    case GazeTargetKind::kElsewhere:
      return "elsewhere";
  }
  return "elsewhere";
}

int action_dream_id(DemoAction action) {
  switch (action) {
    case DemoAction::kNone:
      return 0;
    case DemoAction::kWave:
      return 1;
    case DemoAction::kFly:
      return 4;
    case DemoAction::kHandsOnHead:
      return 3;
    case DemoAction::kCoverEyes:
      return 2;
    case DemoAction::kDriveCar:
      return 5;
    case DemoAction::kDrink:
      return 6;
    case DemoAction::kCustom:
      return 7;
  }
  return 0;
}

Status DemoScriptOptions::check() const {
  for (size_t i = 0; i < custom.size(); ++i) {
    const CustomGesture& g = custom[i];
    if (g.label.empty() || !(g.period_s > 0.1 && g.period_s < 60))
      return make_error(ErrorCode::kInvalidArgument,
                        "custom gesture {}: needs a label and a period in (0.1, 60) s", i);
  }
  double t = 0;
  for (size_t i = 0; i < schedule.size(); ++i) {
    const ActionSegment& s = schedule[i];
    if (!(s.end_s > s.start_s) || std::abs(s.start_s - t) > 1e-9)
      return make_error(ErrorCode::kInvalidArgument,
                        "schedule segment {}: segments must tile the session in time order "
                        "([{}, {}) after {})",
                        i, s.start_s, s.end_s, t);
    if (s.action == DemoAction::kCustom &&
        (s.custom < 0 || s.custom >= static_cast<int>(custom.size())))
      return make_error(ErrorCode::kInvalidArgument,
                        "schedule segment {}: custom gesture {} is not defined", i, s.custom);
    t = s.end_s;
  }
  return ok_status();
}

std::vector<ActionSegment> make_action_schedule(uint64_t seed, double duration_s,
                                                DemoScriptOptions::GestureSet set) {
  std::mt19937_64 rng(sub_seed(seed, "actions"));
  std::vector<DemoAction> order = {DemoAction::kWave, DemoAction::kFly, DemoAction::kHandsOnHead};
  if (set == DemoScriptOptions::GestureSet::kDream)
    order.insert(order.end(), {DemoAction::kCoverEyes, DemoAction::kDriveCar, DemoAction::kDrink});
  if (set == DemoScriptOptions::GestureSet::kDreamFaceVisible)
    order.push_back(DemoAction::kDriveCar);
  for (size_t i = order.size() - 1; i > 0; --i)  // Fisher-Yates with our own draws (portable)
    std::swap(order[i], order[static_cast<size_t>(rng() % (i + 1))]);
  std::vector<ActionSegment> out;
  double t = 0;
  size_t k = 0;
  while (t < duration_s) {
    const double rest = uniform(rng, 0.8, 1.6);
    out.push_back({t, std::min(duration_s, t + rest), DemoAction::kNone});
    t += rest;
    if (t >= duration_s) break;
    const DemoAction a =
        k < order.size() ? order[k] : order[static_cast<size_t>(rng() % order.size())];
    ++k;
    const double len = uniform(rng, 2.0, 3.5);
    out.push_back({t, std::min(duration_s, t + len), a});
    t += len;
  }
  return out;
}

cv::Matx33d HeadPose::rotation() const {
  return rotation_from_ypr_deg(yaw_deg, pitch_deg, roll_deg);
}
cv::Vec3d HeadPose::gaze_dir() const { return rotation() * cv::Vec3d(0, 0, -1); }

void look_at_angles(const cv::Vec3d& from, const cv::Vec3d& to, double& yaw_deg,
                    double& pitch_deg) {
  // gaze = Ry(yaw) Rx(pitch) (0,0,-1) = (-sin(yaw) cos(pitch), sin(pitch), -cos(yaw) cos(pitch))
  const cv::Vec3d g = normalized(to - from);
  pitch_deg = std::asin(std::clamp(g[1], -1.0, 1.0)) * 180 / CV_PI;
  yaw_deg = std::atan2(-g[0], -g[2]) * 180 / CV_PI;
}

double ray_point_distance(const cv::Vec3d& origin, const cv::Vec3d& dir, const cv::Vec3d& point) {
  const cv::Vec3d d = normalized(dir);
  const double s = std::max(0.0, (point - origin).dot(d));
  return cv::norm(origin + s * d - point);
}

double DemoScript::eval(const std::vector<Sinusoid>& s, double t) {
  double v = 0;
  for (const auto& x : s) v += x.amplitude * std::sin(kTwoPi * x.freq_hz * t + x.phase);
  return v;
}

DemoScript::DemoScript(uint64_t seed, double duration_s, DemoGeometry geometry,
                       DemoScriptOptions options)
    : seed_(seed), duration_s_(duration_s), geometry_(geometry), options_(std::move(options)) {
  std::mt19937_64 rng(sub_seed(seed, "head"));
  auto two = [&](double total, double f_lo, double f_hi, double f2_lo, double f2_hi) {
    const double split = uniform(rng, 0.55, 0.75);
    return std::vector<Sinusoid>{
        {total * split, uniform(rng, f_lo, f_hi), uniform(rng, 0, kTwoPi)},
        {total * (1 - split), uniform(rng, f2_lo, f2_hi), uniform(rng, 0, kTwoPi)}};
  };
  // Free head wander on top of the turns towards the gaze targets (fixations, below).
  yaw_ = two(6.0, 0.05, 0.10, 0.13, 0.25);
  pitch_ = two(4.0, 0.07, 0.14, 0.18, 0.30);
  roll_ = two(10.0, 0.06, 0.12, 0.15, 0.28);
  pos_x_ = two(0.03, 0.04, 0.10, 0.12, 0.2);
  pos_y_ = two(0.015, 0.05, 0.12, 0.15, 0.25);
  pos_z_ = two(0.025, 0.04, 0.10, 0.12, 0.2);

  actions_ = options_.schedule.empty() ? make_action_schedule(seed, duration_s, options_.gestures)
                                       : options_.schedule;
  std::mt19937_64 arm_rng(sub_seed(seed, "arms"));
  wave_hz_ = uniform(arm_rng, 1.5, 2.2);
  fly_hz_ = uniform(arm_rng, 0.6, 1.0);
  std::mt19937_64 gesture_rng(sub_seed(seed, "gestures"));
  drive_hz_ = uniform(gesture_rng, 0.3, 0.6);
  drive_amp_rad_ = uniform(gesture_rng, 0.3, 0.6);
  drink_hz_ = uniform(gesture_rng, 0.3, 0.5);
  cover_hz_ = uniform(gesture_rng, 0.4, 0.8);

  // Table objects: one per x band (so paths never overlap), seed-dependent label per band.
  static const char* kNames[] = {"car", "cup", "flower", "plane"};
  std::mt19937_64 obj_rng(sub_seed(seed, "objects"));
  std::vector<int> labels = {0, 1, 2, 3};
  for (size_t i = labels.size() - 1; i > 0; --i)
    std::swap(labels[i], labels[static_cast<size_t>(obj_rng() % (i + 1))]);
  const int n = 4;
  const double band = (0.9 - 0.0) / n;  // objects live in x in [-0.45, 0.45]
  for (int i = 0; i < n; ++i) {
    TableObjectSpec spec;
    spec.id = i;
    spec.label = labels[static_cast<size_t>(i)];
    spec.label_name = kNames[spec.label];
    objects_.push_back(spec);
    ObjectPath p;
    p.x_centre = -0.45 + band * (i + 0.5);
    // Half-diagonal of the footprint is 0.0625 m; band half-width 0.1125 m: amplitude <= 0.045.
    p.x = {uniform(obj_rng, 0.02, 0.045), uniform(obj_rng, 0.05, 0.15),
           uniform(obj_rng, 0, kTwoPi)};
    p.z_centre = uniform(obj_rng, 0.55, 0.62);
    p.z = {uniform(obj_rng, 0.08, 0.12), uniform(obj_rng, 0.04, 0.12), uniform(obj_rng, 0, kTwoPi)};
    p.yaw = {uniform(obj_rng, 10, 30), uniform(obj_rng, 0.03, 0.1), uniform(obj_rng, 0, kTwoPi)};
    paths_.push_back(p);
  }

  std::mt19937_64 therapist_rng(sub_seed(seed, "therapist"));
  therapist_side_ = (therapist_rng() % 2) ? 1.0 : -1.0;
  make_fixations();
  make_blinks();
}

cv::Vec3d DemoScript::therapist_head_m() const {
  const cv::Vec3d& o = geometry_.therapist_head_m;
  return {therapist_side_ * std::abs(o[0]), o[1], o[2]};
}

namespace {
// Gaze direction for yaw/pitch (degrees), the inverse of look_at_angles.
cv::Vec3d gaze_from_angles(double yaw_deg, double pitch_deg) {
  const double y = yaw_deg * CV_PI / 180, p = pitch_deg * CV_PI / 180;
  return {-std::sin(y) * std::cos(p), std::sin(p), -std::cos(y) * std::cos(p)};
}
}  // namespace

// Fixation schedule: the session is cut into cycles of 3.4-5.4 s (rescaled to tile it exactly);
// each cycle holds one look at the robot taking 36-44 % of it (so the mutual-gaze fraction is
// ~40 % in every seed) and 1-3 looks elsewhere (a toy 40 %, the therapist 18 %, a point on the
// table 15 %, elsewhere in the room 27 %), in a seed-dependent order. Consecutive robot looks
// merge.
void DemoScript::make_fixations() {
  std::mt19937_64 rng(sub_seed(seed_, "gaze"));
  const DemoGeometry& g = geometry_;
  const int cycles = std::max(1, static_cast<int>(std::lround(duration_s_ / 4.4)));
  std::vector<double> lengths(static_cast<size_t>(cycles));
  double sum = 0;
  for (double& l : lengths) sum += (l = uniform(rng, 3.4, 5.4));
  for (double& l : lengths) l *= duration_s_ / sum;
  int last_object = -1;
  GazeTargetKind last_kind = GazeTargetKind::kRobot;
  std::vector<Fixation> seq;
  double t = 0;
  for (int c = 0; c < cycles; ++c) {
    const double len = lengths[static_cast<size_t>(c)];
    const double robot = uniform(rng, 0.36, 0.44) * len;
    const double other = len - robot;
    const int k = std::clamp(static_cast<int>(other / 1.1), 1, 3);
    std::vector<double> w(static_cast<size_t>(k));
    double wsum = 0;
    for (double& x : w) wsum += (x = uniform(rng, 0.75, 1.25));
    const bool robot_first = rng() % 2 == 0;
    std::vector<Fixation> cycle;
    for (int i = 0; i < k; ++i) {
      Fixation f;
      f.end_s = other * w[static_cast<size_t>(i)] / wsum;  // a duration for now
      const double u = uniform(rng, 0, 1);
      f.kind = u < 0.40   ? GazeTargetKind::kObject
               : u < 0.58 ? GazeTargetKind::kTherapist
               : u < 0.73 ? GazeTargetKind::kTable
                          : GazeTargetKind::kElsewhere;
      if (f.kind == last_kind && f.kind != GazeTargetKind::kObject)
        f.kind = GazeTargetKind::kObject;
      if (f.kind == GazeTargetKind::kObject) {
        f.object = static_cast<int>(rng() % objects_.size());
        if (f.object == last_object) f.object = (f.object + 1) % static_cast<int>(objects_.size());
        last_object = f.object;
      } else if (f.kind == GazeTargetKind::kTherapist) {
        f.point_m = therapist_head_m();
      } else if (f.kind == GazeTargetKind::kTable) {
        f.point_m = cv::Vec3d(uniform(rng, -0.35, 0.35), g.table_top_y_m, uniform(rng, 0.40, 0.62));
      } else {  // elsewhere in the room: 30-62 deg to a side, 18 deg up .. 8 deg down, 1.6 m
        const double side = rng() % 2 ? 1.0 : -1.0;
        f.point_m = g.head_rest_m +
                    1.6 * gaze_from_angles(side * uniform(rng, 30, 62), uniform(rng, -18, 8));
      }
      last_kind = f.kind;
      cycle.push_back(f);
    }
    Fixation r;
    r.kind = GazeTargetKind::kRobot;
    r.point_m = g.robot_head_m;
    r.end_s = robot;
    if (robot_first)
      cycle.insert(cycle.begin(), r);
    else
      cycle.push_back(r);
    for (Fixation& f : cycle) {
      const double d = f.end_s;
      f.start_s = t;
      f.end_s = t + d;
      t += d;
      if (!seq.empty() && seq.back().kind == GazeTargetKind::kRobot &&
          f.kind == GazeTargetKind::kRobot)
        seq.back().end_s = f.end_s;
      else
        seq.push_back(f);
    }
  }
  seq.back().end_s = std::max(seq.back().end_s, duration_s_);
  // Head shares and turn times from the target directions seen from the rest position.
  double prev_yaw = 0, prev_pitch = 0;
  for (size_t i = 0; i < seq.size(); ++i) {
    Fixation& f = seq[i];
    double yaw = 0, pitch = 0;
    look_at_angles(g.head_rest_m, fixation_point(f, f.start_s), yaw, pitch);
    // The head turns 45-70 % of the way (35-60 % vertically), and at least far enough that the
    // eyes stay ~8 deg (yaw) / ~4 deg (pitch) inside their range.
    f.head_yaw_share =
        std::min(1.0, std::max(uniform(rng, 0.45, 0.7), 1 - 17 / std::max(std::abs(yaw), 1e-3)));
    f.head_pitch_share =
        std::min(1.0, std::max(uniform(rng, 0.35, 0.6), 1 - 14 / std::max(std::abs(pitch), 1e-3)));
    const double hy = yaw * f.head_yaw_share, hp = pitch * f.head_pitch_share;
    const double turn = std::hypot(hy - prev_yaw, hp - prev_pitch);
    f.head_turn_s = std::clamp(0.25 + turn / 90, 0.35, 0.8);
    f.head_turn_s = std::max(0.05, std::min(f.head_turn_s, f.end_s - f.start_s - kHeadLagS - 0.02));
    prev_yaw = hy;
    prev_pitch = hp;
  }
  fixations_ = std::move(seq);
}

// Blinks every 2.5-5.5 s (first after 0.8-3 s): closing 80 ms, closed 60 ms, opening 160 ms.
void DemoScript::make_blinks() {
  std::mt19937_64 rng(sub_seed(seed_, "blinks"));
  for (double t = uniform(rng, 0.8, 3.0); t < duration_s_; t += uniform(rng, 2.5, 5.5))
    blinks_.push_back(t);
}

double DemoScript::eyelid_closure(double t) const {
  double c = 0;
  for (double b : blinks_) {
    const double dt = t - b;
    if (dt < 0 || dt >= 0.30) continue;
    if (dt < 0.08)
      c = std::max(c, smoothstep(dt / 0.08));
    else if (dt < 0.14)
      c = 1;
    else
      c = std::max(c, 1 - smoothstep((dt - 0.14) / 0.16));
  }
  return c;
}

const Fixation& DemoScript::fixation_at(double t) const {
  auto it = std::upper_bound(fixations_.begin(), fixations_.end(), t,
                             [](double x, const Fixation& f) { return x < f.start_s; });
  if (it == fixations_.begin()) return fixations_.front();
  return *(it - 1);
}

cv::Vec3d DemoScript::fixation_point(const Fixation& f, double t) const {
  if (f.kind == GazeTargetKind::kObject) {
    const auto states = object_states(t);
    return states[static_cast<size_t>(f.object)].position_m;
  }
  return f.point_m;
}

HeadPose DemoScript::head_pose(double t) const {
  HeadPose p;
  p.position_m =
      geometry_.head_rest_m + cv::Vec3d(eval(pos_x_, t), eval(pos_y_, t), eval(pos_z_, t));
  // The head turns part of the way towards the current target, blending from the previous one.
  const size_t i = static_cast<size_t>(&fixation_at(t) - fixations_.data());
  auto head_angles = [&](size_t k, double& yaw, double& pitch) {
    const Fixation& f = fixations_[k];
    look_at_angles(p.position_m, fixation_point(f, t), yaw, pitch);
    yaw *= f.head_yaw_share;
    pitch *= f.head_pitch_share;
  };
  double yaw = 0, pitch = 0;
  head_angles(i, yaw, pitch);
  if (i > 0) {
    const Fixation& f = fixations_[i];
    const double w = smoothstep((t - f.start_s - kHeadLagS) / f.head_turn_s);
    if (w < 1) {
      double y0 = 0, p0 = 0;
      head_angles(i - 1, y0, p0);
      yaw = y0 + w * (yaw - y0);
      pitch = p0 + w * (pitch - p0);
    }
  }
  p.yaw_deg = std::clamp(yaw + eval(yaw_, t), -55.0, 55.0);
  p.pitch_deg = std::clamp(pitch + eval(pitch_, t), -15.0, 15.0);
  p.roll_deg = std::clamp(eval(roll_, t), -10.0, 10.0);
  return p;
}

GazeState DemoScript::gaze(double t) const {
  GazeState s;
  const HeadPose hp = head_pose(t);
  const cv::Matx33d R = hp.rotation();
  const Fixation& f = fixation_at(t);
  // Eye-in-head rotation towards `point` (with fixational jitter), clamped to the eye's range.
  auto aim = [&](const cv::Vec3d& point, GazeState& g) {
    g.intended_m = point;
    const double dist = cv::norm(point - hp.position_m);
    const cv::Vec3d jittered =
        point + dist * cv::Vec3d(0.004 * std::sin(kTwoPi * 0.83 * t),
                                 0.003 * std::sin(kTwoPi * 1.27 * t + 1.0), 0);
    const cv::Vec3d d = R.t() * normalized(jittered - hp.position_m);
    const double yaw = std::atan2(-d[0], -d[2]) * 180 / CV_PI;
    const double pitch = std::asin(std::clamp(d[1], -1.0, 1.0)) * 180 / CV_PI;
    g.eye_yaw_deg = std::clamp(yaw, -kMaxEyeYawDeg, kMaxEyeYawDeg);
    g.eye_pitch_deg = std::clamp(pitch, -kMaxEyePitchDeg, kMaxEyePitchDeg);
    g.target_m = hp.position_m + dist * (R * gaze_from_angles(g.eye_yaw_deg, g.eye_pitch_deg));
    return g.eye_yaw_deg != yaw || g.eye_pitch_deg != pitch;
  };
  s.kind = f.kind;
  s.object = f.object;
  const bool clamped = aim(fixation_point(f, t), s);
  // A target out of the eyes' reach while the head is still turning: the eyes wait for the head
  // on the previous target rather than pass near the robot (which would be a spurious, brief
  // mutual gaze).
  const size_t i = static_cast<size_t>(&f - fixations_.data());
  if (clamped && i > 0 && f.kind != GazeTargetKind::kRobot &&
      ray_point_distance(hp.position_m, s.target_m - hp.position_m, geometry_.robot_head_m) <
          geometry_.gaze_radius_m + 0.08) {
    const Fixation& prev = fixations_[i - 1];
    s.kind = prev.kind;
    s.object = prev.object;
    aim(fixation_point(prev, t), s);
  }
  s.eyelid_closure = eyelid_closure(t);
  return s;
}

DemoAction DemoScript::action_at(double t) const {
  for (const auto& s : actions_)
    if (t >= s.start_s && t < s.end_s) return s.action;
  return actions_.empty() ? DemoAction::kNone : actions_.back().action;
}

const ActionSegment& DemoScript::segment_at(double t) const {
  static const ActionSegment kRest{};
  for (const auto& s : actions_)
    if (t >= s.start_s && t < s.end_s) return s;
  return actions_.empty() ? kRest : actions_.back();
}

std::string DemoScript::segment_label(const ActionSegment& s) const {
  if (s.action == DemoAction::kCustom && s.custom >= 0 &&
      s.custom < static_cast<int>(options_.custom.size()))
    return options_.custom[static_cast<size_t>(s.custom)].label;
  return std::string(action_label(s.action));
}

int DemoScript::segment_dream_id(const ActionSegment& s) const {
  if (s.action == DemoAction::kCustom) return 7 + std::max(s.custom, 0);
  return action_dream_id(s.action);
}

namespace {
// Closed Catmull-Rom loop through `p`, u in [0, 1).
cv::Vec3d loop_point(const std::vector<cv::Vec3d>& p, double u) {
  const int n = static_cast<int>(p.size());
  if (n == 1) return p[0];
  const double x = (u - std::floor(u)) * n;
  const int i = static_cast<int>(std::floor(x));
  const double a = x - i;
  auto at = [&](int k) { return p[static_cast<size_t>(((k % n) + n) % n)]; };
  const cv::Vec3d p0 = at(i - 1), p1 = at(i), p2 = at(i + 1), p3 = at(i + 2);
  return 0.5 * (2 * p1 + (p2 - p0) * a + (2 * p0 - 5 * p1 + 4 * p2 - p3) * a * a +
                (3 * p1 - p0 - 3 * p2 + p3) * a * a * a);
}
}  // namespace

// Elbow, wrist, hand for the left arm then the right arm, for the gestures the original demo
// did not have. Head-relative targets follow the head (its rotation and position).
std::array<cv::Vec3d, 6> DemoScript::extra_arm_pose(const ActionSegment& segment, double t,
                                                    const cv::Vec3d& shoulder_l,
                                                    const cv::Vec3d& shoulder_r) const {
  const double ty = geometry_.table_top_y_m;
  const HeadPose hp = head_pose(t);
  const cv::Matx33d R = hp.rotation();
  // [left, right]: elbow, wrist, hand.
  std::array<cv::Vec3d, 6> out{};
  auto place = [&](bool left, const cv::Vec3d& wrist, const cv::Vec3d& pole,
                   const cv::Vec3d* hand) {
    const auto ew = solve_arm(left ? shoulder_l : shoulder_r, wrist, pole);
    const size_t b = left ? 0 : 3;
    out[b] = ew.first;
    out[b + 1] = ew.second;
    out[b + 2] = hand ? *hand : ew.second + kHand * normalized(ew.second - ew.first);
  };
  auto rest = [&](bool left) {
    const double side = left ? 1.0 : -1.0;
    const double phase = left ? 0.0 : 1.3;
    const cv::Vec3d& s = left ? shoulder_l : shoulder_r;
    const cv::Vec3d hand(s[0] + side * 0.03 + 0.004 * std::sin(kTwoPi * 0.4 * t + phase),
                         ty - 0.025, 0.86 + 0.005 * std::sin(kTwoPi * 0.3 * t + phase));
    place(left, hand + cv::Vec3d(0, 0, kHand), cv::Vec3d(side, 1.0, 0.3), &hand);
  };
  switch (segment.action) {
    case DemoAction::kCoverEyes:
      // Both palms over the eyes (fingers up), the wrists below them; a small peek-a-boo shift.
      for (bool left : {true, false}) {
        const double side = left ? 1.0 : -1.0;
        const double peek = 0.01 * std::sin(kTwoPi * cover_hz_ * t);
        const cv::Vec3d hand = hp.position_m + R * cv::Vec3d(side * (0.035 + peek), 0.01, -0.05);
        const cv::Vec3d wrist = hand + R * cv::Vec3d(side * 0.02, kHand, 0.01);
        place(left, wrist, cv::Vec3d(side, 1.0, 0.3), &hand);
      }
      break;
    case DemoAction::kDriveCar: {
      // Both hands on a steering wheel in front of the chest, turning it to and fro.
      const cv::Vec3d sc = 0.5 * (shoulder_l + shoulder_r);
      const cv::Vec3d centre = sc + cv::Vec3d(0, 0.04, -0.28);
      const cv::Vec3d u(1, 0, 0), v = normalized(cv::Vec3d(0, -1, -0.3));
      const double turn = drive_amp_rad_ * std::sin(kTwoPi * drive_hz_ * t);
      for (bool left : {true, false}) {
        const double a = turn + (left ? 0.0 : CV_PI) + (left ? 0.35 : -0.35);
        const cv::Vec3d hand = centre + 0.14 * (std::cos(a) * u + std::sin(a) * v);
        const cv::Vec3d wrist = hand + cv::Vec3d(0, 0.02, kHand);
        place(left, wrist, cv::Vec3d(left ? 1.0 : -1.0, 1.0, 0.3), &hand);
      }
      break;
    }
    case DemoAction::kDrink: {
      // The right hand holds a cup at the mouth, tilting it a little; the left hand rests.
      rest(true);
      const double sip = 0.012 * std::sin(kTwoPi * drink_hz_ * t);
      const cv::Vec3d hand = hp.position_m + R * cv::Vec3d(-0.01, 0.075 + sip, -0.08);
      const cv::Vec3d wrist = hand + R * cv::Vec3d(-0.02, 0.05, 0.04);
      place(false, wrist, cv::Vec3d(-1, 1, 0.2), &hand);
      break;
    }
    case DemoAction::kCustom: {
      if (segment.custom < 0 || segment.custom >= static_cast<int>(options_.custom.size())) {
        rest(true);
        rest(false);
        break;
      }
      const CustomGesture& g = options_.custom[static_cast<size_t>(segment.custom)];
      const double u = (t - segment.start_s) / g.period_s;
      for (bool left : {true, false}) {
        const auto& path = left ? g.left_wrist : g.right_wrist;
        if (path.empty()) {
          rest(left);
          continue;
        }
        const cv::Vec3d wrist = (left ? shoulder_l : shoulder_r) + loop_point(path, u);
        place(left, wrist, cv::Vec3d(left ? 1.0 : -1.0, 1.0, 0.2), nullptr);
      }
      break;
    }
    default:
      rest(true);
      rest(false);
      break;
  }
  return out;
}

// Returns elbow, wrist, hand for the left arm then the right arm.
std::array<cv::Vec3d, 6> DemoScript::arm_pose(const ActionSegment& segment, double t,
                                              const cv::Vec3d& head_centre,
                                              const cv::Vec3d& shoulder_l,
                                              const cv::Vec3d& shoulder_r) const {
  const DemoAction action = segment.action;
  if (action == DemoAction::kCoverEyes || action == DemoAction::kDriveCar ||
      action == DemoAction::kDrink || action == DemoAction::kCustom)
    return extra_arm_pose(segment, t, shoulder_l, shoulder_r);
  const double ty = geometry_.table_top_y_m;
  auto rest = [&](const cv::Vec3d& s, double side, double phase) {
    // Hands lying on the table in front of the body, with a few mm of fidgeting.
    const cv::Vec3d hand(s[0] + side * 0.03 + 0.004 * std::sin(kTwoPi * 0.4 * t + phase),
                         ty - 0.025, 0.86 + 0.005 * std::sin(kTwoPi * 0.3 * t + phase));
    const cv::Vec3d wrist = hand + cv::Vec3d(0, 0, kHand);
    return solve_arm(s, wrist, cv::Vec3d(side, 1.0, 0.3));
  };
  std::pair<cv::Vec3d, cv::Vec3d> left, right;
  switch (action) {
    case DemoAction::kNone:
      left = rest(shoulder_l, 1, 0.0);
      right = rest(shoulder_r, -1, 1.3);
      break;
    case DemoAction::kWave: {
      left = rest(shoulder_l, 1, 0.0);
      // Right hand (the child's right = world -x) raised above the shoulder, waving sideways.
      const double swing = 0.08 * std::sin(kTwoPi * wave_hz_ * t);
      const cv::Vec3d wrist = shoulder_r + cv::Vec3d(-0.17 + swing, -0.27, -0.07);
      right = solve_arm(shoulder_r, wrist, cv::Vec3d(-1, 1, 0.2));
      break;
    }
    case DemoAction::kFly: {
      const double theta = 0.35 * std::sin(kTwoPi * fly_hz_ * t);  // rad, up/down flapping
      for (double side : {1.0, -1.0}) {
        const cv::Vec3d& s = side > 0 ? shoulder_l : shoulder_r;
        const cv::Vec3d wrist =
            s + 0.385 * cv::Vec3d(side * std::cos(theta), -std::sin(theta), -0.05);
        (side > 0 ? left : right) = solve_arm(s, wrist, cv::Vec3d(0, 1, 0.2));
      }
      break;
    }
    case DemoAction::kHandsOnHead:
      for (double side : {1.0, -1.0}) {
        const cv::Vec3d& s = side > 0 ? shoulder_l : shoulder_r;
        const cv::Vec3d wrist = head_centre + cv::Vec3d(side * 0.12, -0.02, 0.01) +
                                cv::Vec3d(0, 0.005 * std::sin(kTwoPi * 0.5 * t), 0);
        (side > 0 ? left : right) = solve_arm(s, wrist, cv::Vec3d(side, 0.3, 0.4));
      }
      break;
    default:  // the other gestures returned above
      break;
  }
  auto hand_of = [&](const std::pair<cv::Vec3d, cv::Vec3d>& ew, bool on_head, double side) {
    if (on_head) return ew.second + kHand * normalized(cv::Vec3d(-side * 0.6, -0.8, 0));
    if (action == DemoAction::kNone || (action == DemoAction::kWave && side > 0))
      return ew.second - cv::Vec3d(0, 0, kHand);
    return ew.second + kHand * normalized(ew.second - ew.first);
  };
  const bool on_head = action == DemoAction::kHandsOnHead;
  return {left.first,  left.second,  hand_of(left, on_head, 1.0),
          right.first, right.second, hand_of(right, on_head, -1.0)};
}

std::array<cv::Vec3d, kJointCount> DemoScript::joints(double t) const {
  const HeadPose hp = head_pose(t);
  const cv::Matx33d R = hp.rotation();
  std::array<cv::Vec3d, kJointCount> j{};
  auto at = [&](JointId id) -> cv::Vec3d& { return j[static_cast<size_t>(id)]; };
  const cv::Vec3d head_centre = hp.position_m + R * cv::Vec3d(0, 0.0, 0.08);
  const cv::Vec3d body =
      hp.position_m + cv::Vec3d(0, 0, 0);  // torso follows the head's translation
  const cv::Vec3d sc = body + cv::Vec3d(0, 0.19, 0.09);
  at(JointId::kHead) = head_centre;
  at(JointId::kShoulderCenter) = sc;
  at(JointId::kShoulderLeft) = sc + cv::Vec3d(0.14, 0.03, 0);
  at(JointId::kShoulderRight) = sc + cv::Vec3d(-0.14, 0.03, 0);
  at(JointId::kSpine) = sc + cv::Vec3d(0, 0.20, 0.01);
  at(JointId::kHipCenter) = sc + cv::Vec3d(0, 0.30, 0.02);
  for (double side : {1.0, -1.0}) {
    const cv::Vec3d hip = at(JointId::kHipCenter) + cv::Vec3d(side * 0.09, 0.03, 0);
    const cv::Vec3d knee = hip + cv::Vec3d(side * 0.02, 0.02, -0.32);
    const cv::Vec3d ankle = knee + cv::Vec3d(0, 0.30, 0.02);
    const cv::Vec3d foot = ankle + cv::Vec3d(0, 0.04, -0.08);
    at(side > 0 ? JointId::kHipLeft : JointId::kHipRight) = hip;
    at(side > 0 ? JointId::kKneeLeft : JointId::kKneeRight) = knee;
    at(side > 0 ? JointId::kAnkleLeft : JointId::kAnkleRight) = ankle;
    at(side > 0 ? JointId::kFootLeft : JointId::kFootRight) = foot;
  }
  const cv::Vec3d sl = at(JointId::kShoulderLeft), sr = at(JointId::kShoulderRight);
  // Blend from the previous segment's pose during the first kTransitionS of a segment.
  std::array<cv::Vec3d, 6> arms = arm_pose(segment_at(t), t, head_centre, sl, sr);
  for (size_t i = 1; i < actions_.size(); ++i) {
    const ActionSegment& s = actions_[i];
    if (t >= s.start_s && t < s.start_s + kTransitionS) {
      const double w = smoothstep((t - s.start_s) / kTransitionS);
      const auto prev = arm_pose(actions_[i - 1], t, head_centre, sl, sr);
      for (size_t k = 0; k < arms.size(); ++k) arms[k] = (1 - w) * prev[k] + w * arms[k];
      break;
    }
  }
  at(JointId::kElbowLeft) = arms[0];
  at(JointId::kWristLeft) = arms[1];
  at(JointId::kHandLeft) = arms[2];
  at(JointId::kElbowRight) = arms[3];
  at(JointId::kWristRight) = arms[4];
  at(JointId::kHandRight) = arms[5];
  return j;
}

std::vector<TableObjectState> DemoScript::object_states(double t) const {
  std::vector<TableObjectState> out;
  for (size_t i = 0; i < objects_.size(); ++i) {
    const TableObjectSpec& s = objects_[i];
    const ObjectPath& p = paths_[i];
    TableObjectState st;
    st.id = s.id;
    st.yaw_deg = eval({p.yaw}, t);
    const double top = geometry_.table_top_y_m - s.height_m;
    st.position_m = cv::Vec3d(p.x_centre + eval({p.x}, t), top, p.z_centre + eval({p.z}, t));
    const double a = st.yaw_deg * CV_PI / 180;
    const cv::Vec3d u(std::cos(a), 0, -std::sin(a)), v(std::sin(a), 0, std::cos(a));
    const cv::Vec3d hu = 0.5 * s.width_m * u, hv = 0.5 * s.depth_m * v;
    const cv::Vec3d down(0, s.height_m, 0);
    st.corners = {st.position_m - hu - hv,        st.position_m + hu - hv,
                  st.position_m + hu + hv,        st.position_m - hu + hv,
                  st.position_m - hu - hv + down, st.position_m + hu - hv + down,
                  st.position_m + hu + hv + down, st.position_m - hu + hv + down};
    out.push_back(st);
  }
  return out;
}

}  // namespace dreamsense::sim
