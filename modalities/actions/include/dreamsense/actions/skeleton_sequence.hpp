#pragma once
// A body's skeleton over time, independent of any dataset or sensor: one frame = a stamp (int64
// nanoseconds from the sensor or recording) and the 20 Kinect v1 joints in core's JointId order
// (dreamsense/core/sensor_frame.hpp). Coordinates are metres in the sensor's frame; the project's
// convention is the optical frame (x right, y down, z forward, right-handed). Dataset readers
// convert their layouts into this (eval/actions).

#include "dreamsense/core/sensor_frame.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace dreamsense::actions {

struct SkeletonFrame {
  int64_t stamp_ns = 0;
  // confidence 0 = missing, 0.5 = inferred, 1 = tracked (Kinect states); a non-finite position is
  // treated as missing whatever its confidence.
  std::array<JointObservation, kJointCount> joints{};
  const JointObservation& joint(JointId id) const { return joints[static_cast<size_t>(id)]; }
  JointObservation& joint(JointId id) { return joints[static_cast<size_t>(id)]; }
};

// Stamps strictly increasing (readers and the online classifier enforce it).
using SkeletonSequence = std::vector<SkeletonFrame>;

// A joint is usable when its confidence is > 0 and its position is finite.
bool joint_usable(const JointObservation& j);

// A labelled stretch of skeleton frames (a dataset segment, or a demonstration of a gesture).
struct LabelledSequence {
  std::string label;
  std::string subject;  // who performed it (subject-disjoint protocols); may be empty
  std::string source;   // where it came from, for messages ("joints_s01_e01.txt frames 252-390")
  SkeletonSequence frames;
};

// Converts a SkeletonBody (one body of a Skeleton sensor frame) into a SkeletonFrame.
SkeletonFrame to_skeleton_frame(const SkeletonBody& body, int64_t stamp_ns);

}  // namespace dreamsense::actions
