// Declared pipeline entry of the eye-centre analyser (perception/analyzer_registry.hpp).

#include "dreamsense/eye_centers/eye_center_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

namespace dreamsense::eye_centers {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "eye_centers";
  f.summary = "pupil centres in the landmarks' eye regions (D4.2 improved integro-differential)";
  f.roles = {roles::kChildCamera};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    EyeCenterAnalyzerOptions o;
    std::string method(to_string(o.locator.method));
    DS_RETURN_IF_ERROR(options.get("method", method));
    const auto parsed = eye_center_method_from_string(method);
    if (!parsed)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}.method: '{}' is unknown (improved_integro_differential, daugman, "
                        "timm_barth)",
                        options.where(), method);
    o.locator.method = *parsed;
    DS_RETURN_IF_ERROR(options.get("iris_size_from_depth", o.iris_size_from_depth));
    DS_RETURN_IF_ERROR(options.get("iris_diameter_mm", o.locator.iris_size.diameter_mm));
    DS_RETURN_IF_ERROR(options.get("iris_min_ratio", o.locator.iris_size.min_ratio));
    DS_RETURN_IF_ERROR(options.get("iris_max_ratio", o.locator.iris_size.max_ratio));
    DS_RETURN_IF_ERROR(
        options.get("iris_fall_back_without_pupil", o.locator.iris_size.fall_back_without_pupil));
    const auto cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    o.cameras.clear();
    for (const auto& [id, m] : cameras) {
      o.cameras.push_back(id);
      o.camera_models[id] = m;
    }
    DS_ASSIGN_OR_RETURN(auto analyzer, make_eye_center_analyzer(o));
    PlannedAnalyzers p;
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::eye_centers
