#pragma once
// The energy gate (DREAM's kind of voice activity decision), shared by the voice activity
// detector's kEnergyGate method (voice_id's utterances) and the sound direction finder, which
// gates on its own in-band level: one frame level in dB per push. The floor starts at the first
// frame's level, follows any drop at once and otherwise rises by floor_rise_db_per_s (so a long
// utterance cannot talk it up quickly). A frame is speech when its level is threshold_db above
// the floor learnt from the frames before it and above min_level_dbfs; hangover_frames frames
// after the last such frame still count (while above min_level_dbfs).

#include "dreamsense/core/status.hpp"

#include <limits>
#include <optional>

namespace dreamsense::audio {

struct EnergyGateOptions {
  double threshold_db = 10.0;
  double floor_rise_db_per_s = 3.0;
  double min_level_dbfs = -std::numeric_limits<double>::infinity();
  int hangover_frames = 0;
  Status check() const;  // lists every bad field
};

class EnergyGate {
 public:
  struct Decision {
    bool speech = false;
    double margin_db = 0;  // level - (floor + threshold), with the floor before this frame
  };
  // Precondition: options.check() passed, frame_s > 0 (the time between pushes).
  EnergyGate(EnergyGateOptions options, double frame_s);
  Decision push(double level_db);
  void reset();
  const EnergyGateOptions& options() const { return options_; }

 private:
  EnergyGateOptions options_;
  double frame_s_;
  std::optional<double> floor_db_;
  int hangover_left_ = 0;
};

}  // namespace dreamsense::audio
