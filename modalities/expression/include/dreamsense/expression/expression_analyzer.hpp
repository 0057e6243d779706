#pragma once
// Expression analyser: keys::kFaceLandmarks (+ the camera frame) -> keys::kFaceExpression.
//
// Per tick, reads kFaceLandmarks (written earlier in the same tick by face_landmarks):
//  - no landmarks entry stamped with this tick: writes nothing;
//  - absent landmarks, no frame of the landmarks' camera, or the face cannot be aligned: absent;
//  - otherwise the model's prediction on the aligned face, smoothed per face track
//    (ExpressionSmoother; the track is the newest track of the previous tick's keys::kFaceTracks,
//    read as feedback, or -1 without face tracks), confidence = the smoothed probability times
//    the landmarks' confidence.
// The classifier runs at most every recognize_interval_s of stream time per face track; between
// runs the track's last prediction feeds the smoother again (the answer lags by at most one
// interval more; the default interval equals the smoothing time constant, 0.4 s). A new track,
// or the stream going backwards, runs it at once.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/expression/expression_model.hpp"
#include "dreamsense/expression/smoothing.hpp"

#include <filesystem>
#include <memory>
#include <vector>

namespace dreamsense::expression {

// The model that ships (modalities/expression/models/MODEL_CARD.md).
std::filesystem::path default_expression_model();

// What recognize_interval_s < 0 means for a model: kNetworkRecognizeIntervalS when its method
// runs the face-api.js network (about 27 ms per face), else 0 (every tick).
inline constexpr double kNetworkRecognizeIntervalS = 0.4;
double auto_recognize_interval_s(const ExpressionModel& model);

struct ExpressionAnalyzerOptions {
  std::vector<SensorId> cameras;  // colour streams whose faces may be selected
  std::filesystem::path model;    // empty: default_expression_model()
  ExpressionSmoothingOptions smoothing;
  double recognize_interval_s = -1;  // < 0: auto_recognize_interval_s(model); 0: every tick
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_expression_analyzer(
    const ExpressionAnalyzerOptions& options);

}  // namespace dreamsense::expression
