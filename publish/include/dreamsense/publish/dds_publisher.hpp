#pragma once
// Publishing the perception primitives over DDS (eProsima Fast DDS, Debian libfastrtps), with
// ROS 2 naming so ROS 2 nodes subscribe without a bridge:
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

#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace dreamsense::publish {

struct DdsPublisherOptions {
  int domain_id = 0;                        // ROS_DOMAIN_ID
  std::string topic_prefix = "dreamsense";  // topics rt/<prefix>/<primitiveName>
  bool network = false;                     // false: this machine only (127.0.0.1 + shared memory)
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
