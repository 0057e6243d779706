// Head pose, gaze, mutual gaze and eye centres against the truth `face` record of the same tick.
//  - head_pose_median_deg: geodesic angle between the estimated and true head rotations (all
//    three axes at once); head_gaze_median_deg: angle between the head-gaze directions;
//    head_position_median_m: getHead against the truth head position.
//  - gaze_median_deg: getEyeGaze (both eyes) against the truth eye-gaze direction, over ticks
//    with a gaze; gaze_coverage: those ticks / ticks whose truth face is visible in some camera.
//  - mutual_gaze_f1: per tick with a truth face, checkMutualGaze's `mutual` (false when there is
//    no face or no gaze) against the truth mutual_gaze.
//  - eye_center_median_px: getEyes pixel centres against the truth pupil pixels in the same
//    camera (eyes_px), over found eyes; eye_position_median_m: getEyes 3-D eye positions against
//    the truth pupils (eyes_m), over eyes with a 3-D position.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/eval/metrics.hpp"
#include "dreamsense/eval/session_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace dreamsense::eval {
using primitives::PrimitiveId;
using primitives::PrimitiveStatus;

MetricGroup head_and_gaze_metrics() {
  MetricGroup g;
  g.name = "head_and_gaze";
  g.metrics = {{"head_pose_median_deg", PrimitiveId::kGetHeadGaze},
               {"head_gaze_median_deg", PrimitiveId::kGetHeadGaze},
               {"head_position_median_m", PrimitiveId::kGetHead},
               {"gaze_median_deg", PrimitiveId::kGetEyeGaze},
               {"gaze_coverage", PrimitiveId::kGetEyeGaze},
               {"mutual_gaze_f1", PrimitiveId::kCheckMutualGaze},
               {"mutual_gaze_precision", PrimitiveId::kCheckMutualGaze},
               {"mutual_gaze_recall", PrimitiveId::kCheckMutualGaze},
               {"eye_center_median_px", PrimitiveId::kGetEyes},
               {"eye_position_median_m", PrimitiveId::kGetEyes}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::map<int64_t, const nlohmann::json*> truth_faces;
    for (const auto* t : d.truth_of("face")) truth_faces[t->value("stamp_ns", int64_t{0})] = t;
    std::map<int64_t, bool> visible_ticks;
    for (const auto& [stamp, tf] : truth_faces) {
      bool visible = false;
      for (const auto& [cam, tc] : (*tf)["cameras"].items()) visible |= tc.value("visible", false);
      visible_ticks[stamp] = visible;
    }
    std::vector<double> pose_err, head_gaze_err, head_pos_err, gaze_err, eye_err, eye_pos_err;
    int face_ticks = 0, gaze_ticks = 0, tp = 0, fp = 0, fn = 0, mutual_ticks = 0;
    for (const auto& r : d.records) {
      const PrimitiveId id = r.id;
      if (id != PrimitiveId::kGetHeadGaze && id != PrimitiveId::kGetHead &&
          id != PrimitiveId::kGetEyeGaze && id != PrimitiveId::kCheckMutualGaze &&
          id != PrimitiveId::kGetEyes)
        continue;
      const auto it = truth_faces.find(r.stamp.ns());
      if (it == truth_faces.end()) continue;
      const nlohmann::json& tf = *it->second;
      if (id == PrimitiveId::kCheckMutualGaze) {
        if (r.status == PrimitiveStatus::kStale || r.status == PrimitiveStatus::kSensorOffline ||
            r.status == PrimitiveStatus::kDisabled)
          continue;
        ++mutual_ticks;
        const auto* m = r.value_as<primitives::MutualGazeValue>();
        const bool predicted = m != nullptr && m->mutual;
        const bool actual = tf.value("mutual_gaze", false);
        tp += predicted && actual;
        fp += predicted && !actual;
        fn += !predicted && actual;
        continue;
      }
      if (r.status == PrimitiveStatus::kDisabled) continue;
      if (id == PrimitiveId::kGetEyeGaze && visible_ticks[it->first]) ++face_ticks;
      if (r.status != PrimitiveStatus::kOk) continue;
      if (const auto* v = r.value_as<primitives::HeadGazeValue>()) {
        const cv::Matx33d dr =
            rotation_from_ypr_deg(v->yaw_deg, v->pitch_deg, v->roll_deg).t() * truth_rotation(tf);
        const double c = (dr(0, 0) + dr(1, 1) + dr(2, 2) - 1) / 2;
        pose_err.push_back(std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI);
        if (tf.contains("head_gaze_dir"))
          head_gaze_err.push_back(angle_between_deg(v->direction, truth_vec3(tf["head_gaze_dir"])));
      } else if (const auto* h = r.value_as<primitives::HeadValue>()) {
        head_pos_err.push_back(cv::norm(h->position_m - truth_vec3(tf["head_position_m"])));
      } else if (const auto* e = r.value_as<primitives::EyeGazeValue>()) {
        ++gaze_ticks;
        gaze_err.push_back(angle_between_deg(e->both.direction, truth_vec3(tf["eye_gaze_dir"])));
      } else if (const auto* eyes = r.value_as<primitives::EyesValue>()) {
        if (tf.contains("eyes_m"))
          for (auto [name, m] :
               {std::pair{"right", &eyes->right_m}, std::pair{"left", &eyes->left_m}})
            if (*m && tf["eyes_m"].contains(name) && !tf["eyes_m"][name].is_null())
              eye_pos_err.push_back(cv::norm(**m - truth_vec3(tf["eyes_m"][name])));
        if (!tf["cameras"].contains(eyes->camera) ||
            !tf["cameras"][eyes->camera].contains("eyes_px"))
          continue;
        const nlohmann::json& te = tf["cameras"][eyes->camera]["eyes_px"];
        for (auto [name, px] :
             {std::pair{"right", &eyes->right_px}, std::pair{"left", &eyes->left_px}}) {
          if (!*px || !te.contains(name) || te[name].is_null()) continue;
          eye_err.push_back(std::hypot((*px)->x - te[name][0].get<double>(),
                                       (*px)->y - te[name][1].get<double>()));
        }
      }
    }
    auto put = [&](const char* name, const std::vector<double>& v, const char* why) {
      if (auto m = median(v))
        metrics[name] = *m;
      else if (!not_evaluated.contains(name))
        not_evaluated[name] = why;
    };
    put("head_pose_median_deg", pose_err, "no ok getHeadGaze record at a truth face tick");
    put("head_gaze_median_deg", head_gaze_err, "no ok getHeadGaze record at a truth face tick");
    put("head_position_median_m", head_pos_err, "no ok getHead record at a truth face tick");
    put("gaze_median_deg", gaze_err, "no ok getEyeGaze record at a truth face tick");
    put("eye_center_median_px", eye_err, "no found eye centre in a camera with truth pupils");
    put("eye_position_median_m", eye_pos_err, "no 3-D eye position at a truth face tick");
    if (face_ticks > 0) metrics["gaze_coverage"] = static_cast<double>(gaze_ticks) / face_ticks;
    if (mutual_ticks > 0) {
      metrics["mutual_gaze_f1"] =
          tp + fp + fn > 0 ? 2.0 * tp / (2.0 * tp + fp + fn) : 1.0;  // nothing to find, none found
      metrics["mutual_gaze_precision"] =
          tp + fp > 0 ? nlohmann::json(1.0 * tp / (tp + fp)) : nlohmann::json(nullptr);
      metrics["mutual_gaze_recall"] =
          tp + fn > 0 ? nlohmann::json(1.0 * tp / (tp + fn)) : nlohmann::json(nullptr);
    }
  };
  return g;
}

}  // namespace dreamsense::eval
