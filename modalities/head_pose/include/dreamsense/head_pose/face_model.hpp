#pragma once
// 3-D face models for head pose by PnP: a subset of the 68 iBUG 300-W landmarks with their
// positions in the head frame (metres). Head frame (docs/demo_session.md, HeadPose in
// dreamsense/perception/head_pose.hpp): origin between the eyes, x towards the subject's LEFT, y
// down, z towards the back of the head; the face looks along -z. Provenance of the numbers:
// README.md.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace dreamsense::head_pose {

struct FaceModel3d {
  std::string name;
  std::vector<int> landmark_index;    // into the 68 landmarks (iBUG 300-W order)
  std::vector<cv::Point3d> points_m;  // same length, head frame
  Status check() const;               // >= 4 points, same lengths, indices in [0, 68), no repeats
};

// Generic adult mean face ("generic_68"): x/y = the mean shape of dlib's 68-point model
// (initial_shape of shape_predictor_68_face_landmarks.dat), made left-right symmetric and scaled
// to an outer-eye-corner distance of 94 mm (the DREAM model's); z = authored per landmark from the
// depths of the DREAM 13-point model (nose tip 29 mm in front of the inner eye corners, ...),
// interpolated for the jaw, lids and lips. Origin = centroid of the 12 eye-contour points.
// `with_jaw` = false drops the 17 jaw-contour points (0-16), whose 2-D position slides along the
// cheek silhouette when the head turns (the default subset for PnP), leaving 51 points.
FaceModel3d generic_face_model(bool with_jaw = false);
// The 13-point DREAM model (SA/config/Landmark13_3D.xml as approximated in
// spec/original-dream.md §3.2, mm -> m), mapped to dlib-68 indices 21, 22, 36, 39, 27, 42, 45,
// 30, 31, 33, 35, 48, 54; origin moved to between the eyes (mid-point of the eye corners).
FaceModel3d dream13_face_model();
// All 68 generic points (the table behind generic_face_model), for tests and drawing.
const std::vector<cv::Point3d>& generic_68_points_m();
// Scales a model (e.g. 0.85 for a child's face); rotation estimates do not depend on scale,
// distances do (proportionally).
FaceModel3d scaled(FaceModel3d model, double factor);

}  // namespace dreamsense::head_pose
