#include "dreamsense/primitives/context.hpp"

#include <algorithm>

namespace dreamsense::primitives {

Status FamilyOptions::check() const {
  for (const auto& [type, block] : blocks_) DS_RETURN_IF_ERROR(block.check());
  return ok_status();
}

Status EvaluatorOptions::check() const {
  std::string bad;
  if (freshness.ns() <= 0) bad += " freshness must be > 0;";
  if (offline_after <= freshness) bad += " offline_after must exceed freshness;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "EvaluatorOptions:" + bad);
  return families.check();
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
