#pragma once
// DREAM's gesture set (F20: none, wave, cover_eyes, hands_on_head, fly, drive_car, drink) from the
// demo generator: skeleton streams of any seed built straight from the scene script (no camera
// rendering), the online model trained on sliding windows, and the per-tick evaluation on other
// seeds. Custom gestures from a recorded session and a segments file (`train gestures`).
//
// Per-tick scoring (README.md "DREAM gestures"): every skeleton frame is a tick; the online
// classifier's answer at tick t is compared with the truth label at t. Within `tolerance_s` of a
// segment boundary either neighbouring label counts as right (the scene blends poses over 0.5 s
// and a trailing window lags). rest_false_positive_rate = share of rest ticks (truth none,
// outside the tolerance zones) answered with a gesture.

#include "dreamsense/actions/action_model.hpp"
#include "dreamsense/actions/gesture_model.hpp"
#include "dreamsense/actions/online.hpp"
#include "dreamsense/eval/action_eval.hpp"
#include "dreamsense/eval/report.hpp"
#include "dreamsense/sim/demo_scene.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace dreamsense::eval::actions {

// "300-399", "1000,1003,1010" or a mix ("1-3,7").
Result<std::vector<uint64_t>> parse_seeds(const std::string& spec);

struct TruthSpan {
  double start_s = 0, end_s = 0;
  std::string label;
};

struct DemoGestureData {
  double duration_s = 60;
  double rate_hz = 30;           // the demo's Kinect rate
  double joint_noise_m = 0.005;  // as the demo session writes its skeleton stream
  sim::DemoScriptOptions script = dream_script();
  static sim::DemoScriptOptions dream_script();  // the six DREAM gestures
};

struct DemoRecording {
  uint64_t seed = 0;
  dreamsense::actions::SkeletonSequence frames;
  std::vector<TruthSpan> truth;
};
// The "front.skeleton" stream the demo session of this seed would write (same noise).
DemoRecording demo_recording(uint64_t seed, const DemoGestureData& data);

struct DreamTrainOptions {
  std::vector<uint64_t> seeds;  // the model card's seeds: 300-399
  DemoGestureData data;
  double window_s = 1.0;  // the online window
  double hop_s = 0.2;     // between training windows
  // Windows ending less than this after a segment starts are left out (their label is
  // ambiguous: the pose is still blending from the previous segment).
  double settle_s = 0.3;
  ActionMethod method = pyramid_method();
  std::string description;
  Status check() const;
};
Result<dreamsense::actions::ActionModel> train_dream_model(
    const DreamTrainOptions& options, const std::function<void(double)>& progress = nullptr);

struct DreamEvalOptions {
  std::vector<uint64_t> seeds;  // fresh seeds (never the training ones)
  DemoGestureData data;
  double tolerance_s = 0.3;
  dreamsense::actions::OnlineOptions online;
  // Without a model: these methods are trained on train_seeds first (baseline and ours, same
  // run); training and test seeds must not overlap.
  std::filesystem::path model;
  std::vector<uint64_t> train_seeds;
  std::vector<ActionMethod> methods = {baseline_method(), pyramid_method(), pyramid_lda_method()};
  double train_hop_s = 0.2;
  Status check() const;
};
Result<EvalReport> run_dream_eval(const DreamEvalOptions& options,
                                  const std::function<void(double)>& progress = nullptr);

// ---- Custom gestures by demonstration ----

struct GestureSegment {
  double start_s = 0, end_s = 0;  // session clock (stamp_ns / 1e9)
  std::string label;
  int line = 0;
};
// Segments file: one demonstration per line, `start_s end_s label` (seconds on the session
// clock, label = letters, digits, '_' or '-'); blank lines and '#' comments are ignored.
Result<std::vector<GestureSegment>> read_gesture_segments(const std::filesystem::path& file);

// The child's skeleton stream of a recorded session: the first skeleton stream (or `stream`);
// per frame the body nearest to the previous choice (the first: nearest to 1.1 m in front of the
// sensor, where DREAM seats the child). Frames without a body keep their stamp with all joints
// missing.
Result<dreamsense::actions::SkeletonSequence> read_session_skeleton(
    const std::filesystem::path& session_dir, const std::string& stream = "");

struct GestureTrainReport {
  dreamsense::actions::GestureModel model;
  std::vector<std::string> lines;  // one per gesture: examples, threshold
};
Result<GestureTrainReport> train_gestures_from_session(
    const std::filesystem::path& session_dir, const std::filesystem::path& segments_file,
    const dreamsense::actions::GestureOptions& options = {}, const std::string& stream = "");

}  // namespace dreamsense::eval::actions
