#pragma once
// What the operator page of `live --ui` is fed (live_analysis.cpp): every tick's frames and
// blackboard, the run's figures for the status strip (session clock, recording size, frames
// not analysed per stream, sensors offline) and the markers made on the page, which go into
// the recorded session (markers.jsonl) and the analysis (events.csv, summary.json).

#include "dreamsense/runner/analysis.hpp"
#include "dreamsense/sources/markers.hpp"
#include "dreamsense/sources/recorder.hpp"
#include "dreamsense/ui/operator_page.hpp"

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace dreamsense::live {

class OperatorFeed {
 public:
  OperatorFeed(ui::OperatorPage& page, Duration offline_after);
  ~OperatorFeed();  // the page makes no more markers through it
  OperatorFeed(const OperatorFeed&) = delete;
  OperatorFeed& operator=(const OperatorFeed&) = delete;
  // Sets the analysis' on_tick_view and markers (the page must outlive the analysis).
  void attach(runner::AnalysisOptions& analysis);
  // Once the devices run: the session clock's origin, the streams and the recording folder.
  void set_capture(const sources::LiveCapture& capture,
                   const std::optional<std::filesystem::path>& record_dir);
  // The analysis has ended: later markers are refused (they would miss the event table).
  void end();
  // What head pose and gaze use (a live self-calibration's LiveSelfCalibration::model_in_use),
  // shown in the status strip; called on the analysis thread every tick.
  void set_face_model_status(std::function<std::string()> status);

 private:
  void on_tick(const MultiFrame& tick, const BlackboardView& view);
  Result<nlohmann::json> make_marker(const std::string& label);

  struct StreamFigures {
    std::optional<uint64_t> last_sequence;
    std::optional<Timestamp> last_stamp;
    uint64_t dropped = 0;  // sequence numbers never seen by the analysis
  };
  ui::OperatorPage& page_;
  const Duration offline_after_;
  std::mutex mutex_;                                                   // everything below
  std::optional<std::chrono::steady_clock::time_point> clock_origin_;  // of the capture
  std::optional<std::filesystem::path> record_dir_;
  std::unique_ptr<sources::MarkerWriter> marker_writer_;
  std::vector<sources::SessionMarker> markers_;
  std::map<SensorId, StreamFigures> streams_;
  Timestamp first_tick_ = Timestamp::unset();
  Timestamp size_checked_ = Timestamp::unset();
  uint64_t record_bytes_ = 0;
  uint64_t ticks_ = 0;
  bool ended_ = false;
  std::function<std::string()> face_model_status_;
};

}  // namespace dreamsense::live
