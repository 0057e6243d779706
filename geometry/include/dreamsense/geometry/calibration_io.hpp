#pragma once
// Calibration files: the core CameraModel YAML keys (core/camera_model.hpp) plus extra, optional
// keys describing how the model was obtained. Always written atomically: a temporary file in
// the same folder, renamed over the target only when complete (nothing is left on failure).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <functional>

namespace dreamsense::geometry {

// Writes `model` (keys of write_camera_model) then calls `extra` to add more keys.
Status write_camera_yaml(const std::filesystem::path& path, const CameraModel& model,
                         const std::function<void(cv::FileStorage&)>& extra = nullptr);

// Runs `writer` on a temporary path with the same extension next to `path`, then renames it.
Status write_atomically(const std::filesystem::path& path,
                        const std::function<Status(const std::filesystem::path&)>& writer);

}  // namespace dreamsense::geometry
