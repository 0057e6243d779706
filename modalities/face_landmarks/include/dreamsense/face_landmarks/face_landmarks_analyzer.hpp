#pragma once
// Face landmarks analyser: landmarks on the selected camera's face (keys::kFaceLandmarks).
//
// Per tick, reads keys::kSelectedCamera (written earlier in the same tick by face_detection):
//  - no selection entry stamped with this tick: writes nothing (no camera frame this tick);
//  - absent selection (no face anywhere): absent kFaceLandmarks;
//  - the selected camera has no frame in this MultiFrame: absent;
//  - otherwise the landmarker runs on that frame and the face box: kFaceLandmarks, confidence =
//    the selected face's detection score x spread_confidence(fit spread) (a fit whose box
//    re-derivation passes disagree, e.g. an occluded or strongly turned face, is reported with
//    low confidence instead of as a confident wrong shape), or absent when the landmarker
//    rejects the face;
//  - with options.cnn_fallback, a dlib fit whose confidence (spread_confidence) is below
//    cnn_fallback_below is replaced by face-api's 68-point CNN fitted from the same face box
//    (the +switch rule of `eval landmarks`: on AFW mean NME 0.0667 -> 0.0393, failures 14 % ->
//    7 %); its confidence is then spread_confidence of its mean distance from dlib's points, so a
//    face the two landmarkers see differently stays low-confidence;
//  - with options.other_views, keys::kFaceLandmarkViews: the landmarks of every other camera's
//    face of the child this tick (keys::kFaceDetections: the face holding the last head pose's
//    projection, else the best-scored one; one landmark fit each), for a multi-view
//    head pose; written (possibly empty) with every present kFaceLandmarks, absent with it.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"

#include <memory>
#include <vector>

namespace dreamsense::face_landmarks {

struct FaceLandmarksAnalyzerOptions {
  // Colour streams the selected camera may be (optional inputs of the contract).
  std::vector<SensorId> cameras{"camera_left", "camera_middle", "camera_right"};
  DlibLandmarkerOptions dlib;  // used by the factory that builds its own landmarker
  // spread_confidence(spread, spread_ok, spread_bad) multiplies the confidence (landmarker.hpp).
  double spread_ok = 0.03, spread_bad = 0.10;
  // Also fit the other cameras' faces (keys::kFaceLandmarkViews; issue 15's multi-view head
  // pose). Costs one landmark fit per other camera with a face.
  bool other_views = true;
  // Other cameras whose face is less frontal than this (DetectedFace::frontalness, 1 - |yaw| / 90
  // from the last head pose) are not fitted: dlib's fits break on strongly turned faces.
  double other_view_min_frontalness = 0.5;
  // face-api's CNN where dlib's own passes disagree (header comment); the weights come from the
  // npm package @vladmandic/face-api (tools/setup.sh); make_face_landmarks_analyzer fails
  // (kNotFound, naming the file) without it, and the pipeline's plan then runs dlib alone.
  bool cnn_fallback = true;
  double cnn_fallback_below = 0.5;  // spread_confidence of dlib's fit
  FaceApiLandmarkerOptions cnn;
  // true: the selected face's fit and the other views' fits run at once (cv::parallel_for_, one
  // task per face); false: one after the other. Same output either way.
  bool parallel = true;
  Status check() const;
};

// Builds a dlib landmarker from options.dlib (loads the model), and face-api's CNN from
// options.cnn when options.cnn_fallback.
Result<std::unique_ptr<Analyzer>> make_face_landmarks_analyzer(
    const FaceLandmarksAnalyzerOptions& options = {});
// Uses landmarkers created elsewhere (shared: load the models once, e.g. in tests); without
// `cnn` there is no fallback whatever options.cnn_fallback says.
Result<std::unique_ptr<Analyzer>> make_face_landmarks_analyzer(
    const FaceLandmarksAnalyzerOptions& options, std::shared_ptr<const Landmarker> landmarker,
    std::shared_ptr<const Landmarker> cnn = nullptr);

}  // namespace dreamsense::face_landmarks
