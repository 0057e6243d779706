// Sound direction: getSoundDirection azimuth of ok records during each truth utterance
// [start_ns, end_ns] against the utterance's truth azimuth (array frame).

#include "dreamsense/eval/session_metrics.hpp"

#include <cmath>

namespace dreamsense::eval {
using primitives::PrimitiveId;

MetricGroup sound_direction_metrics() {
  MetricGroup g;
  g.name = "sound_direction";
  g.metrics = {{"doa_mae_deg", PrimitiveId::kGetSoundDirection},
               {"doa_within_10deg", PrimitiveId::kGetSoundDirection}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::vector<std::pair<int64_t, int64_t>> spans;
    std::vector<double> truth_az;
    for (const auto* t : d.truth_of("speech"))
      if (t->contains("azimuth_deg")) {
        spans.emplace_back(t->value("start_ns", int64_t{0}), t->value("end_ns", int64_t{0}));
        truth_az.push_back((*t)["azimuth_deg"].get<double>());
      }
    std::vector<double> errors;
    for (const auto* r : d.of(PrimitiveId::kGetSoundDirection)) {
      const auto* v = r->value_as<primitives::SoundDirectionValue>();
      if (v == nullptr) continue;
      const int64_t stamp = r->stamp.ns();
      for (size_t i = 0; i < spans.size(); ++i)
        if (stamp >= spans[i].first && stamp <= spans[i].second) {
          errors.push_back(std::abs(v->azimuth_deg - truth_az[i]));
          break;
        }
    }
    if (!errors.empty()) {
      double sum = 0;
      int within = 0;
      for (double e : errors) {
        sum += e;
        if (e <= 10) ++within;
      }
      metrics["doa_mae_deg"] = sum / static_cast<double>(errors.size());
      metrics["doa_within_10deg"] =
          static_cast<double>(within) / static_cast<double>(errors.size());
    } else {
      const char* why = spans.empty() ? "the truth has no speech records"
                                      : "no ok getSoundDirection record during a truth utterance";
      not_evaluated["doa_mae_deg"] = why;
      not_evaluated["doa_within_10deg"] = why;
    }
  };
  return g;
}

}  // namespace dreamsense::eval
