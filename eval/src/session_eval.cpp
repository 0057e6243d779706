#include "dreamsense/eval/session_eval.hpp"

#include "dreamsense/eval/session_metrics.hpp"
#include "dreamsense/export/primitive_json.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <map>

namespace dreamsense::eval {
namespace fs = std::filesystem;
using nlohmann::json;

Status SessionEvalOptions::check() const {
  if (session_dir.empty() || analysis_dir.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "eval session: session and analysis folders are required");
  return ok_status();
}

namespace {

// One line per modality: its metrics and the primitive each needs (session/*.cpp).
std::vector<MetricGroup> metric_groups() {
  return {body_metrics(),          sound_direction_metrics(), face_detection_metrics(),
          head_and_gaze_metrics(), speech_metrics(),          speaker_metrics(),
          action_metrics(),        object_metrics(),          face_recognition_metrics(),
          robot_voice_metrics()};
}

}  // namespace

Result<json> evaluate_session(const SessionEvalOptions& options) {
  DS_RETURN_IF_ERROR(options.check());
  DS_ASSIGN_OR_RETURN(const auto manifest, sources::read_manifest(options.session_dir));
  if (manifest.truth.empty())
    return make_error(ErrorCode::kNotFound, "{}: the session has no truth.jsonl to compare with",
                      (options.session_dir / sources::kManifestName).string());
  SessionData data;
  DS_ASSIGN_OR_RETURN(data.truth, sources::read_truth(options.session_dir / manifest.truth));
  const fs::path records_file = options.analysis_dir / "primitives.jsonl";
  if (!fs::exists(records_file))
    return make_error(ErrorCode::kNotFound, "{}: missing (run `dreamsense analyze` first)",
                      records_file.string());
  DS_ASSIGN_OR_RETURN(data.records, exporters::read_primitives_jsonl(records_file));

  // Status per primitive over the run; a metric is only computed for an enabled primitive.
  std::map<std::string, std::map<std::string, int>> status;
  int evaluated = 0, ok = 0;
  for (const auto& r : data.records) {
    status[primitives::info(r.id).name][primitives::to_string(r.status)]++;
    if (r.status != primitives::PrimitiveStatus::kDisabled) {
      ++evaluated;
      if (r.ok()) ++ok;
    }
  }

  json metrics = json::object(), not_evaluated = json::object();
  const auto groups = metric_groups();
  for (const auto& g : groups)
    for (const auto& [metric, primitive] : g.metrics) {
      metrics[metric] = nullptr;
      if (!data.enabled(primitive))
        not_evaluated[metric] =
            std::string(primitives::info(primitive).name) + " is disabled (no analyser yet)";
    }
  metrics["primitives_ok_fraction"] =
      evaluated > 0 ? json(static_cast<double>(ok) / evaluated) : json(nullptr);
  for (const auto& g : groups) {
    if (!g.compute) continue;
    bool any = false;
    for (const auto& [metric, primitive] : g.metrics) any |= data.enabled(primitive);
    if (any) g.compute(data, metrics, not_evaluated);
  }

  json out;
  out["task"] = "session";
  out["dataset"] = {{"name", manifest.name}, {"items", data.records.size() / 25}};
  out["protocol"] = "primitives.jsonl of the analysis against the session's truth.jsonl";
  out["metrics"] = metrics;
  out["timing"] = json::object();
  out["per_class"] = json::object();
  out["not_evaluated"] = not_evaluated;
  out["primitive_status"] = status;
  return out;
}

}  // namespace dreamsense::eval
