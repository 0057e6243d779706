#include "dreamsense/audio/energy_gate.hpp"

#include <string>

namespace dreamsense::audio {

Status EnergyGateOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (!(threshold_db >= 0 && threshold_db <= 60))
    add(fmt::format("threshold_db must be in [0, 60] (is {})", threshold_db));
  if (!(floor_rise_db_per_s >= 0)) add("floor_rise_db_per_s must be >= 0");
  if (hangover_frames < 0) add("hangover_frames must be >= 0");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "EnergyGateOptions: {}", bad);
  return ok_status();
}

EnergyGate::EnergyGate(EnergyGateOptions options, double frame_s)
    : options_(options), frame_s_(frame_s) {
  DS_CHECK(frame_s > 0);
}

void EnergyGate::reset() {
  floor_db_.reset();
  hangover_left_ = 0;
}

EnergyGate::Decision EnergyGate::push(double level_db) {
  Decision d;
  bool above = false;
  if (!floor_db_) {
    floor_db_ = level_db;
    d.margin_db = -options_.threshold_db;
  } else {
    d.margin_db = level_db - (*floor_db_ + options_.threshold_db);
    above = d.margin_db > 0;
    if (level_db < *floor_db_)
      floor_db_ = level_db;
    else
      *floor_db_ += options_.floor_rise_db_per_s * frame_s_;
  }
  const bool audible = level_db > options_.min_level_dbfs;
  if (above && audible) {
    hangover_left_ = options_.hangover_frames;
    d.speech = true;
  } else if (hangover_left_ > 0 && audible) {
    --hangover_left_;
    d.speech = true;
  }
  return d;
}

}  // namespace dreamsense::audio
