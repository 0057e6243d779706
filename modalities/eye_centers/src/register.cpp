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
    const auto cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    o.cameras.clear();
    for (const auto& [id, m] : cameras) o.cameras.push_back(id);
    DS_ASSIGN_OR_RETURN(auto analyzer, make_eye_center_analyzer(o));
    PlannedAnalyzers p;
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::eye_centers
