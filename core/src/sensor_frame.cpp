#include "dreamsense/core/sensor_frame.hpp"

#include "dreamsense/core/multi_frame.hpp"

namespace dreamsense {
namespace {
constexpr std::array<std::string_view, kJointCount> kJointNames = {
    "shoulder_center", "head",           "shoulder_left", "elbow_left",  "wrist_left",
    "hand_left",       "shoulder_right", "elbow_right",   "wrist_right", "hand_right",
    "spine",           "hip_center",     "hip_left",      "knee_left",   "ankle_left",
    "foot_left",       "hip_right",      "knee_right",    "ankle_right", "foot_right"};
}  // namespace

const char* to_string(SensorKind kind) {
  switch (kind) {
    case SensorKind::kColor:
      return "color";
    case SensorKind::kDepth:
      return "depth";
    case SensorKind::kSkeleton:
      return "skeleton";
    case SensorKind::kAudio:
      return "audio";
  }
  return "unknown";
}

std::optional<SensorKind> sensor_kind_from_string(std::string_view s) {
  for (SensorKind k :
       {SensorKind::kColor, SensorKind::kDepth, SensorKind::kSkeleton, SensorKind::kAudio})
    if (s == to_string(k)) return k;
  return std::nullopt;
}

std::string_view joint_name(JointId id) { return kJointNames[static_cast<int>(id)]; }

std::optional<JointId> joint_from_name(std::string_view name) {
  for (int i = 0; i < kJointCount; ++i)
    if (kJointNames[i] == name) return static_cast<JointId>(i);
  return std::nullopt;
}

SensorKind SensorFrame::kind() const {
  struct Visitor {
    SensorKind operator()(const ColorImage&) const { return SensorKind::kColor; }
    SensorKind operator()(const DepthImage&) const { return SensorKind::kDepth; }
    SensorKind operator()(const Skeleton&) const { return SensorKind::kSkeleton; }
    SensorKind operator()(const AudioChunk&) const { return SensorKind::kAudio; }
  };
  return std::visit(Visitor{}, payload);
}

const std::vector<FramePtr>& MultiFrame::chunks_of(const SensorId& id) const {
  static const std::vector<FramePtr> kEmpty;
  auto it = chunks.find(id);
  return it == chunks.end() ? kEmpty : it->second;
}

}  // namespace dreamsense
