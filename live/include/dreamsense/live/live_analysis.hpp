#pragma once
// Live analysis (`dreamsense live`, docs/recording.md): opens the devices of a configuration,
// optionally records them, analyses them as they deliver (runner::analyze_live on its own
// thread) until the duration is reached, SIGINT/SIGTERM arrives or the analysis ends, and
// optionally publishes the primitives on DDS and serves the operator page. The verb only parses
// flags into LiveAnalysisOptions and prints the summary.

#include "dreamsense/core/status.hpp"
#include "dreamsense/publish/dds_publisher.hpp"
#include "dreamsense/runner/analysis.hpp"
#include "dreamsense/self_calibration/analysis.hpp"
#include "dreamsense/sources/recorder.hpp"
#include "dreamsense/ui/operator_page.hpp"

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace dreamsense::live {

struct LiveAnalysisOptions {
  // The analysis (out_dir, plan, ...); its on_tick_frames / on_records are replaced when the
  // operator page or DDS is on.
  runner::AnalysisOptions analysis;
  std::filesystem::path config;                     // device configuration (YAML)
  std::optional<std::filesystem::path> record;      // also record the session into this new folder
  double duration_s = 0;                            // stop after this long (0: until a signal)
  bool stop_on_signals = true;                      // SIGINT / SIGTERM stop the run
  std::optional<publish::DdsPublisherOptions> dds;  // publish the primitives
  std::optional<ui::OperatorPageOptions> ui;        // serve the operator page
  // A child without a calibration folder (self_calibration::needs_self_calibration of the
  // capture's configuration with this mode) is self-calibrated while the session runs
  // (self_calibration/live.hpp, files in OUT/self_calibration/): head pose and gaze use the
  // generic models until it converges and the child's after. kNever: generic throughout.
  self_calibration::SelfCalibrationMode self_calibration =
      self_calibration::SelfCalibrationMode::kWhenNoSubject;
  std::vector<runner::OptionOverride> self_calibration_overrides;  // --set self_calibration.K=V
  // When the live self-calibration converged: also save it as the subject's folder
  // (self_calibration::save_subject_folder under plan.subjects_dir; `saved_to` in its status).
  bool save_live_self_calibration = false;
  // Called once the operator page serves (its URL), and once the capture runs.
  std::function<void(const std::string& url)> on_ui_started;
  std::function<void()> on_capture_started;
};

struct LiveAnalysisSummary {
  runner::AnalysisSummary analysis;
  sources::RecordStats capture;
  std::optional<publish::DdsPublisherStats> dds;  // when publishing
  // The live self-calibration's status (LiveSelfCalibration::status() and `used_from_ns`, the
  // stamp of the tick after which the child's models were used), when one ran; also in
  // summary.json as `live_self_calibration`.
  std::optional<nlohmann::json> self_calibration;
};

// Errors: the publisher, the configuration, the operator page or a device that cannot start;
// an analysis or capture error (the first of them).
Result<LiveAnalysisSummary> run_live_analysis(const LiveAnalysisOptions& options);

}  // namespace dreamsense::live
