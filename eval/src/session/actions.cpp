// Body actions (F20 identifyTrajectory) against the truth's action segments, per tick.
//
// Every tick's identifyTrajectory record (not disabled) is compared with the truth label of the
// segment that contains the tick's stamp. An ok record answers its label; any other status
// (no_data: no body or the window not full yet; stale; sensor_offline) answers "none" — the
// controller gets no gesture. Within kEdgeToleranceS of a segment boundary either neighbouring
// label counts as right: the demo scene blends one pose into the next over 0.5 s, and a trailing
// window of 1 s needs a few hundred ms of the new movement before it can name it (the same rule
// and tolerance as `eval actions --dataset demo-gestures`, modalities/actions/README.md).
//  - action_accuracy: right ticks / all ticks inside the truth's segments.
//  - action_confusion: {truth label: {answered label: ticks}} over the ticks outside the
//    tolerance zones; action_recall: per truth label, the diagonal share of its row.
//  - action_rest_false_positive_rate: rest ticks (truth "none", outside the tolerance zones)
//    answered with a gesture / those rest ticks.

#include "dreamsense/eval/session_metrics.hpp"

#include <algorithm>
#include <string>
#include <vector>

namespace dreamsense::eval {
using primitives::PrimitiveId;

namespace {
constexpr double kEdgeToleranceS = 0.3;
constexpr const char* kNone = "none";

struct TruthSegment {
  int64_t start_ns = 0, end_ns = 0;
  std::string label;
};
}  // namespace

MetricGroup action_metrics() {
  MetricGroup g;
  g.name = "actions";
  g.metrics = {{"action_accuracy", PrimitiveId::kIdentifyTrajectory},
               {"action_rest_false_positive_rate", PrimitiveId::kIdentifyTrajectory},
               {"action_recall", PrimitiveId::kIdentifyTrajectory},
               {"action_confusion", PrimitiveId::kIdentifyTrajectory}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::vector<TruthSegment> truth;
    for (const auto* t : d.truth_of("action"))
      truth.push_back({t->value("start_ns", int64_t{0}), t->value("end_ns", int64_t{0}),
                       t->value("label", std::string(kNone))});
    std::sort(truth.begin(), truth.end(),
              [](const auto& a, const auto& b) { return a.start_ns < b.start_ns; });
    if (truth.empty()) {
      for (const char* m : {"action_accuracy", "action_rest_false_positive_rate", "action_recall",
                            "action_confusion"})
        not_evaluated[m] = "the truth has no action segments";
      return;
    }
    const auto tol = static_cast<int64_t>(kEdgeToleranceS * 1e9);
    int total = 0, right = 0, rest = 0, rest_gesture = 0;
    std::map<std::string, std::map<std::string, int>> confusion;
    for (const auto* r : d.of(PrimitiveId::kIdentifyTrajectory)) {
      if (r->status == primitives::PrimitiveStatus::kDisabled) continue;
      const int64_t t = r->stamp.ns();
      const auto it = std::upper_bound(truth.begin(), truth.end(), t,
                                       [](int64_t v, const auto& s) { return v < s.start_ns; });
      if (it == truth.begin()) continue;
      const auto seg = std::prev(it);
      if (t >= seg->end_ns) continue;  // after the truth's last segment
      std::string said = kNone;
      if (const auto* v = r->value_as<primitives::ClassLabelValue>(); v && r->ok()) said = v->label;
      bool ok = said == seg->label, near_edge = false;
      if (seg != truth.begin() && t - seg->start_ns <= tol) {
        near_edge = true;
        ok |= said == std::prev(seg)->label;
      }
      if (std::next(seg) != truth.end() && seg->end_ns - t <= tol) {
        near_edge = true;
        ok |= said == std::next(seg)->label;
      }
      ++total;
      right += ok;
      if (near_edge) continue;
      confusion[seg->label][said]++;
      if (seg->label == kNone) {
        ++rest;
        rest_gesture += said != kNone;
      }
    }
    if (total == 0) {
      not_evaluated["action_accuracy"] = "no identifyTrajectory record falls in a truth segment";
      return;
    }
    metrics["action_accuracy"] = static_cast<double>(right) / total;
    if (rest > 0)
      metrics["action_rest_false_positive_rate"] = static_cast<double>(rest_gesture) / rest;
    else
      not_evaluated["action_rest_false_positive_rate"] = "no rest outside the tolerance zones";
    nlohmann::json recall = nlohmann::json::object(), conf = nlohmann::json::object();
    for (const auto& [label, row] : confusion) {
      int n = 0;
      for (const auto& [said, k] : row) n += k, conf[label][said] = k;
      const auto diag = row.find(label);
      recall[label] = n > 0 && diag != row.end() ? static_cast<double>(diag->second) / n : 0.0;
    }
    metrics["action_recall"] = recall;
    metrics["action_confusion"] = conf;
  };
  return g;
}

}  // namespace dreamsense::eval
