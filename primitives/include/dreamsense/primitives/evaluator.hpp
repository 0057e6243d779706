#pragma once
// Evaluates all 25 primitives at each tick from a blackboard snapshot.
// Statuses: ok; no_data (the analyser looked and found nothing); stale (the newest observation is
// older than `freshness`); sensor_offline (the primitive's sensors delivered nothing for
// `offline_after`); disabled (no analyser for it is configured). Values are never invented.

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/primitives/catalogue.hpp"

#include <map>
#include <set>
#include <string>
#include <vector>

namespace dreamsense::primitives {

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
  Status check() const;
};

class Evaluator {
 public:
  // `body_sensor`: the skeleton stream the body analyser uses (empty: body primitives disabled).
  // `audio_sensor`: the mic-array stream of the sound direction analyser (empty: disabled).
  Evaluator(EvaluatorOptions options, SensorId body_sensor, SensorId audio_sensor = {});

  std::vector<PrimitiveRecord> evaluate(const MultiFrame& tick, const BlackboardView& view);

 private:
  PrimitiveRecord base(PrimitiveId id, Timestamp stamp) const;
  void evaluate_body(const MultiFrame& tick, const BlackboardView& view,
                     std::vector<PrimitiveRecord>& out);
  void evaluate_sound_direction(const MultiFrame& tick, const BlackboardView& view,
                                std::vector<PrimitiveRecord>& out);
  EvaluatorOptions options_;
  SensorId body_sensor_;
  SensorId audio_sensor_;
  std::map<SensorId, Timestamp> last_seen_;
  Timestamp first_tick_ = Timestamp::unset();
};

}  // namespace dreamsense::primitives
