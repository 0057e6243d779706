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
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <typeindex>
#include <vector>

namespace dreamsense::primitives {

// Per-family parameters. Each primitive family defines its own options block next to its
// functions (a struct with documented defaults and `Status check() const`, e.g.
// ObjectPrimitiveOptions in objects.hpp): the default queries the evaluator answers with and the
// family's own parameters. FamilyOptions holds them by type; a block that was never set answers
// with its defaults, so a new family needs no edit here.
class FamilyOptions {
 public:
  template <typename T>
  void set(T block) {
    auto held = std::make_shared<const T>(std::move(block));
    blocks_[std::type_index(typeid(T))] = Block{held, [held] { return held->check(); }};
  }
  // The block set for T, else T's defaults.
  template <typename T>
  const T& get() const {
    auto it = blocks_.find(std::type_index(typeid(T)));
    if (it == blocks_.end()) {
      static const T kDefaults{};
      return kDefaults;
    }
    return *static_cast<const T*>(it->second.value.get());
  }
  Status check() const;  // every set block's check()

 private:
  struct Block {
    std::shared_ptr<const void> value;
    std::function<Status()> check;
  };
  std::map<std::type_index, Block> blocks_;
};

struct EvaluatorOptions {
  Duration freshness = Duration::from_ms(100);  // older observations are stale
  Duration offline_after = Duration::from_seconds(1.0);
  FamilyOptions families;  // each family's default queries and parameters
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
  // The options block of a primitive family (its defaults unless set in EvaluatorOptions).
  template <typename T>
  const T& family_options() const {
    return options_.families.get<T>();
  }
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
