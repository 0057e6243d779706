#pragma once
// Offline analysis of a recorded session (`dreamsense analyze`): opens and validates the session,
// plans the analysis graph (plan.hpp), runs the pipeline and writes
//   primitives.jsonl, events.log, dream.json, report.html, summary.json
// into the output folder. Outputs appear under their final names together, only when all are
// complete (core/output_file.hpp StagedOutputDir); a failed run leaves the folder as it was.

#include "dreamsense/core/pipeline.hpp"
#include "dreamsense/primitives/evaluator.hpp"
#include "dreamsense/runner/plan.hpp"
#include "dreamsense/sources/markers.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>

namespace dreamsense::sources {
class LiveCapture;
}

namespace dreamsense::runner {

struct AnalysisOptions {
  // A session folder, or a plain video file (is_video_input): a one-camera session made on the
  // fly (sources/video_file.hpp, docs/video_input.md).
  std::filesystem::path session_dir;
  // Video input only: a CameraModel file replacing the approximate intrinsics.
  std::filesystem::path calibration;
  // Also write the CSV tables (export/csv_tables.hpp, docs/outputs.md). Unset: on for a video,
  // off for a session.
  std::optional<bool> csv;
  std::filesystem::path out_dir;             // empty: run without writing outputs (benchmarks)
  SyncPolicy policy = SyncPolicy::kSettled;  // replay: settled (deterministic)
  bool pace_source = true;                   // live policy only
  // Threads per tick for the analysers (PipelineOptions::threads; 0: auto; the outputs are the
  // same with any number). `batch` runs its analyses with 1.
  int threads = 0;
  primitives::EvaluatorOptions evaluator;
  // The analysis graph: pipeline.yaml, command-line options and the child's calibration.
  PlanOptions plan;
  // An output folder that already holds an analysis is an error unless this is set (--force);
  // then every earlier output is replaced, none is left beside the new ones.
  bool replace_existing = false;
  // Analyse a stream even when more than 20 % of its records are damaged (the damage policy in
  // docs/session_format.md; what is skipped is reported either way).
  bool allow_damaged = false;
  // Follow session files that are links to files outside the session folder (--follow-links).
  bool follow_links_outside = false;
  // Also write overlay.mp4 (boxes, landmarks, head axes, gaze rays, selected camera).
  bool overlay = false;
  bool overlay_mosaic = false;  // overlay.mp4 shows every colour camera, tiled
  // Privacy (--blur-faces): faces pixelated in every picture written (overlay.mp4, the report's
  // key frames; export/overlay.hpp face_regions_px).
  bool blur_faces = false;
  // Called with every tick's primitive records as they are produced (e.g. DDS publishing in
  // `live --publish dds`); an error ends the analysis.
  std::function<Status(const std::vector<primitives::PrimitiveRecord>&)> on_records;
  // Called with every tick's frames before its primitives (e.g. the operator page's cameras).
  std::function<void(const MultiFrame&)> on_tick_frames;
  // Called with every tick's frames and the blackboard after the tick's analysers ran (the
  // operator page draws face boxes and landmarks from it when asked; keep this cheap).
  std::function<void(const MultiFrame&, const BlackboardView&)> on_tick_view;
  // Operator markers (docs/session_format.md "Markers") for events.csv and summary.json
  // "markers", asked for once at the end of the run (live: those made on the operator page).
  // Unset for a session: its markers.jsonl.
  std::function<std::vector<sources::SessionMarker>()> markers;
  // live: the child's face model and gaze constants found while the session runs (a live
  // self-calibration, self_calibration/live.hpp), asked for after every tick with the tick's
  // frames. When it returns files, the analysers that use them (AnalyzerFactory::
  // uses_subject_models: head pose, gaze) are planned again with them and replace the running
  // ones from the next tick on (once; logged with the tick's stamp).
  std::function<std::optional<SubjectFiles>(const MultiFrame&)> live_subject_models;
  // The report's "Child calibration" paragraph, asked for when the report is written: the
  // self-calibration's status and quality (self_calibration::report_lines; live: as the session
  // ended). Without it the report names the calibration files the plan used, or the generic
  // models.
  std::function<std::vector<std::string>()> report_calibration;
  // live: called once the analysers are built (models loaded), before the first tick; `live
  // --duration` counts from here, so a slow start does not eat the analysed time.
  std::function<void()> on_ready;
  Status check() const;
};

struct AnalysisSummary {
  PipelineStats pipeline;
  std::vector<std::string> analyzers;  // names of the analysers that ran, in order
  nlohmann::json plan;                 // PipelinePlan::to_json()
  std::map<std::string, std::map<std::string, int>> status_counts;  // primitive -> status -> n
  std::vector<std::filesystem::path> outputs;
  // What was analysed: {"kind": "session"|"video", ...; for a video its size, frame rate,
  // frames, codec, "calibration" ("approximate" or the file), "approximate_calibration", "audio"}.
  nlohmann::json input;
  // What the damage policy skipped, per stream (recorded sessions; docs/session_format.md).
  std::vector<sources::StreamDamage> damage;
  // Per primitive: ok answers that held a NaN/infinity and were reported as no_data instead.
  std::map<std::string, int> non_finite;
  // Resources per minute of the input (from the first tick; the last minute may be partial),
  // for soak tests and long recordings: summary.json "per_minute" (docs/outputs.md).
  struct Minute {
    uint64_t first_tick = 0;  // index into pipeline.tick_latency_ms
    uint64_t ticks = 0;
    double peak_rss_mb = 0;  // the process's peak resident memory at the minute's end
  };
  std::vector<Minute> per_minute;
  // Per stream read: ticks that held its data, its newest stamp, and the ticks at which it had
  // delivered nothing for the evaluator's offline_after (a camera unplugged, a video "device"
  // that ended, a recording stream that stops early) while the others went on; status
  // "sensor_offline" when it was still silent at the end. summary.json "sensors".
  struct Sensor {
    uint64_t ticks_with_data = 0;
    std::optional<int64_t> last_stamp_ns;
    uint64_t offline_ticks = 0;
    bool offline = false;
  };
  std::map<SensorId, Sensor> sensors;
  std::vector<sources::SessionMarker> markers;  // operator markers, summary.json "markers"
  // The eyes' sideways bias the gaze analyser had learnt from fixations on the robot by the
  // last getEyeGaze answer (EyeGazeValue::fixation_yaw_deg); null without a gaze.
  std::optional<double> gaze_fixation_yaw_deg;
  nlohmann::json to_json() const;
};

// The file names an analysis writes into its output folder (all of them are replaced together).
const std::vector<std::string>& analysis_output_names();

using AnalysisProgress = std::function<void(double fraction)>;

// True when `path` is analysed as a plain video: not a folder, and a file with a video extension
// (or any existing file other than session.yaml).
bool is_video_input(const std::filesystem::path& path);

Result<AnalysisSummary> analyze_session(const AnalysisOptions& options,
                                        const AnalysisProgress& progress = nullptr);

// The graph analyze_session would run on this session (--print-pipeline), without running it.
Result<PipelinePlan> plan_session(const AnalysisOptions& options);

// Live analysis (`dreamsense live`): the analysers the capture's streams support, run on its
// frames as they arrive (latest-within-tolerance policy with the flow limiter: a slow analyser
// drops ticks, counted, instead of falling behind), with the same outputs as analyze_session.
// options.session_dir is not used (the capture's manifest describes the streams). Returns when
// the capture has ended (LiveCapture::stop()); the caller then calls capture.finish().
Result<AnalysisSummary> analyze_live(const AnalysisOptions& options, sources::LiveCapture& capture);

// Adds `value` as `key` to OUT/summary.json, written by an analysis (atomic rewrite): for what
// is known only after it, e.g. the live capture's per-stream counts or a self-calibration.
Status add_to_summary(const std::filesystem::path& out_dir, const std::string& key,
                      const nlohmann::json& value);

}  // namespace dreamsense::runner
