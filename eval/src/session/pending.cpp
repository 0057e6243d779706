// Metrics of analysers that have not landed yet: declared, so that `eval session` lists them as
// not evaluated with the reason (their primitive is disabled).

#include "dreamsense/eval/session_metrics.hpp"

namespace dreamsense::eval {
using primitives::PrimitiveId;

MetricGroup action_metrics() {
  return {"actions", {{"action_accuracy", PrimitiveId::kIdentifyTrajectory}}, nullptr};
}

MetricGroup object_metrics() {
  return {"objects",
          {{"object_track_mean_iou", PrimitiveId::kGetObjects},
           {"object_position_median_m", PrimitiveId::kGetObjects}},
          nullptr};
}

}  // namespace dreamsense::eval
