#include "dreamsense/geometry/calibration_io.hpp"

#include "dreamsense/core/opencv_error.hpp"

#include <atomic>
#include <system_error>
#include <unistd.h>

namespace dreamsense::geometry {

Status write_atomically(const std::filesystem::path& path,
                        const std::function<Status(const std::filesystem::path&)>& writer) {
  namespace fs = std::filesystem;
  static std::atomic<int> counter{0};
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kIoError, "{}: folder {} does not exist", path.string(),
                      dir.string());
  // Same extension, so that OpenCV FileStorage picks the same format (YAML/XML).
  const fs::path tmp =
      dir / fmt::format(".{}.tmp{}-{}{}", path.stem().string(), static_cast<long>(::getpid()),
                        counter++, path.extension().string());
  Status s = writer(tmp);
  if (s && !fs::exists(tmp, ec))
    s = make_error(ErrorCode::kIoError, "{}: nothing was written", path.string());
  if (s) {
    fs::rename(tmp, path, ec);
    if (ec)
      s = make_error(ErrorCode::kIoError, "{}: cannot write ({})", path.string(), ec.message());
  }
  if (!s) fs::remove(tmp, ec);
  return s;
}

Status write_camera_yaml(const std::filesystem::path& path, const CameraModel& m,
                         const std::function<void(cv::FileStorage&)>& extra) {
  return write_atomically(path, [&](const std::filesystem::path& tmp) -> Status {
    try {
      cv::FileStorage fs(tmp.string(), cv::FileStorage::WRITE);
      if (!fs.isOpened())
        return make_error(ErrorCode::kIoError, "{}: cannot write calibration file", path.string());
      // The keys of dreamsense::write_camera_model, so read_camera_model reads this file.
      write_camera_model_keys(fs, m);
      if (extra) extra(fs);
      return ok_status();
    } catch (const cv::Exception& e) {
      return make_error(ErrorCode::kIoError, "{}: {}", path.string(), opencv_reason(e));
    }
  });
}

}  // namespace dreamsense::geometry
