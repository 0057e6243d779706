#include "dreamsense/self_calibration/analysis.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/gaze/fixation_yaw.hpp"
#include "dreamsense/gaze/gaze_estimator.hpp"
#include "dreamsense/perception/options_node.hpp"
#include "dreamsense/self_calibration/session.hpp"
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>

#include <cmath>

namespace dreamsense::self_calibration {
namespace fs = std::filesystem;

bool needs_self_calibration(const runner::PlanOptions& plan,
                            const sources::SessionManifest& manifest, SelfCalibrationMode mode) {
  if (mode == SelfCalibrationMode::kAlways) return true;
  if (mode == SelfCalibrationMode::kNever) return false;
  if (!plan.subject_from_session || !plan.subject_dir.empty() || !plan.face_model.empty() ||
      !plan.gaze_model.empty())
    return false;
  // Only sessions with calibrated colour cameras (the self-calibration triangulates).
  bool colour = false;
  for (const auto& s : manifest.streams)
    if (s.kind == SensorKind::kColor && !s.calibration.empty()) colour = true;
  if (!colour) return false;
  const auto it = manifest.metadata.find("subject");
  if (it == manifest.metadata.end() || it->second.empty()) return true;
  return !fs::is_directory(plan.subjects_dir / it->second);
}

bool needs_self_calibration(const runner::AnalysisOptions& o, SelfCalibrationMode mode) {
  if (mode == SelfCalibrationMode::kNever) return false;
  auto manifest = sources::read_manifest(o.session_dir);
  if (!manifest) return mode == SelfCalibrationMode::kAlways;  // the analysis reports the error
  return needs_self_calibration(o.plan, *manifest, mode);
}

namespace {

// `--set self_calibration.KEY=VALUE` read as an analyser's options are (typed reads, one-line
// errors naming the key, unread keys unknown).
Status apply_overrides(const std::vector<runner::OptionOverride>& overrides,
                       SessionSelfCalibrationOptions& so, LiveSelfCalibrationOptions* live) {
  OptionsNode node("self_calibration", YAML::Node(YAML::NodeType::Map));
  for (const auto& o : overrides) DS_RETURN_IF_ERROR(node.set(o.key, o.value));
  if (live != nullptr) {
    DS_RETURN_IF_ERROR(node.get("live_nice", live->nice));
    DS_RETURN_IF_ERROR(node.get("live_attempts", live->attempts));
  }
  DS_RETURN_IF_ERROR(node.get("max_seconds", so.max_seconds));
  DS_RETURN_IF_ERROR(node.get("tick_step", so.tick_step));
  DS_RETURN_IF_ERROR(node.get("enough_frames", so.enough_frames));
  DS_RETURN_IF_ERROR(node.get("guided_search", so.guided_search));
  DS_RETURN_IF_ERROR(node.get("size_guided_search", so.size_guided_search));
  DS_RETURN_IF_ERROR(node.get("rolled_search_min_deg", so.rolled_search_min_deg));
  DS_RETURN_IF_ERROR(node.get("gaze_level", so.gaze_level.enabled));
  DS_RETURN_IF_ERROR(node.get("gaze_level_eye_yaw", so.gaze_level.eye_yaw));
  DS_RETURN_IF_ERROR(node.get("gaze_level_follow_yaw", so.gaze_level.follow_yaw_bias));
  DS_RETURN_IF_ERROR(node.get("gaze_level_max_yaw_deg", so.gaze_level.max_yaw_deg));
  DS_RETURN_IF_ERROR(node.get("gaze_level_max_pitch_deg", so.gaze_level.max_pitch_deg));
  DS_RETURN_IF_ERROR(node.get("gaze_level_min_ticks", so.gaze_level.min_ticks));
  for (const auto& key : node.unread_keys())
    return make_error(ErrorCode::kInvalidArgument, "{}.{}: unknown option", node.where(), key);
  return ok_status();
}

}  // namespace

Result<SessionSelfCalibrationOptions> self_calibration_options(
    const runner::PlanOptions& plan, const std::vector<runner::OptionOverride>& overrides,
    LiveSelfCalibrationOptions* live) {
  // The robot's head given on the command line (--robot-head, as the gaze analyser's option)
  // wins over the session's metadata, as it does for mutual gaze.
  SessionSelfCalibrationOptions so;
  for (const auto& over : plan.overrides)
    if (over.analyzer == "gaze" && over.key == "mutual.robot_head_m") {
      std::string v = over.value;
      for (char& ch : v)
        if (ch == '[' || ch == ']') ch = ' ';
      so.face.fixation_target_world_m = parse_vec3(v);
    }
  DS_RETURN_IF_ERROR(apply_overrides(overrides, so, live));
  DS_RETURN_IF_ERROR(so.check());
  return so;
}

std::vector<runner::OptionOverride> take_self_calibration_overrides(
    std::vector<runner::OptionOverride>& overrides) {
  std::vector<runner::OptionOverride> taken;
  std::erase_if(overrides, [&](const runner::OptionOverride& o) {
    if (o.analyzer != "self_calibration") return false;
    taken.push_back(o);
    return true;
  });
  return taken;
}

Result<nlohmann::json> self_calibrate_for_analysis(runner::AnalysisOptions& o,
                                                   const ForAnalysisOptions& options) {
  const SelfCalibrationMode mode = options.mode;
  auto progress = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  progress("self-calibration: the child's face from the session...");
  DS_ASSIGN_OR_RETURN(const SessionSelfCalibrationOptions so,
                      self_calibration_options(o.plan, options.overrides));
  DS_ASSIGN_OR_RETURN(const SessionSelfCalibration c, self_calibrate_session(o.session_dir, so));
  const fs::path dir = o.out_dir / "self_calibration";
  DS_RETURN_IF_ERROR(write_self_calibration(c, dir));
  nlohmann::json j = c.to_json();
  if (mode == SelfCalibrationMode::kAlways) o.plan.subject_from_session = false;
  if (c.face.converged()) {
    o.plan.face_model = dir / "face_model.yaml";
    o.plan.gaze_model = dir / "gaze.yaml";
    // The planner would otherwise log that the subject's missing folder means a generic model.
    if (o.plan.subject_from_session) {
      if (auto manifest = sources::read_manifest(o.session_dir)) {
        const auto it = manifest->metadata.find("subject");
        if (it != manifest->metadata.end())
          log::info("no calibration for subject '{}' in {}: self-calibrated from the session",
                    it->second, o.plan.subjects_dir.string());
      }
      o.plan.subject_from_session = false;
    }
    j["face_model"] = "self-calibrated";
    j["files"] = dir.string();
    progress(fmt::format("self-calibration converged: {} ({:.1f} s CPU)", c.face.reason, c.cpu_s));
    if (options.save_subject) {
      auto manifest = sources::read_manifest(o.session_dir);
      if (!manifest) return tl::unexpected(manifest.error());
      DS_ASSIGN_OR_RETURN(const fs::path target,
                          save_subject_folder(dir, o.plan.subjects_dir, manifest->metadata,
                                              o.session_dir.string()));
      j["saved_to"] = target.string();
    }
  } else {
    j["face_model"] = "generic_51 (self-calibration did not converge)";
    log::warn(
        "self-calibration did not converge ({}): {}; generic face model and built-in gaze "
        "constants",
        head_pose::to_string(c.face.status), c.face.reason);
    if (options.save_subject)
      progress("--save-subject: nothing saved (the self-calibration did not converge)");
  }
  return j;
}

Result<fs::path> save_subject_folder(const fs::path& files, const fs::path& subjects_dir,
                                     const std::map<std::string, std::string>& metadata,
                                     const std::string& where) {
  const auto it = metadata.find("subject");
  if (it == metadata.end() || it->second.empty() || it->second.find('/') != std::string::npos)
    return make_error(ErrorCode::kInvalidArgument,
                      "{}: --save-subject needs the session's metadata subject id", where);
  const fs::path target = subjects_dir / it->second;
  if (fs::exists(target))
    return make_error(ErrorCode::kInvalidArgument,
                      "{}: subject folder exists; not overwritten by --save-subject",
                      target.string());
  std::error_code ec;
  fs::create_directories(target, ec);
  for (const char* name : {"face_model.yaml", "gaze.yaml", "self_calibration.json"})
    if (!ec) fs::copy_file(files / name, target / name, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", target.string(), ec.message());
  log::info("self-calibration saved to {}", target.string());
  return target;
}

Status save_learnt_fixation_yaw(nlohmann::json& status, const runner::AnalysisSummary& summary) {
  const auto saved = status.find("saved_to");
  if (saved == status.end() || !saved->is_string() || !summary.gaze_fixation_yaw_deg ||
      *summary.gaze_fixation_yaw_deg == 0)
    return ok_status();
  const double yaw = *summary.gaze_fixation_yaw_deg;
  const fs::path file = fs::path(saved->get<std::string>()) / "gaze.yaml";
  if (!(std::abs(yaw) <= gaze::kMaxFixationYawDeg)) {
    log::warn("{}: the learnt sideways correction {:+.1f} deg is beyond +-{} deg, not saved",
              file.string(), yaw, gaze::kMaxFixationYawDeg);
    return ok_status();
  }
  DS_ASSIGN_OR_RETURN(gaze::GazeModelFile model, gaze::read_gaze_model(file));
  model.fixation_yaw_start_deg = yaw;
  DS_RETURN_IF_ERROR(gaze::write_gaze_model(file, model));
  status["saved_fixation_yaw_deg"] = yaw;
  log::info("{}: the gaze's learnt sideways correction {:+.1f} deg saved for the next session",
            file.string(), yaw);
  return ok_status();
}

std::vector<std::string> report_lines(const nlohmann::json& status) {
  std::vector<std::string> lines;
  const bool converged = status.value("converged", false);
  const std::string reason = status.value("reason", std::string());
  const bool live = status.value("live", false);
  const std::string state = status.value("state", std::string());
  if (live && state == "searching") {
    lines.push_back(
        "self-calibration during the session: still searching when the session ended, so the "
        "generic face model and built-in gaze constants throughout");
  } else if (converged && live) {
    const auto used = status.find("used_from_ns");
    lines.push_back(
        used != status.end() && used->is_number()
            ? fmt::format("self-calibrated during the session (no calibration recording): the "
                          "generic face model and gaze constants until {:.1f} s, the child's "
                          "from then on",
                          static_cast<double>(used->get<int64_t>()) * 1e-9)
            : std::string("self-calibrated during the session, after its last tick: the generic "
                          "face model and gaze constants throughout"));
  } else if (converged) {
    lines.push_back(
        fmt::format("self-calibrated from the session's first {:.0f} s (no calibration "
                    "recording)",
                    status.value("seconds_searched", 0.0)));
  } else {
    lines.push_back(fmt::format(
        "self-calibration {} ({}): generic face model and built-in gaze constants",
        state == "failed" ? "failed" : "did not converge", status.value("status", std::string())));
  }
  if (!reason.empty()) lines.push_back(reason);
  if (converged) lines.push_back(fmt::format("{:.1f} s of CPU", status.value("cpu_s", 0.0)));
  if (status.contains("error")) lines.push_back("error: " + status.value("error", std::string()));
  // The folder is named after the child's subject id: summary.json has it, the report not.
  if (status.contains("saved_to"))
    lines.push_back("saved as the child's subject folder (summary.json: saved_to)");
  return lines;
}

}  // namespace dreamsense::self_calibration
