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
    DS_RETURN_IF_ERROR(options.get("quantized_leaves", o.dlib.quantized_leaves));
    DS_RETURN_IF_ERROR(options.get("other_views", o.other_views));
    DS_RETURN_IF_ERROR(options.get("other_view_min_frontalness", o.other_view_min_frontalness));
    DS_RETURN_IF_ERROR(options.get("cnn_fallback", o.cnn_fallback));
    DS_RETURN_IF_ERROR(options.get("cnn_fallback_below", o.cnn_fallback_below));
    DS_RETURN_IF_ERROR(options.get("parallel", o.parallel));
    const auto cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    o.cameras.clear();
    for (const auto& [id, m] : cameras) o.cameras.push_back(id);
    if (auto s = o.check(); !s) return tl::unexpected(s.error());
    PlannedAnalyzers p;
    DS_ASSIGN_OR_RETURN(std::shared_ptr<const Landmarker> dlib, shared_dlib_landmarker(o.dlib));
    std::shared_ptr<const Landmarker> cnn;
    if (o.cnn_fallback) {
      auto c = make_face_api_landmarker(o.cnn);
      // face-api's weights not installed: dlib alone, with the reason (--print-pipeline); the
      // fallback only matters on faces dlib cannot fit (modalities/face_landmarks/README.md).
      if (!c && c.error().code != ErrorCode::kNotFound) return tl::unexpected(c.error());
      p.notes.push_back(c ? "face-api's CNN where dlib's passes disagree"
                          : "CNN fallback off: " + c.error().message);
      if (c) cnn = std::move(*c);
    }
    DS_ASSIGN_OR_RETURN(auto analyzer, make_face_landmarks_analyzer(o, dlib, cnn));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::face_landmarks
