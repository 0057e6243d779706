// Declared pipeline entry of the face detection analyser (perception/analyzer_registry.hpp).

#include "dreamsense/face_detection/face_detection_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

#include <fmt/format.h>

namespace dreamsense::face_detection {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "face_detection";
  f.summary =
      "faces in every child camera (cascade + ROI tracking) and the selected camera (head yaw, "
      "D4.2)";
  f.roles = {roles::kChildCamera};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    FaceDetectionAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("frontal_cascade", o.detector.frontal_cascade));
    DS_RETURN_IF_ERROR(options.get("use_profile", o.detector.use_profile));
    DS_RETURN_IF_ERROR(options.get("detection_width", o.detector.detection_width));
    DS_RETURN_IF_ERROR(options.get("full_search_interval", o.tracker.full_search_interval));
    DS_RETURN_IF_ERROR(options.get("roi_margin", o.tracker.roi_margin));
    DS_RETURN_IF_ERROR(options.get("roi_min_scale", o.tracker.roi_min_scale));
    DS_RETURN_IF_ERROR(options.get("roi_max_scale", o.tracker.roi_max_scale));
    DS_RETURN_IF_ERROR(options.get("roi_narrow_first", o.tracker.roi_narrow_first));
    DS_RETURN_IF_ERROR(options.get("roi_narrow_min_scale", o.tracker.roi_narrow_min_scale));
    DS_RETURN_IF_ERROR(options.get("roi_narrow_max_scale", o.tracker.roi_narrow_max_scale));
    DS_RETURN_IF_ERROR(options.get("roi_narrow_max_change", o.tracker.roi_narrow_max_change));
    DS_RETURN_IF_ERROR(options.get("lost_search_interval", o.tracker.lost_search_interval));
    DS_RETURN_IF_ERROR(options.get("turned_away_yaw_deg", o.tracker.turned_away_yaw_deg));
    DS_RETURN_IF_ERROR(
        options.get("turned_away_search_interval", o.tracker.turned_away_search_interval));
    DS_RETURN_IF_ERROR(options.get("cascade_interval", o.tracker.cascade_interval));
    DS_RETURN_IF_ERROR(options.get("guide_min_iou", o.tracker.guide_min_iou));
    DS_RETURN_IF_ERROR(options.get("roll_min_deg", o.tracker.roll_min_deg));
    DS_RETURN_IF_ERROR(options.get("roll_step_deg", o.tracker.roll_step_deg));
    DS_RETURN_IF_ERROR(options.get("lost_roll_deg", o.tracker.lost_roll_deg));
    DS_RETURN_IF_ERROR(
        options.get("lost_roll_search_interval", o.tracker.lost_roll_search_interval));
    DS_RETURN_IF_ERROR(options.get("lost_roll_max_yaw_deg", o.tracker.lost_roll_max_yaw_deg));
    DS_RETURN_IF_ERROR(options.get("parallel", o.parallel));
    PlannedAnalyzers p;
    // The calibrations give the faces' 3-D positions and the yaw-based camera selection.
    for (const auto* s : ctx.with_role(roles::kChildCamera))
      if (!s->camera)
        p.notes.push_back(
            fmt::format("camera '{}' has no calibration: no face positions from it", s->id));
    o.camera_models = ctx.cameras_with_role(roles::kChildCamera);
    if (o.camera_models.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    o.cameras.clear();
    for (const auto& [id, m] : o.camera_models) o.cameras.push_back(id);
    DS_ASSIGN_OR_RETURN(auto analyzer, make_face_detection_analyzer(o));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::face_detection
