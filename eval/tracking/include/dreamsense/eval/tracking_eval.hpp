#pragma once
// `dreamsense eval tracking --dataset otb|mil DIR [--tracker NAME|all]`: one-pass evaluation
// (OPE, Wu, Lim & Yang, CVPR 2013) of every chosen tracker on the same decoded frames.
//
// Protocol: each tracker starts from the first labelled box and runs over every later frame
// without re-initialisation. Scored frames: the labelled frames after the initial one (MIL's
// unlabelled frames are skipped). Per tracker: success AUC = mean over the IoU thresholds
// 0, 0.05, ..., 1 of the fraction of frames with IoU > threshold; precision20 = fraction with a
// centre error <= 20 px; mean IoU; mean centre error (px); fps = frames processed (init included)
// / seconds in init() and update() (frames are decoded before the clock starts). Several
// sequences: per-sequence metrics averaged over sequences, fps over all frames.

#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/report.hpp"
#include "dreamsense/eval/tracking_datasets.hpp"

#include <functional>
#include <string>
#include <vector>

namespace dreamsense::eval {

struct TrackingEvalOptions {
  std::string dataset;  // "otb" | "mil"
  std::filesystem::path dir;
  std::vector<std::string> trackers = {"all"};  // names of objects::make_tracker, or "all"
  int start_frame = 0;                          // otb: frame number of the first box (0 = auto)
  int max_frames = 0;                           // > 0: only the first N frames of each sequence
  Status check() const;
};

// Per-frame results of one tracker on one sequence.
struct TrackRun {
  std::vector<double> iou;           // scored frames
  std::vector<double> centre_error;  // scored frames, px
  size_t frames = 0;                 // processed (init + updates)
  size_t lost = 0;                   // frames the tracker reported lost
  double seconds = 0;
};

struct TrackScores {
  double auc = 0, precision20 = 0, mean_iou = 0, mean_center_error_px = 0, fps = 0;
  std::vector<double> success;  // at thresholds 0, 0.05, ..., 1 (21 values)
};

// The OPE thresholds 0, 0.05, ..., 1.
const std::vector<double>& success_thresholds();
TrackScores score_run(const TrackRun& run);

// Runs one tracker over decoded frames (frames[i] with truth[i]); the tracker starts on the
// first labelled frame. Error when no frame is labelled or the tracker rejects the first box.
Result<TrackRun> run_tracker(std::string_view tracker, const std::vector<cv::Mat>& frames,
                             const std::vector<std::optional<cv::Rect2d>>& truth);

Result<EvalReport> run_tracking_eval(const TrackingEvalOptions& options,
                                     const std::function<void(double)>& progress = {});

}  // namespace dreamsense::eval
