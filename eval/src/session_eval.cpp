#include "dreamsense/eval/session_eval.hpp"

#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/eval/metrics.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <cmath>
#include <fstream>
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

// Which primitive each metric needs, so a disabled one is reported as such, not as zero.
const std::map<std::string, std::string> kMetricPrimitive = {
    {"face_recall", "getFaces"},
    {"face_false_positive_rate", "getFaces"},
    {"camera_selection_accuracy", "getFaces"},
    {"head_pose_median_deg", "getHeadGaze"},
    {"gaze_median_deg", "getEyeGaze"},
    {"mutual_gaze_f1", "checkMutualGaze"},
    {"eye_center_median_px", "getEyes"},
    {"doa_mae_deg", "getSoundDirection"},
    {"doa_within_10deg", "getSoundDirection"},
    {"speech_accuracy", "recognizeSpeech"},
    {"speaker_accuracy", "identifyVoice"},
    {"action_accuracy", "identifyTrajectory"},
    {"object_track_mean_iou", "getObjects"},
    {"object_position_median_m", "getObjects"},
    {"body_joint_median_error_m", "getBodyPose"},
};

Result<std::vector<json>> read_jsonl(const fs::path& path) {
  std::ifstream in(path);
  if (!in)
    return make_error(ErrorCode::kNotFound, "{}: missing (run `dreamsense analyze` first)",
                      path.string());
  std::vector<json> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    try {
      out.push_back(json::parse(line));
    } catch (const json::exception& e) {
      return make_error(ErrorCode::kCorruptData, "{}: line {}: {}", path.string(), n, e.what());
    }
  }
  return out;
}

}  // namespace

Result<json> evaluate_session(const SessionEvalOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto manifest = sources::read_manifest(options.session_dir);
  if (!manifest) return tl::unexpected(manifest.error());
  if (manifest->truth.empty())
    return make_error(ErrorCode::kNotFound, "{}: the session has no truth.jsonl to compare with",
                      (options.session_dir / sources::kManifestName).string());
  auto truth = sources::read_truth(options.session_dir / manifest->truth);
  if (!truth) return tl::unexpected(truth.error());
  auto records = read_jsonl(options.analysis_dir / "primitives.jsonl");
  if (!records) return tl::unexpected(records.error());

  // Status per primitive over the run; a metric is only computed for an enabled primitive.
  std::map<std::string, std::map<std::string, int>> status;
  int evaluated = 0, ok = 0;
  for (const auto& r : *records) {
    const std::string p = r.value("primitive", "");
    const std::string st = r.value("status", "");
    status[p][st]++;
    if (st != "disabled") {
      ++evaluated;
      if (st == "ok") ++ok;
    }
  }
  auto enabled = [&](const std::string& primitive) {
    auto it = status.find(primitive);
    if (it == status.end()) return false;
    int n = 0;
    for (const auto& [st, c] : it->second)
      if (st != "disabled") n += c;
    return n > 0;
  };

  json metrics = json::object(), not_evaluated = json::object();
  for (const auto& [metric, primitive] : kMetricPrimitive) {
    metrics[metric] = nullptr;
    if (!enabled(primitive)) not_evaluated[metric] = primitive + " is disabled (no analyser yet)";
  }
  metrics["primitives_ok_fraction"] =
      evaluated > 0 ? json(static_cast<double>(ok) / evaluated) : json(nullptr);

  // Body: getBodyPose joints against the truth skeleton of the same skeleton frame.
  if (enabled("getBodyPose")) {
    std::map<int64_t, const json*> truth_skeleton;
    for (const auto& t : *truth)
      if (t.value("type", "") == "skeleton") truth_skeleton[t.value("stamp_ns", int64_t{0})] = &t;
    std::vector<double> errors;
    for (const auto& r : *records) {
      if (r.value("primitive", "") != "getBodyPose" || r.value("status", "") != "ok") continue;
      auto it = truth_skeleton.find(r.value("data_stamp_ns", int64_t{-1}));
      if (it == truth_skeleton.end()) continue;
      const json& tj = (*it->second)["joints"];
      for (const auto& [name, jv] : r["value"]["joints"].items()) {
        if (!tj.contains(name) || jv.value("confidence", 0.0) <= 0) continue;
        const auto p = jv["position_m"];
        const auto q = tj[name];
        const double dx = p[0].get<double>() - q[0].get<double>();
        const double dy = p[1].get<double>() - q[1].get<double>();
        const double dz = p[2].get<double>() - q[2].get<double>();
        errors.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
      }
    }
    if (auto m = median(errors))
      metrics["body_joint_median_error_m"] = *m;
    else
      not_evaluated["body_joint_median_error_m"] =
          "no getBodyPose record matches a truth skeleton frame";
  }

  // Sound direction: getSoundDirection azimuth of ok records during each truth utterance
  // [start_ns, end_ns] against the utterance's truth azimuth (array frame).
  if (enabled("getSoundDirection")) {
    std::vector<std::pair<int64_t, int64_t>> spans;
    std::vector<double> truth_az;
    for (const auto& t : *truth)
      if (t.value("type", "") == "speech" && t.contains("azimuth_deg")) {
        spans.emplace_back(t.value("start_ns", int64_t{0}), t.value("end_ns", int64_t{0}));
        truth_az.push_back(t["azimuth_deg"].get<double>());
      }
    std::vector<double> errors;
    for (const auto& r : *records) {
      if (r.value("primitive", "") != "getSoundDirection" || r.value("status", "") != "ok")
        continue;
      const int64_t stamp = r.value("stamp_ns", int64_t{-1});
      for (size_t i = 0; i < spans.size(); ++i)
        if (stamp >= spans[i].first && stamp <= spans[i].second) {
          errors.push_back(std::abs(r["value"]["azimuth_deg"].get<double>() - truth_az[i]));
          break;
        }
    }
    if (!errors.empty()) {
      double sum = 0;
      int within = 0;
      for (double e : errors) {
        sum += e;
        if (e <= 10) ++within;
      }
      metrics["doa_mae_deg"] = sum / static_cast<double>(errors.size());
      metrics["doa_within_10deg"] =
          static_cast<double>(within) / static_cast<double>(errors.size());
    } else {
      const char* why = spans.empty() ? "the truth has no speech records"
                                      : "no ok getSoundDirection record during a truth utterance";
      not_evaluated["doa_mae_deg"] = why;
      not_evaluated["doa_within_10deg"] = why;
    }
  }

  json out;
  out["task"] = "session";
  out["dataset"] = {{"name", manifest->name}, {"items", records->size() / 25}};
  out["protocol"] = "primitives.jsonl of the analysis against the session's truth.jsonl";
  out["metrics"] = metrics;
  out["timing"] = json::object();
  out["per_class"] = json::object();
  out["not_evaluated"] = not_evaluated;
  out["primitive_status"] = status;
  return out;
}

}  // namespace dreamsense::eval
