#include "dreamsense/primitives/context.hpp"

#include <algorithm>

namespace dreamsense::primitives {

Status EvaluatorOptions::check() const {
  std::string bad;
  if (freshness.ns() <= 0) bad += " freshness must be > 0;";
  if (offline_after <= freshness) bad += " offline_after must exceed freshness;";
  if (!(track_hand_dt_s >= 0)) bad += " track_hand_dt_s must be >= 0;";
  if (!(sound_direction_threshold >= 0 && sound_direction_threshold <= 1))
    bad += " sound_direction_threshold must be in [0, 1];";
  if (!(track_face_dt_s >= 0)) bad += " track_face_dt_s must be >= 0;";
  if (!(track_object_dt_s >= 0)) bad += " track_object_dt_s must be >= 0;";
  if (!(objects_circle_radius_m > 0)) bad += " objects_circle_radius_m must be > 0;";
  if (!(object_query_radius_m > 0)) bad += " object_query_radius_m must be > 0;";
  const cv::Vec3d n =
      (head_gaze_plane[1] - head_gaze_plane[0]).cross(head_gaze_plane[2] - head_gaze_plane[0]);
  if (!(cv::norm(n) > 1e-9)) bad += " the three head_gaze_plane points are collinear;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "EvaluatorOptions:" + bad);
  return face_geometry.check();
}

const std::vector<SensorId>& PrimitiveContext::sensors_of(std::string_view key) const {
  static const std::vector<SensorId> kNone;
  auto it = key_sensors_.find(key);
  return it == key_sensors_.end() ? kNone : it->second;
}

PrimitiveStatus PrimitiveContext::status_of(std::optional<Timestamp> entry_stamp, bool present,
                                            std::string_view key) const {
  Timestamp last = first_tick_;
  for (const auto& s : sensors_of(key)) {
    auto seen = last_seen_.find(s);
    if (seen != last_seen_.end()) last = std::max(last, seen->second);
  }
  if (tick_ - last > options_.offline_after) return PrimitiveStatus::kSensorOffline;
  if (!entry_stamp) return PrimitiveStatus::kNoData;
  if (tick_ - *entry_stamp > options_.freshness) return PrimitiveStatus::kStale;
  if (!present) return PrimitiveStatus::kNoData;
  return PrimitiveStatus::kOk;
}

}  // namespace dreamsense::primitives
