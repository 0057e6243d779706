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

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/expression/expression_model.hpp"
#include "dreamsense/expression/smoothing.hpp"

#include <filesystem>
#include <memory>
#include <vector>

namespace dreamsense::expression {

// The model that ships (modalities/expression/models/MODEL_CARD.md): lbp_hog trained on all of
// ckplus48 (7 classes, no neutral).
std::filesystem::path default_expression_model();

struct ExpressionAnalyzerOptions {
  std::vector<SensorId> cameras;  // colour streams whose faces may be selected
  std::filesystem::path model;    // empty: default_expression_model()
  ExpressionSmoothingOptions smoothing;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_expression_analyzer(
    const ExpressionAnalyzerOptions& options);

}  // namespace dreamsense::expression
