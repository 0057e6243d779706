// Body: getBodyPose joints against the truth skeleton of the same skeleton frame.

#include "dreamsense/eval/metrics.hpp"
#include "dreamsense/eval/session_metrics.hpp"

#include <map>

namespace dreamsense::eval {
using primitives::PrimitiveId;

MetricGroup body_metrics() {
  MetricGroup g;
  g.name = "body";
  g.metrics = {{"body_joint_median_error_m", PrimitiveId::kGetBodyPose}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::map<int64_t, const nlohmann::json*> truth_skeleton;
    for (const auto* t : d.truth_of("skeleton"))
      truth_skeleton[t->value("stamp_ns", int64_t{0})] = t;
    std::vector<double> errors;
    for (const auto* r : d.of(PrimitiveId::kGetBodyPose)) {
      const auto* pose = r->value_as<primitives::BodyPoseValue>();
      if (pose == nullptr) continue;
      auto it = truth_skeleton.find(r->data_stamp.is_set() ? r->data_stamp.ns() : -1);
      if (it == truth_skeleton.end()) continue;
      const nlohmann::json& tj = (*it->second)["joints"];
      for (const auto& j : pose->joints) {
        const std::string name(joint_name(j.joint));
        if (!tj.contains(name) || j.confidence <= 0) continue;
        errors.push_back(cv::norm(j.position_m - truth_vec3(tj[name])));
      }
    }
    if (auto m = median(errors))
      metrics["body_joint_median_error_m"] = *m;
    else
      not_evaluated["body_joint_median_error_m"] =
          "no getBodyPose record matches a truth skeleton frame";
  };
  return g;
}

}  // namespace dreamsense::eval
