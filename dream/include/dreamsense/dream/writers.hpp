#pragma once
// DREAM's file formats: the event log of its sensoryInterpretationLogger and its dataset export
// (dream.json, schema dream.1.1 in ../shared/data/dream_dataset_format).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/output_file.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/primitives/catalogue.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <vector>

namespace dreamsense::dream {

// events.log in the spirit of DREAM's sensoryInterpretationLogger (event-based format): one line
// per published message, "<port>;<local time YYYY-MM-DD hh:mm:ss.mmm>;<values ;-separated>".
// Published = status ok, with the legacy vector. A primitive whose status changes to something
// else gets one line "<port>;<time>;<status>" (the original published nothing then).
// The time is the recording's clock (clock_origin_unix_ns + stamp), never the analysis time.
class EventLogWriter {
 public:
  Status open(const std::filesystem::path& path, int64_t clock_origin_unix_ns);
  Status write(const std::vector<primitives::PrimitiveRecord>& records);
  Status commit() { return file_.commit(); }

 private:
  OutputFile file_;
  int64_t origin_ns_ = 0;
  std::map<int, primitives::PrimitiveStatus> last_status_;
};

// Formats a wall-clock time as DREAM's logger did: "YYYY-MM-DD hh:mm:ss.mmm" (local time).
std::string format_local_time(int64_t unix_ns);

// dream.json: the DREAM dataset export (schema dream.1.1), frame-aligned at the tick rate.
// Skeleton positions are millimetres in the session's world frame, as DREAM's Kinect pipeline
// wrote them; missing values are null.
class DreamExport {
 public:
  struct Frame {
    std::optional<SkeletonBody> skeleton;          // world, metres
    std::optional<cv::Vec3d> head_gaze, eye_gaze;  // unit vectors in world
  };
  void add(const Frame& frame) { frames_.push_back(frame); }
  // The frame of one tick from the blackboard: the child's skeleton, head gaze and eye gaze
  // observed within `freshness` of the tick.
  void add(const BlackboardView& view, Timestamp tick, Duration freshness);
  size_t size() const { return frames_.size(); }
  nlohmann::json build(const sources::SessionManifest& manifest) const;
  Status write(const std::filesystem::path& path, const sources::SessionManifest& manifest) const;

 private:
  std::vector<Frame> frames_;
};

}  // namespace dreamsense::dream
