#pragma once
// Self-calibration before an analysis (issue 15): when it runs, pointing the analysis at its
// files, and its status in summary.json. `--subject auto` runs it always; by default it runs
// when the session's subject has no calibration folder (and no explicit model file); never with
// `--subject none` or a subject folder. The session-level algorithm is in session.hpp; the
// face-model fit in modalities/head_pose (self_calibration.hpp).

#include "dreamsense/core/status.hpp"
#include "dreamsense/runner/analysis.hpp"
#include "dreamsense/self_calibration/live.hpp"
#include "dreamsense/self_calibration/session.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace dreamsense::self_calibration {

enum class SelfCalibrationMode { kWhenNoSubject, kAlways, kNever };

// True when the analysis `o` should self-calibrate first (see above; only sessions with
// calibrated colour cameras: the self-calibration triangulates).
bool needs_self_calibration(const runner::AnalysisOptions& o, SelfCalibrationMode mode);
// The same for a plan and a manifest (a live capture's).
bool needs_self_calibration(const runner::PlanOptions& plan,
                            const sources::SessionManifest& manifest, SelfCalibrationMode mode);

struct ForAnalysisOptions {
  SelfCalibrationMode mode = SelfCalibrationMode::kWhenNoSubject;
  // Also copy the converged files to subjects_dir/<the session's subject> (a new folder).
  bool save_subject = false;
  // One-line progress messages for the user ("self-calibration: ...", "... converged: ...").
  std::function<void(const std::string&)> progress;
  // `--set self_calibration.KEY=VALUE` (taken out of the plan's overrides by
  // take_self_calibration_overrides), read like an analyser's options: tick_step,
  // enough_frames, max_seconds, guided_search, gaze_level, gaze_level_eye_yaw,
  // gaze_level_max_yaw_deg, gaze_level_max_pitch_deg, gaze_level_min_ticks. An unknown key or a bad
  // value is an error.
  std::vector<runner::OptionOverride> overrides;
};

// The self-calibration's options for an analysis: `--set self_calibration.KEY=VALUE` (see
// ForAnalysisOptions::overrides, and max_seconds), the fixation target from --robot-head when
// given. With `live` (a live self-calibration) also its keys live_nice and live_attempts, read
// into it. An unknown key or a bad value is an error.
Result<SessionSelfCalibrationOptions> self_calibration_options(
    const runner::PlanOptions& plan, const std::vector<runner::OptionOverride>& overrides,
    LiveSelfCalibrationOptions* live = nullptr);

// Removes the overrides of the pseudo-analyser "self_calibration" from `overrides` (the planner
// knows only analysers) and returns them.
std::vector<runner::OptionOverride> take_self_calibration_overrides(
    std::vector<runner::OptionOverride>& overrides);

// Writes OUT/self_calibration/ and points `o` at its files when it converged; returns the
// status for summary.json's `self_calibration`.
Result<nlohmann::json> self_calibrate_for_analysis(runner::AnalysisOptions& o,
                                                   const ForAnalysisOptions& options);

// Copies a converged self-calibration's files (face_model.yaml, gaze.yaml,
// self_calibration.json in `files`) to subjects_dir/<metadata subject> and returns that folder.
// Errors (nothing copied): no usable subject id in `metadata` (`where` names the session), the
// folder exists (never overwritten), a copy that fails.
Result<std::filesystem::path> save_subject_folder(
    const std::filesystem::path& files, const std::filesystem::path& subjects_dir,
    const std::map<std::string, std::string>& metadata, const std::string& where);

// After the analysis of a self-calibration that `--save-subject` saved (`status` has `saved_to`):
// the sideways correction the gaze learnt from the child's fixations on the robot
// (summary.gaze_fixation_yaw_deg, gaze/fixation_yaw.hpp) goes into the saved folder's gaze.yaml
// (`fixation_yaw_start_deg`), so the next session of the child applies it from its first tick,
// and into `status` (`saved_fixation_yaw_deg`). Nothing is written when there is no saved folder
// or no correction was learnt; a correction beyond gaze::kMaxFixationYawDeg is not saved (a
// warning). Error: the saved gaze.yaml cannot be read or written.
Status save_learnt_fixation_yaw(nlohmann::json& status, const runner::AnalysisSummary& summary);

// The report's "Child calibration" paragraph (runner::AnalysisOptions::report_calibration) from
// a self-calibration's status (self_calibrate_for_analysis's, or LiveSelfCalibration::status()):
// what head pose and gaze used, the quality figures, or why it did not converge.
std::vector<std::string> report_lines(const nlohmann::json& status);

}  // namespace dreamsense::self_calibration
