#pragma once
// Facial landmarks of the selected face (modalities/face_landmarks): V13.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <algorithm>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// Number of landmarks in the iBUG 300-W / dlib-68 mark-up.
inline constexpr int kFaceLandmarkCount = 68;

// The bounding box (extent) of points; empty for none.
inline cv::Rect2d points_extent(const std::vector<cv::Point2d>& points) {
  if (points.empty()) return {};
  double x0 = points[0].x, y0 = points[0].y, x1 = x0, y1 = y0;
  for (const cv::Point2d& p : points) {
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  }
  return {x0, y0, x1 - x0, y1 - y0};
}

// Centroid of the six eye-contour points from `first` (36: the subject's right eye, 42: the left);
// (0, 0) when there are fewer points.
inline cv::Point2d eye_contour_centroid(const std::vector<cv::Point2d>& points, size_t first) {
  cv::Point2d c(0, 0);
  if (points.size() < first + 6) return c;
  for (size_t i = first; i < first + 6; ++i) c += points[i];
  return c * (1.0 / 6);
}

// In-plane roll of 68 landmarks (deg): the image angle of the line from the subject's right eye
// to the left eye (y down: positive = that line descends to the image right; 0 = upright). 0 for
// another point count or a degenerate line.
double eye_line_roll_deg(const std::vector<cv::Point2d>& points);

// 68 facial landmarks of the selected face in the selected camera's image, iBUG 300-W order as
// seen in the image: 0-16 jaw contour (image left to right), 17-21 and 22-26 brows, 27-30 nose
// bridge (27 top, 30 tip), 31-35 nostrils, 36-41 the eye on the image left (the subject's RIGHT
// eye for a face looking at the camera), 42-47 the other eye, 48-59 outer lips, 60-67 inner lips.
struct FaceLandmarks {
  SensorId camera;        // the camera whose image was fitted (keys::kSelectedCamera)
  Timestamp frame_stamp;  // stamp of that camera frame
  uint64_t frame_sequence = 0;
  cv::Size image_size;                 // of that frame
  cv::Rect2d box_px;                   // face box the landmarker started from
  std::vector<cv::Point2d> points_px;  // kFaceLandmarkCount points, full-resolution pixels
  // Centroid of the six contour points of the subject's right (36-41) / left (42-47) eye.
  cv::Point2d right_eye_px() const { return eye_contour_centroid(points_px, 36); }
  cv::Point2d left_eye_px() const { return eye_contour_centroid(points_px, 42); }
};

// The same face's landmarks in the other cameras at the same tick (issue 15: a multi-view head
// pose). Each other camera's face of the child (CameraFaces::head_face, else its best-scored
// detection) is fitted when it is frontal enough
// (face_landmarks.other_view_min_frontalness); which of them show the selected face is for the
// reader to check (head_pose drops views that disagree with the others).
struct FaceLandmarkViews {
  std::vector<FaceLandmarks> others;  // not the selected camera; empty = one view only
};

namespace keys {
// Landmarks on the selected camera's face; absent entry when no face is selected or the
// landmarker rejected it. Nothing is written in ticks without a selection entry.
inline constexpr Key<FaceLandmarks> kFaceLandmarks{"face.landmarks"};
// Written with every kFaceLandmarks entry (present with an empty list when the option
// face_landmarks.other_views is off or no other camera has a face).
inline constexpr Key<FaceLandmarkViews> kFaceLandmarkViews{"face.landmark_views"};
}  // namespace keys

}  // namespace dreamsense
