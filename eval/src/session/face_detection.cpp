// Face detection and camera selection against the truth `face` records of the same tick.
//  - A detection in camera c matches when that camera's truth face is visible and the
//    detection's box centre lies inside the truth box.
//  - face_recall: camera frames with a matched detection / camera frames whose truth face is
//    visible with |yaw| <= 45 deg (issue 4's protocol).
//  - face_false_positive_rate: camera frames with an unmatched detection / camera frames searched.
//  - camera_selection_accuracy: ticks whose selected camera is the truth best_camera (the most
//    frontal view) / ticks with a truth best_camera. Strict; the _within_10deg variant also
//    accepts a camera whose face is at most 10 deg less frontal than the best one's.
//  - face_position_median_m: the first face's 3-D position against the truth head position.
// Ticks whose getFaces is stale or sensor_offline are skipped (nothing was observed); no_data
// means every camera was searched and found nothing.

#include "dreamsense/eval/metrics.hpp"
#include "dreamsense/eval/session_metrics.hpp"

#include <cmath>
#include <map>

namespace dreamsense::eval {
using primitives::PrimitiveId;
using primitives::PrimitiveStatus;

MetricGroup face_detection_metrics() {
  MetricGroup g;
  g.name = "face_detection";
  g.metrics = {{"face_recall", PrimitiveId::kGetFaces},
               {"face_false_positive_rate", PrimitiveId::kGetFaces},
               {"camera_selection_accuracy", PrimitiveId::kGetFaces},
               {"camera_selection_accuracy_within_10deg", PrimitiveId::kGetFaces},
               {"face_position_median_m", PrimitiveId::kGetFaces}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::map<int64_t, const nlohmann::json*> truth_faces;
    for (const auto* t : d.truth_of("face")) truth_faces[t->value("stamp_ns", int64_t{0})] = t;
    int visible = 0, found = 0, searched = 0, false_pos = 0, sel_total = 0, sel_exact = 0,
        sel_near = 0;
    std::vector<double> position_errors;
    auto inside = [](const nlohmann::json& box, double x, double y) {
      return x >= box[0].get<double>() && y >= box[1].get<double>() &&
             x <= box[0].get<double>() + box[2].get<double>() &&
             y <= box[1].get<double>() + box[3].get<double>();
    };
    const std::map<SensorId, std::vector<primitives::CameraFace>> none;
    for (const auto* r : d.of(PrimitiveId::kGetFaces)) {
      if (r->status != PrimitiveStatus::kOk && r->status != PrimitiveStatus::kNoData) continue;
      auto it = truth_faces.find(r->stamp.ns());
      if (it == truth_faces.end()) continue;
      const nlohmann::json& tf = *it->second;
      const auto* v = r->value_as<primitives::FacesValue>();
      const bool ok = v != nullptr;
      const auto& seen = ok ? v->cameras : none;
      std::map<std::string, bool> matched_in;
      for (const auto& [cam, tc] : tf["cameras"].items()) {
        const bool is_visible = tc.value("visible", false);
        const auto dets = seen.find(cam);
        if (ok && dets == seen.end()) continue;  // no frame from it this tick
        ++searched;
        bool matched = false, unmatched = false;
        if (dets != seen.end())
          for (const auto& det : dets->second) {
            const double cx = det.box_px.x + det.box_px.width / 2;
            const double cy = det.box_px.y + det.box_px.height / 2;
            if (is_visible && inside(tc["box"], cx, cy))
              matched = true;
            else
              unmatched = true;
          }
        matched_in[cam] = matched;
        if (unmatched) ++false_pos;
        if (is_visible && std::abs(tc.value("yaw_deg", 180.0)) <= 45) {
          ++visible;
          if (matched) ++found;
        }
      }
      const nlohmann::json best = tf.value("best_camera", nlohmann::json(nullptr));
      if (!best.is_null()) {
        ++sel_total;
        if (ok && v->selected_camera) {
          const std::string& s = *v->selected_camera;
          const std::string b = best.get<std::string>();
          if (s == b) {
            ++sel_exact;
            ++sel_near;
          } else if (matched_in[s] && tf["cameras"].contains(s) && tf["cameras"].contains(b) &&
                     std::abs(tf["cameras"][s].value("yaw_deg", 180.0)) <=
                         std::abs(tf["cameras"][b].value("yaw_deg", 180.0)) + 10.0) {
            ++sel_near;
          }
        }
      }
      if (ok && !v->faces.empty() && tf.contains("head_position_m"))
        position_errors.push_back(
            cv::norm(v->faces[0].position_m - truth_vec3(tf["head_position_m"])));
    }
    if (visible > 0)
      metrics["face_recall"] = static_cast<double>(found) / visible;
    else
      not_evaluated["face_recall"] = "no truth face visible with |yaw| <= 45 deg";
    if (searched > 0)
      metrics["face_false_positive_rate"] = static_cast<double>(false_pos) / searched;
    if (sel_total > 0) {
      metrics["camera_selection_accuracy"] = static_cast<double>(sel_exact) / sel_total;
      metrics["camera_selection_accuracy_within_10deg"] = static_cast<double>(sel_near) / sel_total;
    }
    if (auto m = median(position_errors)) metrics["face_position_median_m"] = *m;
  };
  return g;
}

}  // namespace dreamsense::eval
