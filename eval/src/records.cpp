#include "records.hpp"

#include "dreamsense/core/camera_model.hpp"

#include <fstream>
#include <string>

namespace dreamsense::eval {
using nlohmann::json;

Result<std::vector<json>> read_jsonl(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in)
    return make_error(ErrorCode::kNotFound, "{}: missing (run `dreamsense analyze` first)",
                      path.string());
  std::vector<json> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    try {
      out.push_back(json::parse(line));
    } catch (const json::exception& e) {
      return make_error(ErrorCode::kCorruptData, "{}: line {}: {}", path.string(), n, e.what());
    }
  }
  return out;
}

cv::Vec3d vec3(const json& a) {
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

cv::Matx33d ypr_rotation(const json& o) {
  return rotation_from_ypr_deg(o["yaw_deg"].get<double>(), o["pitch_deg"].get<double>(),
                               o["roll_deg"].get<double>());
}

}  // namespace dreamsense::eval
