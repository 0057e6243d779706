#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/eval/session_metrics.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::eval {

std::vector<const primitives::PrimitiveRecord*> SessionData::of(primitives::PrimitiveId id) const {
  std::vector<const primitives::PrimitiveRecord*> out;
  for (const auto& r : records)
    if (r.id == id) out.push_back(&r);
  return out;
}

std::vector<const nlohmann::json*> SessionData::truth_of(const std::string& type) const {
  std::vector<const nlohmann::json*> out;
  for (const auto& t : truth)
    if (t.value("type", "") == type) out.push_back(&t);
  return out;
}

bool SessionData::enabled(primitives::PrimitiveId id) const {
  for (const auto& r : records)
    if (r.id == id && r.status != primitives::PrimitiveStatus::kDisabled) return true;
  return false;
}

double angle_between_deg(const cv::Vec3d& a, const cv::Vec3d& b) {
  const double c = a.dot(b) / (cv::norm(a) * cv::norm(b));
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI;
}

cv::Vec3d truth_vec3(const nlohmann::json& a) {
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

cv::Matx33d truth_rotation(const nlohmann::json& o) {
  return rotation_from_ypr_deg(o["yaw_deg"].get<double>(), o["pitch_deg"].get<double>(),
                               o["roll_deg"].get<double>());
}

}  // namespace dreamsense::eval
