// Declared pipeline entry of the body analyser (perception/analyzer_registry.hpp).

#include "dreamsense/body/body_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

namespace dreamsense::body {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "body";
  f.summary = "the tracked child's skeleton in world (child selection among the bodies in view)";
  f.roles = {roles::kBody};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    BodyAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("expected_position_m", o.selection.expected_position_m));
    DS_RETURN_IF_ERROR(options.get("max_jump_m", o.selection.max_jump_m));
    const StreamDescription* s = ctx.first_with_role(roles::kBody);
    if (s == nullptr) return PlannedAnalyzers::skip("no stream with role body");
    o.skeleton_sensor = s->id;
    // world_from_sensor from the stream's calibration (identity: the skeleton sensor is world).
    if (s->camera) {
      o.world_from_sensor_R = s->camera->R.t();
      o.world_from_sensor_t = -(s->camera->R.t() * s->camera->t);
    }
    DS_ASSIGN_OR_RETURN(auto analyzer, make_body_analyzer(o));
    PlannedAnalyzers p;
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::body
