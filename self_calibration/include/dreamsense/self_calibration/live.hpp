#pragma once
// Self-calibration during a live session (issue 15: a new child on day one, `dreamsense live`):
// the same search as a recording's self-calibration (TickSelfCalibration: every tick_step-th
// tick, until enough_frames ticks had the face in two cameras or max_seconds of session time
// passed), fed with the live ticks' camera frames on its own thread, so the analysis does not
// wait for it. When it converges, its face_model.yaml and gaze.yaml are written to a work folder
// and handed to the analysis once (runner::AnalysisOptions::live_subject_models), which then
// plans head pose and gaze again with them: the generic models until then, the child's after.
// A live tick the search thread has no room for (it is still searching an earlier one) is not
// searched (counted); an attempt that does not converge (the child not yet seen by two cameras)
// is followed by a fresh one, up to `attempts`.

#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/self_calibration/session.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>
#include <optional>

namespace dreamsense::self_calibration {

struct LiveSelfCalibrationOptions {
  SessionSelfCalibrationOptions search;  // as for a recording (self_calibration_options)
  int attempts = 3;                      // searches of max_seconds each until one converges
  // true: offer() waits for the search thread instead of skipping a tick when it is busy, so
  // every tick_step-th tick is searched (tests, replays); a live analysis must not wait.
  bool wait_when_busy = false;
  // The search thread's nice value (Linux: per thread, 0-19): above the analysis's, so that on a
  // busy machine the live ticks keep the CPU and the search takes the rest (it then converges
  // later). 0 = the analysis's priority.
  int nice = 10;
  // Where the converged files are written (created); the analysis reads them from there.
  std::filesystem::path work_dir;
  Status check() const;
};

class LiveSelfCalibration {
 public:
  // The calibrated child cameras of the live capture's manifest (files relative to `dir` or
  // absolute) and its metadata robot_head_m as the fixation target (unless options.search has
  // one). Errors: no calibrated camera, unreadable calibrations, bad options; the search thread
  // starts here.
  static Result<std::unique_ptr<LiveSelfCalibration>> start(
      const sources::SessionManifest& manifest, const std::filesystem::path& dir,
      const LiveSelfCalibrationOptions& options);
  ~LiveSelfCalibration();  // stops the search (the tick in hand is finished) and joins it
  LiveSelfCalibration(const LiveSelfCalibration&) = delete;
  LiveSelfCalibration& operator=(const LiveSelfCalibration&) = delete;

  // The analysis's tick thread, after every tick: hands every tick_step-th tick's camera frames
  // to the search; returns the converged files once, at the first tick after they were written.
  std::optional<SubjectFiles> offer(const MultiFrame& tick);
  // What head pose and gaze use now, for the operator page: "generic model, self-calibrating",
  // "the child's self-calibrated model", or "generic model (self-calibration did not converge |
  // failed)". Cheap; any thread.
  std::string model_in_use() const;
  // Blocks until the search is over (converged, given up or failed); for tests and measurements.
  void wait() const;
  // For summary.json: `live` true, `state` (searching, converged, not_converged, failed),
  // `used_from_ns` (the tick offer() handed the files over at, or null), attempts, ticks
  // offered / queued / skipped, the search thread's CPU seconds, and the last attempt's
  // SessionSelfCalibration::to_json() fields.
  nlohmann::json status() const;

 private:
  struct State;
  explicit LiveSelfCalibration(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace dreamsense::self_calibration
