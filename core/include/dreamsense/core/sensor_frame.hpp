#pragma once
// Immutable sensor frames, shared between stages without copies (FramePtr).
// A frame is created once by a Source and never modified afterwards: the cv::Mat inside must not
// be written through by anyone (its buffer is shared by every consumer).

#include "dreamsense/core/timestamp.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace dreamsense {

using SensorId = std::string;  // e.g. "camera_left", "front.color", "front.depth", "mic_array"

enum class SensorKind { kColor, kDepth, kSkeleton, kAudio };
const char* to_string(SensorKind kind);
std::optional<SensorKind> sensor_kind_from_string(std::string_view s);

// Colour image: 8-bit BGR (CV_8UC3) or grey (CV_8UC1).
struct ColorImage {
  cv::Mat image;
};

// Depth image: CV_16UC1 in millimetres, 0 = no measurement.
struct DepthImage {
  cv::Mat depth_mm;
  bool registered_to_color =
      false;  // pixel (u,v) corresponds to the same pixel of the colour image
};

// Kinect v1 joint set; the first ten are the DREAM joints in the legacy getBodyPose order.
enum class JointId : int {
  kShoulderCenter = 0,
  kHead,
  kShoulderLeft,
  kElbowLeft,
  kWristLeft,
  kHandLeft,
  kShoulderRight,
  kElbowRight,
  kWristRight,
  kHandRight,
  kSpine,
  kHipCenter,
  kHipLeft,
  kKneeLeft,
  kAnkleLeft,
  kFootLeft,
  kHipRight,
  kKneeRight,
  kAnkleRight,
  kFootRight,
};
inline constexpr int kJointCount = 20;
inline constexpr int kDreamJointCount = 10;
// snake_case names ("shoulder_center", "hand_left", ...).
std::string_view joint_name(JointId id);
std::optional<JointId> joint_from_name(std::string_view name);

struct JointObservation {
  cv::Vec3d position_m{0, 0, 0};  // in the skeleton sensor's frame (metres)
  float confidence = 0.f;         // 0 = not tracked, 0.5 = inferred, 1 = tracked (Kinect states)
  bool valid() const { return confidence > 0.f; }
};

struct SkeletonBody {
  int body_id = 0;
  std::array<JointObservation, kJointCount> joints{};
  const JointObservation& joint(JointId id) const { return joints[static_cast<int>(id)]; }
  JointObservation& joint(JointId id) { return joints[static_cast<int>(id)]; }
};

// All bodies a skeleton tracker reported in one frame (possibly none).
struct Skeleton {
  std::vector<SkeletonBody> bodies;
};

// Interleaved float samples in [-1, 1]; the frame stamp is the time of the first sample.
struct AudioChunk {
  int sample_rate = 16000;
  int channels = 1;
  std::vector<float> samples;  // frames() * channels values
  int64_t frames() const {
    return channels > 0 ? static_cast<int64_t>(samples.size()) / channels : 0;
  }
  Duration duration() const {
    return Duration::from_ns(frames() * 1000000000LL / (sample_rate > 0 ? sample_rate : 1));
  }
};

using FramePayload = std::variant<ColorImage, DepthImage, Skeleton, AudioChunk>;

struct SensorFrame {
  SensorId sensor;
  Timestamp stamp;
  uint64_t sequence = 0;  // per-sensor frame index, starting at 0
  FramePayload payload;

  SensorKind kind() const;
  template <typename T>
  const T* as() const {
    return std::get_if<T>(&payload);
  }
};

using FramePtr = std::shared_ptr<const SensorFrame>;

template <typename Payload>
FramePtr make_frame(SensorId sensor, Timestamp stamp, uint64_t sequence, Payload payload) {
  return std::make_shared<const SensorFrame>(
      SensorFrame{std::move(sensor), stamp, sequence, FramePayload(std::move(payload))});
}

}  // namespace dreamsense
