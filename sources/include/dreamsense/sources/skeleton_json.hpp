#pragma once
// One skeleton frame as JSON: a line of a session's skeleton stream (<id>.jsonl,
// docs/session_format.md) and a datagram of the live UDP skeleton input (docs/recording.md):
//   {"stamp_ns": 40000000, "sequence": 1,
//    "bodies": [{"id": 3, "joints": {"head": [x, y, z, confidence], ...}}]}
// Joints in metres in the sensor's frame, Kinect v1 names (core/sensor_frame.hpp joint_name),
// confidence in [0, 1] (optional, default 1); a position further than 100 m on an axis is damage.

#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <optional>
#include <string_view>

namespace dreamsense::sources {

inline constexpr double kMaxSkeletonJointDistanceM = 100.0;

struct SkeletonJson {
  std::optional<int64_t> stamp_ns;
  std::optional<uint64_t> sequence;
  Skeleton skeleton;
};

// Parses one frame; a kCorruptData error says what is wrong (without a file name: the caller
// adds where it came from).
Result<SkeletonJson> parse_skeleton_json(std::string_view text);

}  // namespace dreamsense::sources
