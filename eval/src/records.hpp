#pragma once
// Reading analysis records and truth values (internal to the eval library).

#include "dreamsense/core/status.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>
#include <vector>

namespace dreamsense::eval {

// One JSON object per non-empty line; a missing file or a bad line is an error naming it.
Result<std::vector<nlohmann::json>> read_jsonl(const std::filesystem::path& path);

// [x, y, z] -> vector.
cv::Vec3d vec3(const nlohmann::json& a);

// world_from_head of an object with yaw_deg, pitch_deg, roll_deg (getHeadGaze values and truth
// face records), by core's rotation_from_ypr_deg.
cv::Matx33d ypr_rotation(const nlohmann::json& o);

}  // namespace dreamsense::eval
