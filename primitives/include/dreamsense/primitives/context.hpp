#pragma once
// What a primitive is answered from: one tick's blackboard snapshot, the evaluator's options and
// the sensors behind each blackboard key (for sensor_offline), plus the typed answer a primitive
// function returns. Primitive functions (body.hpp, face.hpp, audio.hpp, ...) are pure functions of
// a PrimitiveContext and their query, usable from C++ without the evaluator.
//
// Statuses: ok; no_data (the analyser looked and found nothing); stale (the newest observation is
// older than `freshness`); sensor_offline (the sensors behind the observation delivered nothing
// for `offline_after`); disabled (no analyser writes what the primitive reads). Values are never
// invented.

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/primitives/catalogue.hpp"

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::primitives {

struct FaceGeometryOptions {
  // Physical width that a frontal-cascade box spans. 0.15 m fits an adult face (and the demo's
  // portrait); children's faces are smaller (~0.12-0.13 m): set it per study.
  double face_width_m = 0.15;
  double same_face_distance_m = 0.3;
  Status check() const;
};

struct EvaluatorOptions {
  Duration freshness = Duration::from_ms(100);  // older observations are stale
  Duration offline_after = Duration::from_seconds(1.0);
  // Default query of trackHand in batch analysis: the right hand's current position, predicted
  // this far ahead.
  double track_hand_dt_s = 0.2;
  // Default query of getSoundDirection: directions with a lower confidence are no_data. The
  // confidence is calibrated (modalities/sound_direction/README.md): >= 0.5 is within 10 deg
  // about 90 % of the time in eval doa's rooms, >= 0.7 (DREAM's consumer) about 98 %.
  double sound_direction_threshold = 0.5;
  FaceGeometryOptions face_geometry;
  // Default query of getHeadGaze (plane), F12: three points (world, m) spanning the plane; the
  // default is the world plane z = 0 (the front sensor's image plane, where the robot stands).
  std::array<cv::Vec3d, 3> head_gaze_plane{cv::Vec3d(0, 0, 0), cv::Vec3d(1, 0, 0),
                                           cv::Vec3d(0, 1, 0)};
  // Default query of trackFace (F23): predict the face this far ahead.
  double track_face_dt_s = 0.2;
  // Default query of trackObject (F25): predict the first object this far ahead.
  double track_object_dt_s = 0.2;
  // Default query of getObjects (circle), F14: a circle on the table (world, m).
  cv::Vec3d objects_circle_centre_m{0, 0.3, 0.6};
  double objects_circle_radius_m = 0.15;
  // F8, F15, F19, F25 with a position: the object nearest to it, if within this distance.
  double object_query_radius_m = 0.15;
  Status check() const;
};

// The sensors behind each blackboard key: the streams its writer reads, and those behind the
// keys the writer reads, transitively (Pipeline::key_sensors). A key absent from the map has no
// writer in this pipeline.
using KeySensors = std::map<std::string, std::vector<SensorId>, std::less<>>;

// The newest entry of a key with its status.
template <typename T>
struct Observation {
  std::optional<Entry<T>> entry;
  PrimitiveStatus status = PrimitiveStatus::kDisabled;
  bool ok() const { return status == PrimitiveStatus::kOk; }
  const T& value() const { return *entry->value; }
};

// Holds the snapshot itself (a cheap shared handle) and refers to the evaluator's options and
// state, which must outlive it.
class PrimitiveContext {
 public:
  PrimitiveContext(BlackboardView view, Timestamp tick, const EvaluatorOptions& options,
                   const KeySensors& key_sensors, const std::map<SensorId, Timestamp>& last_seen,
                   Timestamp first_tick, const std::map<SensorId, CameraModel>& cameras)
      : view_(std::move(view)),
        tick_(tick),
        options_(options),
        key_sensors_(key_sensors),
        last_seen_(last_seen),
        first_tick_(first_tick),
        cameras_(cameras) {}

  const BlackboardView& view() const { return view_; }
  Timestamp tick() const { return tick_; }
  const EvaluatorOptions& options() const { return options_; }
  // Calibrated cameras of the session (for 3-D positions from image boxes).
  const std::map<SensorId, CameraModel>& cameras() const { return cameras_; }
  // True when an analyser of this pipeline writes `key`.
  bool written(std::string_view key) const { return key_sensors_.count(key) > 0; }
  // The sensors behind `key` (empty when nobody writes it).
  const std::vector<SensorId>& sensors_of(std::string_view key) const;

  // ok / no_data / stale / sensor_offline of the newest entry of `key` (disabled when no
  // analyser writes it).
  template <typename T>
  Observation<T> observe(Key<T> key) const {
    Observation<T> o;
    if (!written(key.name)) return o;
    o.entry = view_.get(key);
    o.status = status_of(o.entry ? std::optional<Timestamp>(o.entry->stamp) : std::nullopt,
                         o.entry && o.entry->present(), key.name);
    return o;
  }

 private:
  PrimitiveStatus status_of(std::optional<Timestamp> entry_stamp, bool present,
                            std::string_view key) const;
  BlackboardView view_;
  Timestamp tick_;
  const EvaluatorOptions& options_;
  const KeySensors& key_sensors_;
  const std::map<SensorId, Timestamp>& last_seen_;
  Timestamp first_tick_;
  const std::map<SensorId, CameraModel>& cameras_;
};

// A primitive function's answer: the status, the typed value (only when ok), and where it came
// from. `query` is the query that was answered (resolved defaults included).
template <typename V>
struct Answer {
  PrimitiveStatus status = PrimitiveStatus::kDisabled;
  std::optional<V> value;
  std::optional<double> confidence;
  std::string source;    // sensor of the data, empty if none
  Timestamp data_stamp;  // stamp of the observation used (unset if none)
  PrimitiveQuery query;
  bool ok() const { return status == PrimitiveStatus::kOk && value.has_value(); }
  // Starts an answer from an observation: its status and stamp.
  template <typename T>
  static Answer from(const Observation<T>& o) {
    Answer a;
    a.status = o.status;
    if (o.entry) a.data_stamp = o.entry->stamp;
    return a;
  }
};

template <typename V>
PrimitiveRecord to_record(PrimitiveId id, Timestamp tick, Answer<V> a) {
  PrimitiveRecord r;
  r.stamp = tick;
  r.id = id;
  r.status = a.status;
  r.confidence = a.confidence;
  if (a.status == PrimitiveStatus::kOk && a.value) r.value = std::move(*a.value);
  r.query = std::move(a.query);
  r.source = std::move(a.source);
  r.data_stamp = a.data_stamp;
  return r;
}

}  // namespace dreamsense::primitives
