#include "dreamsense/head_pose/face_model.hpp"

#include <set>

namespace dreamsense::head_pose {
namespace {

// Generated once (README.md "3-D face models"): x/y from the symmetrised mean shape of dlib's
// shape_predictor_68_face_landmarks.dat scaled to 94 mm between the outer eye corners, z authored
// from the DREAM 13-point model's depths; origin at the centroid of the eye contours (36-47).
// Metres, head frame (x towards the subject's left, y down, z backwards). Inter-ocular distance
// (eye-contour centroids) 67.5 mm.
const std::vector<cv::Point3d> kGeneric68 = {
    {-0.0773, 0.0011, 0.0493},    // 0
    {-0.0768, 0.0215, 0.0473},    // 1
    {-0.0746, 0.0419, 0.0433},    // 2
    {-0.0703, 0.0619, 0.0373},    // 3
    {-0.0624, 0.0804, 0.0293},    // 4
    {-0.0501, 0.0965, 0.0193},    // 5
    {-0.0352, 0.1099, 0.0093},    // 6
    {-0.0187, 0.1207, 0.0013},    // 7
    {0.0000, 0.1239, -0.0047},    // 8
    {0.0187, 0.1207, 0.0013},     // 9
    {0.0352, 0.1099, 0.0093},     // 10
    {0.0501, 0.0965, 0.0193},     // 11
    {0.0624, 0.0804, 0.0293},     // 12
    {0.0703, 0.0619, 0.0373},     // 13
    {0.0746, 0.0419, 0.0433},     // 14
    {0.0768, 0.0215, 0.0473},     // 15
    {0.0773, 0.0011, 0.0493},     // 16
    {-0.0626, -0.0138, 0.0113},   // 17
    {-0.0530, -0.0225, 0.0013},   // 18
    {-0.0395, -0.0250, -0.0047},  // 19
    {-0.0254, -0.0231, -0.0067},  // 20
    {-0.0123, -0.0176, -0.0057},  // 21
    {0.0123, -0.0176, -0.0057},   // 22
    {0.0254, -0.0231, -0.0067},   // 23
    {0.0395, -0.0250, -0.0047},   // 24
    {0.0530, -0.0225, 0.0013},    // 25
    {0.0626, -0.0138, 0.0113},    // 26
    {0.0000, -0.0016, -0.0087},   // 27
    {0.0000, 0.0116, -0.0147},    // 28
    {0.0000, 0.0246, -0.0217},    // 29
    {0.0000, 0.0381, -0.0287},    // 30
    {-0.0157, 0.0472, -0.0147},   // 31
    {-0.0082, 0.0499, -0.0167},   // 32
    {0.0000, 0.0523, -0.0177},    // 33
    {0.0082, 0.0499, -0.0167},    // 34
    {0.0157, 0.0472, -0.0147},    // 35
    {-0.0470, 0.0001, 0.0063},    // 36
    {-0.0386, -0.0047, -0.0027},  // 37
    {-0.0286, -0.0046, -0.0027},  // 38
    {-0.0198, 0.0020, 0.0003},    // 39
    {-0.0292, 0.0037, -0.0007},   // 40
    {-0.0392, 0.0036, -0.0007},   // 41
    {0.0198, 0.0020, 0.0003},     // 42
    {0.0286, -0.0046, -0.0027},   // 43
    {0.0386, -0.0047, -0.0027},   // 44
    {0.0470, 0.0001, 0.0063},     // 45
    {0.0392, 0.0036, -0.0007},    // 46
    {0.0292, 0.0037, -0.0007},    // 47
    {-0.0300, 0.0716, -0.0087},   // 48
    {-0.0190, 0.0672, -0.0147},   // 49
    {-0.0078, 0.0649, -0.0187},   // 50
    {0.0000, 0.0668, -0.0197},    // 51
    {0.0078, 0.0649, -0.0187},    // 52
    {0.0190, 0.0672, -0.0147},    // 53
    {0.0300, 0.0716, -0.0087},    // 54
    {0.0193, 0.0824, -0.0147},    // 55
    {0.0085, 0.0872, -0.0167},    // 56
    {0.0000, 0.0881, -0.0167},    // 57
    {-0.0085, 0.0872, -0.0167},   // 58
    {-0.0193, 0.0824, -0.0147},   // 59
    {-0.0254, 0.0722, -0.0097},   // 60
    {-0.0079, 0.0714, -0.0157},   // 61
    {0.0000, 0.0722, -0.0167},    // 62
    {0.0079, 0.0714, -0.0157},    // 63
    {0.0254, 0.0722, -0.0097},    // 64
    {0.0080, 0.0773, -0.0147},    // 65
    {0.0000, 0.0782, -0.0157},    // 66
    {-0.0080, 0.0773, -0.0147},   // 67
};

}  // namespace

const std::vector<cv::Point3d>& generic_68_points_m() { return kGeneric68; }

Status FaceModel3d::check() const {
  if (landmark_index.size() != points_m.size())
    return make_error(ErrorCode::kInvalidArgument, "FaceModel3d '{}': {} indices but {} points",
                      name, landmark_index.size(), points_m.size());
  if (points_m.size() < 4)
    return make_error(ErrorCode::kInvalidArgument, "FaceModel3d '{}': {} points (need >= 4)", name,
                      points_m.size());
  std::set<int> seen;
  for (int i : landmark_index)
    if (i < 0 || i >= 68 || !seen.insert(i).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "FaceModel3d '{}': landmark index {} out of [0, 68) or repeated", name, i);
  return ok_status();
}

FaceModel3d generic_face_model(bool with_jaw) {
  FaceModel3d m;
  m.name = with_jaw ? "generic_68" : "generic_51";
  for (int i = with_jaw ? 0 : 17; i < 68; ++i) {
    m.landmark_index.push_back(i);
    m.points_m.push_back(kGeneric68[static_cast<size_t>(i)]);
  }
  return m;
}

FaceModel3d dream13_face_model() {
  // (dlib-68 index, x, y, z) in mm as in spec/original-dream.md §3.2 (x right in a frontal view
  // = the subject's left), made symmetric; DREAM point order 0..12.
  struct P {
    int index;
    double x, y, z;
  };
  const P pts[] = {{22, 14, -65, -5},   {21, -14, -65, -5}, {36, -47, -38, 7},  {39, -21, -37, 1},
                   {27, 0, -43, -8},    {42, 21, -37, 1},   {45, 47, -38, 7},   {30, 0, -3, -28},
                   {31, -15, 7.5, -14}, {33, 0, 12, -17},   {35, 15, 7.5, -14}, {48, -28, 34, -8},
                   {54, 28, 34, -8}};
  const cv::Point3d origin(0, -37.5, 4);  // mid-point of the four eye corners
  FaceModel3d m;
  m.name = "dream_13";
  for (const P& p : pts) {
    m.landmark_index.push_back(p.index);
    m.points_m.push_back((cv::Point3d(p.x, p.y, p.z) - origin) * 1e-3);
  }
  return m;
}

FaceModel3d scaled(FaceModel3d model, double factor) {
  for (cv::Point3d& p : model.points_m) p *= factor;
  return model;
}

}  // namespace dreamsense::head_pose
