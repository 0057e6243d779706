// Declared pipeline entry of the face landmarks analyser (perception/analyzer_registry.hpp).

#include "dreamsense/face_landmarks/face_landmarks_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

namespace dreamsense::face_landmarks {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "face_landmarks";
  f.summary = "68 landmarks on the selected camera's face (dlib ensemble of regression trees)";
  f.roles = {roles::kChildCamera};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    FaceLandmarksAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("model", o.dlib.model));
    DS_RETURN_IF_ERROR(options.get("other_views", o.other_views));
    DS_RETURN_IF_ERROR(options.get("other_view_min_frontalness", o.other_view_min_frontalness));
    const auto cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    o.cameras.clear();
    for (const auto& [id, m] : cameras) o.cameras.push_back(id);
    DS_ASSIGN_OR_RETURN(auto analyzer, make_face_landmarks_analyzer(o));
    PlannedAnalyzers p;
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::face_landmarks
