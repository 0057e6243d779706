#pragma once
// The project's face detector and landmarker behind vision's FaceCropAligner (library
// dreamsense::vision_locate, separate from the base library so that dreamsense::vision does not
// depend on the analysers): the Viola-Jones cascade of modalities/face_detection (DREAM's
// haarcascade_frontalface_alt2) and dlib's 68-point landmarker of modalities/face_landmarks.

#include "dreamsense/core/status.hpp"
#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/vision/face_crops.hpp"

#include <memory>

namespace dreamsense::vision {

struct FaceLocatorOptions {
  // Cascade options; the factory overrides min_face_px (FaceCropOptions::min_face_fraction of the
  // working size), detection_width (no shrinking of the working image) and turns the
  // frontalness proxy off (not needed here).
  face_detection::FaceDetectorOptions detector;
  face_landmarks::DlibLandmarkerOptions landmarks;
};

// The process's dlib landmarker for options.landmarks (face_landmarks::shared_dlib_landmarker:
// the 100 MB model is loaded once, on first use, and shared with the pipeline).
Result<std::shared_ptr<const face_landmarks::Landmarker>> load_landmarker(
    const FaceLocatorOptions& options = {});

// The cascade options the aligner's finder uses for `crop` (options.detector with min_face_px
// from min_face_fraction of the working size, no shrinking of the working image, no frontalness).
face_detection::FaceDetectorOptions crop_finder_options(const FaceCropOptions& crop,
                                                        const FaceLocatorOptions& options = {});

// An aligner with a cascade of its own (not thread-safe: one per thread) and the shared
// landmarker.
Result<FaceCropAligner> make_face_crop_aligner(
    const FaceCropOptions& crop, std::shared_ptr<const face_landmarks::Landmarker> landmarker,
    const FaceLocatorOptions& options = {});

}  // namespace dreamsense::vision
