#pragma once
// Body analyser: turns the skeleton stream into the tracked child's body in world
// (keys::kChildBody). Method and numbers: modalities/body/README.md.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"

#include <memory>
#include <optional>

namespace dreamsense::body {

struct ChildSelectionOptions {
  // Without a previous choice, the child is the body nearest to this point (world, metres):
  // by default 1.1 m in front of the front sensor, where DREAM seats the child.
  cv::Vec3d expected_position_m{0.0, 0.0, 1.1};
  // A body further than this from the previous child's position is a different person.
  double max_jump_m = 0.5;
  Status check() const;
};

// Picks the child among the bodies in view: the body nearest to the previous choice (if within
// max_jump_m), else the one nearest to expected_position_m. Uses the shoulder centre (or head).
// Returns the index in `bodies`, or nullopt if none has a usable joint.
std::optional<size_t> select_child(const std::vector<SkeletonBody>& bodies,
                                   const std::optional<cv::Vec3d>& previous,
                                   const ChildSelectionOptions& options);

struct BodyAnalyzerOptions {
  SensorId skeleton_sensor = "front.skeleton";
  // world_from_sensor transform of the skeleton stream; identity when the skeleton sensor is
  // the world frame (the default world is the front sensor's optical frame).
  cv::Matx33d world_from_sensor_R = cv::Matx33d::eye();
  cv::Vec3d world_from_sensor_t{0, 0, 0};
  ChildSelectionOptions selection;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_body_analyzer(const BodyAnalyzerOptions& options);

}  // namespace dreamsense::body
