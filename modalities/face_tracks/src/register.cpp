// Declared pipeline entry of the face tracks analyser (perception/analyzer_registry.hpp).

#include "dreamsense/face_tracks/face_tracks_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

namespace dreamsense::face_tracks {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "face_tracks";
  f.summary = "3-D face tracks with stable ids (constant velocity; trackFace)";
  f.roles = {roles::kChildCamera};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    FaceTracksAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("use_head_pose", o.use_head_pose));
    o.cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (o.cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    DS_ASSIGN_OR_RETURN(auto analyzer, make_face_tracks_analyzer(o));
    PlannedAnalyzers p;
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::face_tracks
