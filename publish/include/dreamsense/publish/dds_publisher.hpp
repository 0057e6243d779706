#pragma once
// Publishing the perception primitives over DDS (eProsima Fast DDS, Debian libfastrtps), with
// ROS 2 naming so ROS 2 nodes subscribe without a bridge.
// Typed (ros_topics, default): ROS4HRI (REP-155) topics rt/humans/faces/tracked,
// rt/humans/faces/<id>/{roi,expression,gaze}, rt/humans/voices/tracked,
// rt/humans/voices/<id>/speech and rt/<prefix>/mutual_gaze, with hri_msgs / dreamsense_msgs types
// generated from publish/idl by fastddsgen, std_msgs/Header stamps = analysis stamps
// (publish/README.md has the table). JSON (json_topics):
//   topic  rt/<prefix>/<primitiveName>      e.g. rt/dreamsense/getFaces (dds_topic_name)
//   type   std_msgs::msg::dds_::String_     (ROS 2 std_msgs/msg/String)
//   data   the record exactly as one line of primitives.jsonl (docs/primitives.md)
// so `ros2 topic echo /dreamsense/getFaces std_msgs/msg/String` shows it. One message per
// primitive per tick, reliable, keep-last 10 (a late subscriber gets the last few).
//
// Privacy (spec/system.md): nothing is published unless asked for (`live --publish dds`), and by
// default only on this machine (shared memory and UDP on 127.0.0.1); `network = true` is the
// explicit opt-in to every interface. A build without Fast DDS returns kUnsupported from create().

#include "dreamsense/core/status.hpp"
#include "dreamsense/primitives/catalogue.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace dreamsense::publish {

struct DdsPublisherOptions {
  int domain_id = 0;                        // ROS_DOMAIN_ID
  std::string topic_prefix = "dreamsense";  // topics rt/<prefix>/<primitiveName>
  bool network = false;                     // false: this machine only (127.0.0.1 + shared memory)
  // Typed ROS 2 messages (ROS4HRI / REP-155 topics and dreamsense_msgs; publish/README.md). Needs
  // a build with fastddsgen; create() is an error when asked for without it.
  bool ros_topics = true;
  // The JSON-string topics rt/<prefix>/<primitiveName> (std_msgs/String, one primitives.jsonl
  // line each).
  bool json_topics = false;
  // Image sizes of the cameras, to normalise face boxes for /humans/faces/<id>/roi (a camera
  // without a size gets no roi message).
  std::map<std::string, cv::Size> image_sizes;
  // Also publish records whose status is not ok (disabled, no_data, ...): a subscriber then sees
  // every tick. Default: ok records only.
  bool all_statuses = false;
  std::set<std::string> only;  // primitive names to publish; empty = all 25
  Status check() const;
};

// The ROS 2 topic of a primitive: rt/<prefix>/<token>, the token being the primitive's name with
// every run of other characters than [A-Za-z0-9] turned into one '_' ("getHeadGaze (plane)" ->
// "getHeadGaze_plane").
std::string dds_topic_token(const std::string& primitive);
std::string dds_topic_name(const DdsPublisherOptions& options, const std::string& primitive);
inline constexpr const char* kDdsStringTypeName = "std_msgs::msg::dds_::String_";

// ROS 2 / ROS4HRI mapping, exposed for tests.
struct RosTime {
  int32_t sec = 0;
  uint32_t nanosec = 0;
};
RosTime ros_time(Timestamp t);  // builtin_interfaces/Time of a stamp (ns -> sec + nanosec)
// The hri_msgs/Expression constant for an expression label ("sadness" -> "sad", "fear" ->
// "scared", ...); a label without an equivalent is passed on unchanged.
std::string hri_expression(const std::string& label);
// A pixel box as (xmin, ymin, xmax, ymax) normalised by the image size and clipped to [0, 1];
// nullopt for an empty image size or a box outside the image.
std::optional<std::array<float, 4>> normalized_roi(const cv::Rect2d& box, cv::Size image);
// Whether this build can publish the typed messages.
bool have_ros_messages();
inline constexpr const char* kRosTrackedFacesTopic = "rt/humans/faces/tracked";
inline constexpr const char* kRosTrackedVoicesTopic = "rt/humans/voices/tracked";

struct DdsPublisherStats {
  uint64_t published = 0;
  uint64_t failed = 0;  // write() refused by DDS
};

class DdsPublisher {
 public:
  static Result<std::unique_ptr<DdsPublisher>> create(const DdsPublisherOptions& options);
  ~DdsPublisher();
  DdsPublisher(const DdsPublisher&) = delete;
  DdsPublisher& operator=(const DdsPublisher&) = delete;
  // Publishes the records of one tick (those the options select).
  Status publish(const std::vector<primitives::PrimitiveRecord>& records);
  DdsPublisherStats stats() const;

 private:
  struct Impl;
  explicit DdsPublisher(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A subscriber for tests and tools: collects the JSON strings received on one primitive's topic.
class DdsStringSubscriber {
 public:
  static Result<std::unique_ptr<DdsStringSubscriber>> create(const DdsPublisherOptions& options,
                                                             const std::string& primitive);
  ~DdsStringSubscriber();
  // Waits up to timeout_ms for at least `count` messages in total; returns all received so far.
  std::vector<std::string> wait_for(size_t count, int timeout_ms);

 private:
  struct Impl;
  explicit DdsStringSubscriber(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::publish
