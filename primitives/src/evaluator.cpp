#include "dreamsense/primitives/evaluator.hpp"

namespace dreamsense::primitives {

const std::vector<std::string>& keys_read(PrimitiveId id, const PrimitiveRegistry& registry) {
  static const std::vector<std::string> kNone;
  const PrimitiveRow* row = registry.find(id);
  return row ? row->reads : kNone;
}

Evaluator::Evaluator(EvaluatorOptions options, KeySensors key_sensors,
                     std::map<SensorId, CameraModel> cameras, const PrimitiveRegistry& registry)
    : options_(std::move(options)),
      key_sensors_(std::move(key_sensors)),
      cameras_(std::move(cameras)),
      registry_(&registry) {}

bool Evaluator::enabled(PrimitiveId id) const {
  const PrimitiveRow* row = registry_->find(id);
  if (row == nullptr) return false;
  for (const auto& k : row->reads)
    if (key_sensors_.count(k) == 0) return false;
  return true;
}

PrimitiveContext Evaluator::context(BlackboardView view, Timestamp tick) const {
  return PrimitiveContext(std::move(view), tick, options_, key_sensors_, last_seen_, first_tick_,
                          cameras_);
}

std::vector<PrimitiveRecord> Evaluator::evaluate(const MultiFrame& tick,
                                                 const BlackboardView& view) {
  if (!first_tick_.is_set()) first_tick_ = tick.stamp;
  for (const auto& [id, f] : tick.frames) last_seen_[id] = f->stamp;
  for (const auto& [id, c] : tick.chunks)
    if (!c.empty()) last_seen_[id] = c.back()->stamp;

  const PrimitiveContext ctx = context(view, tick.stamp);
  std::vector<PrimitiveRecord> out;
  out.reserve(kPrimitiveCount);
  for (const auto& i : catalogue()) {
    if (enabled(i.id)) {
      out.push_back(registry_->find(i.id)->evaluate(ctx));
    } else {
      PrimitiveRecord r;
      r.stamp = tick.stamp;
      r.id = i.id;
      out.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace dreamsense::primitives
