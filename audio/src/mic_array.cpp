#include "dreamsense/audio/mic_array.hpp"

#include "dreamsense/core/file_storage_check.hpp"

#include <cmath>
#include <exception>

namespace dreamsense::audio {

MicArrayGeometry MicArrayGeometry::kinect_v1() {
  MicArrayGeometry g;
  for (double x : {0.113, -0.036, -0.076, -0.113}) g.mics_m.emplace_back(x, 0, 0);
  return g;
}

int MicArrayGeometry::rank() const {
  if (mics_m.size() < 2) return 0;
  cv::Vec3d mean(0, 0, 0);
  for (const auto& m : mics_m) mean += m;
  mean *= 1.0 / static_cast<double>(mics_m.size());
  cv::Mat a(static_cast<int>(mics_m.size()), 3, CV_64F);
  for (int i = 0; i < a.rows; ++i)
    for (int k = 0; k < 3; ++k) a.at<double>(i, k) = mics_m[static_cast<size_t>(i)][k] - mean[k];
  cv::Mat w;
  cv::SVD::compute(a, w, cv::SVD::NO_UV);
  // Singular values measure the spread off the best-fit subspace: ~1 mm tolerance per mic.
  const double tol = 1e-3 * std::sqrt(static_cast<double>(mics_m.size()));
  int r = 0;
  for (int i = 0; i < w.rows; ++i)
    if (w.at<double>(i) > tol) ++r;
  return r;
}

Status MicArrayGeometry::check() const {
  std::string bad;
  if (mics_m.size() < 2) bad += " needs at least 2 microphones;";
  // Plausible: finite positions within 10 m of the array origin, a finite pose within 1 km.
  for (size_t i = 0; i < mics_m.size(); ++i)
    if (!cv::checkRange(mics_m[i]) || cv::norm(mics_m[i]) > 10)
      bad += fmt::format(" microphone {} position is not finite or more than 10 m away;", i);
  if (!cv::checkRange(array_from_world_R) || !cv::checkRange(array_from_world_t) ||
      cv::norm(array_from_world_t) > 1000)
    bad += " array_from_world_R/_t hold a non-finite or implausible value;";
  for (size_t i = 0; i < mics_m.size(); ++i)
    for (size_t j = i + 1; j < mics_m.size(); ++j)
      if (cv::norm(mics_m[i] - mics_m[j]) < 1e-3)
        bad += fmt::format(" microphones {} and {} coincide;", i, j);
  if (sample_rate < 8000 || sample_rate > 192000)
    bad += fmt::format(" sample_rate {} outside [8000, 192000];", sample_rate);
  if (cv::norm(array_from_world_R * array_from_world_R.t() - cv::Matx33d::eye()) > 1e-6 ||
      cv::determinant(array_from_world_R) < 0)
    bad += " array_from_world_R is not a rotation;";
  if (bad.empty() && rank() == 1) {
    for (const auto& m : mics_m)
      if (std::abs(m[1] - mics_m[0][1]) > 1e-3 || std::abs(m[2] - mics_m[0][2]) > 1e-3) {
        bad += " a linear array must lie along the array frame's x axis;";
        break;
      }
  }
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "mic array:" + bad);
  return ok_status();
}

Result<MicArrayGeometry> named_geometry(const std::string& name) {
  if (name == "kinect1") return MicArrayGeometry::kinect_v1();
  return make_error(ErrorCode::kInvalidArgument, "unknown array geometry '{}' (known: kinect1)",
                    name);
}

Result<MicArrayGeometry> read_mic_array(const std::filesystem::path& path) {
  MicArrayGeometry g;
  if (!std::filesystem::exists(path))
    return make_error(ErrorCode::kNotFound, "{}: missing mic array calibration", path.string());
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  try {
    cv::Mat m;
    fs["mic_positions_m"] >> m;
    if (m.empty() || m.cols != 3)
      return make_error(ErrorCode::kCorruptData, "{}: mic_positions_m must be an Nx3 matrix",
                        path.string());
    m.convertTo(m, CV_64F);
    g.mics_m.clear();
    for (int i = 0; i < m.rows; ++i)
      g.mics_m.emplace_back(m.at<double>(i, 0), m.at<double>(i, 1), m.at<double>(i, 2));
    if (!fs["sample_rate"].empty()) g.sample_rate = static_cast<int>(fs["sample_rate"]);
    cv::Mat R, t;
    fs["array_from_world_R"] >> R;
    fs["array_from_world_t"] >> t;
    if (!R.empty()) {
      if (R.rows != 3 || R.cols != 3)
        return make_error(ErrorCode::kCorruptData, "{}: array_from_world_R must be 3x3",
                          path.string());
      R.convertTo(R, CV_64F);
      g.array_from_world_R = cv::Matx33d(R);
    }
    if (!t.empty()) {
      if (t.total() != 3)
        return make_error(ErrorCode::kCorruptData, "{}: array_from_world_t must have 3 values",
                          path.string());
      t.convertTo(t, CV_64F);
      g.array_from_world_t = cv::Vec3d(t.ptr<double>()[0], t.ptr<double>()[1], t.ptr<double>()[2]);
    }
  } catch (const std::exception&) {
    return make_error(ErrorCode::kCorruptData,
                      "{}: not a valid OpenCV YAML/XML file, or a key holds a value of the wrong "
                      "type (mic_positions_m, sample_rate, array_from_world_R, array_from_world_t)",
                      path.string());
  }
  if (auto s = g.check(); !s)
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), s.error().message);
  return g;
}

}  // namespace dreamsense::audio
