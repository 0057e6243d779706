#pragma once
// report.html: a self-contained page (no scripts, no network: inline CSS, inline SVG, key frames
// as data: URIs) that tells a researcher what happened in a session (docs/outputs.md):
//   1. summary: what was analysed (session or video; approximate intrinsics flagged), duration,
//      share of time in mutual gaze, number and lengths of mutual-gaze episodes, utterances;
//   2. where the child looked: a bar chart (at the robot / camera, elsewhere, no face);
//   3. an event timeline with a time axis in seconds (face found, mutual gaze, speech with its
//      transcript, speaker, gestures, expressions, any labelled primitive);
//   4. key frames of the selected camera with the analysis overlay;
//   5. data quality: face found %, dropped frames, calibration, analysers that did not run and why;
//   6. per-primitive availability (ok / no_data / stale / sensor_offline / disabled, in %);
//   7. plots of each answered primitive's quantities with units (from the value's member names:
//      *_deg, *_m, *_s, *_mps), one chart per primitive and unit, time axis in seconds;
//   8. the list of episodes (the rows of events.csv).
// Everything per primitive comes from the primitive's JSON form, so a new primitive appears
// without changes here.

#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"
#include "dreamsense/primitives/catalogue.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::exporters {

class EpisodeCollector;

// What the report says about the run besides the primitives.
struct ReportContext {
  std::vector<std::string> summary_lines;  // free text (timing)
  // The child's calibration that head pose and gaze used (subject folder, self-calibration and
  // its quality, or the generic models): a paragraph of its own.
  std::vector<std::string> calibration_lines;
  nlohmann::json input;  // AnalysisSummary::input
  nlohmann::json plan;   // PipelinePlan::to_json() (not_running, ...)
  std::vector<std::string> analyzers;
  uint64_t ticks = 0;
  uint64_t dropped_frames = 0;
  double wall_seconds = 0;
};

class HtmlReport {
 public:
  HtmlReport();
  ~HtmlReport();
  void add(const std::vector<primitives::PrimitiveRecord>& records);
  // Key frames: set the expected media span, then ask per tick whether a key frame is wanted
  // (at 10, 30, 50, 70 and 90 % of the span) and give it (a BGR picture, e.g. draw_overlay's).
  void set_span(Timestamp start, Timestamp end);
  bool wants_key_frame(Timestamp stamp) const;
  void add_key_frame(Timestamp stamp, const std::string& camera, const cv::Mat& picture);

  std::string build(const sources::SessionManifest& manifest, const ReportContext& context) const;
  Status write(const std::filesystem::path& path, const sources::SessionManifest& manifest,
               const ReportContext& context) const;

 private:
  struct Series {  // one plotted quantity of one primitive
    std::vector<float> t_s, v;
  };
  struct PrimitiveData {
    std::map<std::string, int> status_counts;
    std::map<std::string, Series> series;  // flattened value member -> samples (ok ticks only)
  };
  std::map<int, PrimitiveData> primitives_;  // by primitive id
  std::unique_ptr<EpisodeCollector> episodes_;
  std::vector<double> face_found_t_s_;  // ticks with getFaces ok
  int64_t first_stamp_ns_ = -1, last_stamp_ns_ = -1, tick_ns_ = 0;
  uint64_t ticks_ = 0;
  Timestamp span_start_ = Timestamp::unset(), span_end_ = Timestamp::unset();
  struct KeyFrame {
    double t_s;
    std::string camera, jpeg_base64;
  };
  std::vector<KeyFrame> key_frames_;
};

}  // namespace dreamsense::exporters
