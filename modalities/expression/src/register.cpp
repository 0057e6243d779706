// Declared pipeline entry of the expression analyser (perception/analyzer_registry.hpp).

#include "dreamsense/expression/expression_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

namespace dreamsense::expression {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "expression";
  f.summary =
      "facial expression of the selected face (face-api.js expression network features + "
      "softmax head trained on FER2013, 7 classes with neutral, run every 0.4 s per track; the "
      "classical LBP + HOG CK+48 model selectable), smoothed per face track";
  f.roles = {roles::kChildCamera};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    ExpressionAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("model", o.model));
    DS_RETURN_IF_ERROR(options.get("recognize_interval_s", o.recognize_interval_s));
    DS_RETURN_IF_ERROR(
        options.child("smoothing").get("time_constant_s", o.smoothing.time_constant_s));
    DS_RETURN_IF_ERROR(options.child("smoothing").get("switch_margin", o.smoothing.switch_margin));
    const auto cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    for (const auto& [id, m] : cameras) o.cameras.push_back(id);
    DS_ASSIGN_OR_RETURN(auto analyzer, make_expression_analyzer(o));
    PlannedAnalyzers p;
    p.notes.push_back(
        "model " + (o.model.empty() ? default_expression_model() : o.model).string() +
        (o.recognize_interval_s >= 0
             ? fmt::format(", classifier every {} s per track", o.recognize_interval_s)
             : std::string()));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::expression
