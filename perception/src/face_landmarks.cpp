#include "dreamsense/perception/face_landmarks.hpp"

#include <cmath>

namespace dreamsense {

double eye_line_roll_deg(const std::vector<cv::Point2d>& points) {
  if (points.size() != static_cast<size_t>(kFaceLandmarkCount)) return 0;
  const cv::Point2d d = eye_contour_centroid(points, 42) - eye_contour_centroid(points, 36);
  if (!(std::isfinite(d.x) && std::isfinite(d.y)) || (d.x == 0 && d.y == 0)) return 0;
  return std::atan2(d.y, d.x) * 180.0 / CV_PI;
}

}  // namespace dreamsense
