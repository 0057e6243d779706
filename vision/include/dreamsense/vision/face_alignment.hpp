#pragma once
// Face alignment shared by the face analysers (expression, identity): a similarity transform
// (rotation, uniform scale, translation) that puts the two eye centres of the 68 iBUG landmarks
// on fixed points of a square canonical crop, i.e. eyes level and a fixed inter-ocular distance.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <utility>
#include <vector>

namespace dreamsense::vision {

inline constexpr int kLandmarkCount68 = 68;

struct AlignmentOptions {
  int size = 64;               // side of the square crop, px
  double eye_distance = 0.40;  // distance between the eye centres / size
  double eye_row = 0.34;       // row of the eye line / size (the eyes are centred horizontally)
  // Instead of the two eye centres: the least-squares similarity that maps the landmarks onto
  // dlib's mean face template (get_face_chip_details: points 27-54 and 60-64, i.e. nose, eyes and
  // upper lips) with `template_padding` around it - the crops dlib's face descriptor network was
  // trained on (150 px, padding 0.25). eye_distance and eye_row are then ignored.
  bool dlib_template = false;
  double template_padding = 0.25;
  Status check() const;
  bool operator==(const AlignmentOptions&) const = default;
};

// Centroids of the six contour points of the subject's right eye (36-41, image left for a face
// looking at the camera) and left eye (42-47). `landmarks` must hold 68 points (DS_CHECK).
std::pair<cv::Point2d, cv::Point2d> eye_centres(const std::vector<cv::Point2d>& landmarks);

// The similarity mapping image pixels to crop pixels that sends `right_eye` to
// ((0.5 - d/2) S, r S) and `left_eye` to ((0.5 + d/2) S, r S) (S = size, (d, r) =
// eye_geometry(options)). nullopt when the eyes (nearly) coincide.
std::optional<cv::Matx23d> similarity_from_eyes(cv::Point2d right_eye, cv::Point2d left_eye,
                                                const AlignmentOptions& options);

// The similarity of the options' mode (eye centres or dlib template) from 68 landmarks; nullopt
// when degenerate. For the template, the eye positions it implies are eye_geometry().
std::optional<cv::Matx23d> similarity_from_landmarks(const std::vector<cv::Point2d>& landmarks,
                                                     const AlignmentOptions& options);
// A frontal 68-point face in a square of side `size` (x right, y down): dlib's mean face for
// points 17-67 (brows, nose, eyes, mouth) and a half-ellipse for the jaw 0-16 (dlib's template
// has no jaw). For tests and synthetic faces.
std::vector<cv::Point2d> mean_face_landmarks(double size);

// (eye_distance, eye_row) of the crop: the options' own, or the template's eye centres.
std::pair<double, double> eye_geometry(const AlignmentOptions& options);

// Where an aligned face came from (datasets report how often each path was taken).
enum class AlignmentSource {
  kLandmarks,          // eye centres of 68 landmarks (given, or fitted on a detected face)
  kLandmarksFromCrop,  // landmarks fitted on the crop's default box (no detection)
  kCropGeometry,       // no usable landmarks: the crop itself, assumed to be a face crop
};
const char* to_string(AlignmentSource source);

struct AlignedFace {
  cv::Mat grey;                        // size x size, CV_8UC1
  cv::Matx23d crop_from_image;         // image px -> crop px
  std::vector<cv::Point2d> landmarks;  // the 68 points in crop px; empty for kCropGeometry
  AlignmentSource source = AlignmentSource::kLandmarks;
};

// Grey CV_8UC1 view/copy of a CV_8UC1, CV_8UC3 (BGR) or CV_8UC4 (BGRA) image; other types are an
// error naming the type.
Result<cv::Mat> to_grey(const cv::Mat& image);

// The grey region of a camera frame around a face: the landmarks' bounding box grown by `margin`
// times its size on every side, clipped to the image, and the landmarks moved into it. Aligning
// from the region instead of the whole frame saves the colour conversion of a large frame
// (1280x960: ~1 ms); the crops are the same unless the face is at the border. Empty region when
// there are no landmarks or they lie outside the image.
struct FaceRegion {
  cv::Mat grey;
  std::vector<cv::Point2d> landmarks;
};
Result<FaceRegion> face_region(const cv::Mat& image, const std::vector<cv::Point2d>& landmarks,
                               double margin = 1.0);

// Warps `image` (any type to_grey accepts) with the similarity of the landmarks' eye centres.
// Pixels outside the image repeat the border. nullopt when `landmarks` has not 68 points or the
// eyes coincide.
Result<std::optional<AlignedFace>> align_face(const cv::Mat& image,
                                              const std::vector<cv::Point2d>& landmarks,
                                              const AlignmentOptions& options = {});

// The crop of `image` through an explicit transform (used by the crop fallback).
AlignedFace warp_face(const cv::Mat& grey, const cv::Matx23d& crop_from_image,
                      const AlignmentOptions& options, AlignmentSource source);

// The face of `aligned` warped again from its image at another crop size (the transform scaled by
// size / aligned.grey.cols): one alignment, crops at every resolution a descriptor needs.
cv::Mat resample_face(const cv::Mat& image_grey, const AlignedFace& aligned, int size);

// iBUG 68-point index of each point's mirror image (left/right swapped: 0 <-> 16, 36 <-> 45, ...).
int mirrored_landmark_index(int i);
// The face mirrored about the crop's vertical centre line (the eyes stay on their targets):
// grey flipped, crop_from_image composed with the flip, landmarks mirrored and re-indexed so
// that index i is again the same facial point. A mirror image is another plausible face.
AlignedFace mirror_face(const AlignedFace& face);

// Applies a 2x3 affine transform to points.
std::vector<cv::Point2d> transform_points(const cv::Matx23d& t,
                                          const std::vector<cv::Point2d>& points);

}  // namespace dreamsense::vision
