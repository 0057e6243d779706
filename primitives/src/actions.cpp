#include "dreamsense/primitives/actions.hpp"

#include "dreamsense/primitives/registry.hpp"

namespace dreamsense::primitives {

Answer<ClassLabelValue> identify_trajectory(const PrimitiveContext& ctx,
                                            const std::optional<WindowQuery>& /*query*/) {
  const Observation<ActionState> obs = ctx.observe(keys::kChildAction);
  auto a = Answer<ClassLabelValue>::from(obs);
  const auto& sensors = ctx.sensors_of(keys::kChildAction.name);
  if (!sensors.empty()) a.source = sensors.front();
  if (!obs.entry) return a;
  if (obs.entry->present()) a.query = WindowQuery{obs.value().window_s};
  if (a.status != PrimitiveStatus::kOk) return a;
  const ActionState& s = obs.value();
  if (!s.ready) {  // nothing to classify: no body in view, or the window is not full yet
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  ClassLabelValue v;
  v.label = s.label;
  v.id = s.dream_id;
  for (const auto& [label, score] : s.scores) v.scores[label] = score;
  a.value = std::move(v);
  a.confidence = obs.entry->confidence;
  return a;
}

// The row of the actions family.
void register_actions_primitives(PrimitiveRegistry& r) {
  r.add(PrimitiveId::kIdentifyTrajectory, {keys::kChildAction.name},
        [](const PrimitiveContext& c) { return identify_trajectory(c); });
}

}  // namespace dreamsense::primitives
