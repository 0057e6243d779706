// Declared pipeline entry of the actions analyser (perception/analyzer_registry.hpp).

#include "dreamsense/actions/action_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

#include <fmt/format.h>

namespace dreamsense::actions {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "actions";
  f.summary =
      "the child's body action, F20 identifyTrajectory (sliding window over the skeleton "
      "history, linear SVM with open-set rejection; custom gestures by DTW)";
  f.roles = {roles::kBody};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    // model: the action model (default: the shipped DREAM-gesture model; "none" = custom
    // gestures only). gestures: `train gestures` output (default: the session's metadata
    // `gestures`, else the subject folder's gestures.yaml; "none" = no custom gestures).
    ActionAnalyzerOptions o;
    std::filesystem::path model_file = default_action_model_path();
    std::filesystem::path gestures_file;
    DS_RETURN_IF_ERROR(options.get("model", model_file));
    DS_RETURN_IF_ERROR(options.get("gestures", gestures_file));
    DS_RETURN_IF_ERROR(options.get("window_s", o.online.window_s));
    DS_RETURN_IF_ERROR(options.get("min_coverage", o.online.min_coverage));
    DS_RETURN_IF_ERROR(options.get("smoothing_s", o.online.smoothing_s));
    if (ctx.first_with_role(roles::kBody) == nullptr)
      return PlannedAnalyzers::skip("no stream with role body");
    PlannedAnalyzers p;
    if (model_file.filename() != "none") o.model = model_file;
    if (gestures_file.empty()) {
      DS_ASSIGN_OR_RETURN(auto session_gestures, ctx.metadata_file("gestures"));
      if (session_gestures) {
        gestures_file = *session_gestures;
      } else if (!ctx.subject.folder.empty() &&
                 std::filesystem::exists(ctx.subject.folder / "gestures.yaml")) {
        gestures_file = ctx.subject.folder / "gestures.yaml";
      }
    }
    if (!gestures_file.empty() && gestures_file.filename() != "none") o.gestures = gestures_file;
    p.notes.push_back("action model " + (o.model.empty() ? "none" : o.model.string()));
    p.notes.push_back("custom gestures " + (o.gestures.empty() ? "none" : o.gestures.string()));
    DS_ASSIGN_OR_RETURN(auto analyzer, make_action_analyzer(o));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::actions
