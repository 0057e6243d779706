#pragma once
// Evaluates all 25 primitives at each tick from a blackboard snapshot (catalogue order, one record
// each). A primitive is enabled when every blackboard key it reads has a writer in the pipeline
// (KeySensors); otherwise its record is `disabled`. The evaluator holds no per-primitive code:
// each primitive is one row registered by its family (registry.hpp: the keys it reads and its
// function with the default query of the family's options block).

#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/primitives/context.hpp"
#include "dreamsense/primitives/registry.hpp"

#include <map>
#include <vector>

namespace dreamsense::primitives {

// The blackboard keys a primitive reads; all must have a writer for it to be enabled.
const std::vector<std::string>& keys_read(PrimitiveId id,
                                          const PrimitiveRegistry& registry = builtin_primitives());

class Evaluator {
 public:
  // `key_sensors`: the keys this pipeline writes and the sensors behind each
  // (Pipeline::key_sensors). `cameras`: the session's calibrated cameras. `registry`: the
  // primitive rows (must outlive the evaluator).
  Evaluator(EvaluatorOptions options, KeySensors key_sensors,
            std::map<SensorId, CameraModel> cameras = {},
            const PrimitiveRegistry& registry = builtin_primitives());

  bool enabled(PrimitiveId id) const;
  std::vector<PrimitiveRecord> evaluate(const MultiFrame& tick, const BlackboardView& view);
  // A context for queries with other parameters (C++ API), judged with the sensor activity seen
  // by the last evaluate(): e.g. get_head_gaze_plane(evaluator.context(view, tick), {p1, p2, p3}).
  // It refers to this evaluator, which must outlive it.
  PrimitiveContext context(BlackboardView view, Timestamp tick) const;
  const EvaluatorOptions& options() const { return options_; }

 private:
  EvaluatorOptions options_;
  KeySensors key_sensors_;
  std::map<SensorId, CameraModel> cameras_;
  const PrimitiveRegistry* registry_;
  std::map<SensorId, Timestamp> last_seen_;
  Timestamp first_tick_ = Timestamp::unset();
};

}  // namespace dreamsense::primitives
