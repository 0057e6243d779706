// Declared pipeline entry of the head pose analyser (perception/analyzer_registry.hpp).

#include "dreamsense/head_pose/face_shape_fit.hpp"
#include "dreamsense/head_pose/head_pose_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

namespace dreamsense::head_pose {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "head_pose";
  f.summary =
      "head pose by PnP of the landmarks against the child's 3-D face model (generic when the "
      "child has none), One-Euro filtered";
  f.roles = {roles::kChildCamera};
  f.uses_subject_models = true;
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    HeadPoseAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("max_rms_per_interocular", o.estimator.max_rms_per_interocular));
    DS_RETURN_IF_ERROR(options.get("multi_view", o.multi_view));
    DS_RETURN_IF_ERROR(options.get("view_weight_power", o.estimator.view_weight_power));
    DS_RETURN_IF_ERROR(options.child("filter").get("enabled", o.filter.enabled));
    o.cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (o.cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    const SubjectFiles& subject = ctx.subject;
    if (!subject.gaze_model.empty()) {
      DS_ASSIGN_OR_RETURN(o.model_from_head, read_model_from_head(subject.gaze_model));
    }
    if (!subject.face_model.empty()) {
      DS_ASSIGN_OR_RETURN(o.estimator.model, read_face_model(subject.face_model.string()));
    }
    PlannedAnalyzers p;
    p.notes.push_back("face model " + (subject.face_model.empty()
                                           ? std::string("generic_51 (no subject calibration)")
                                           : subject.face_model.string()));
    DS_ASSIGN_OR_RETURN(auto analyzer, make_head_pose_analyzer(o));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::head_pose
