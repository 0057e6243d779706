#include "dreamsense/geometry/correspondences.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace dreamsense::geometry {

namespace {
std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}
}  // namespace

Result<CsvTable> read_numeric_csv(const std::filesystem::path& path,
                                  const std::vector<int>& allowed_columns) {
  std::ifstream in(path);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open", path.string());
  CsvTable t;
  std::string line;
  int line_no = 0;
  bool first_content = true;
  while (std::getline(in, line)) {
    ++line_no;
    if (auto h = line.find('#'); h != std::string::npos) line.resize(h);
    line = trim(line);
    if (line.empty()) continue;
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    bool numeric = true;
    while (std::getline(ss, cell, ',')) {
      cell = trim(cell);
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      if (cell.empty() || end != cell.c_str() + cell.size()) {
        numeric = false;
        break;
      }
      row.push_back(v);
    }
    if (!numeric) {
      if (first_content) {  // header
        first_content = false;
        continue;
      }
      return make_error(ErrorCode::kCorruptData, "{}:{}: not a number: '{}'", path.string(),
                        line_no, cell);
    }
    first_content = false;
    const int cols = static_cast<int>(row.size());
    if (t.columns == 0) {
      if (std::find(allowed_columns.begin(), allowed_columns.end(), cols) ==
          allowed_columns.end()) {
        std::string allowed;
        for (int c : allowed_columns)
          allowed += (allowed.empty() ? "" : " or ") + std::to_string(c);
        return make_error(ErrorCode::kCorruptData, "{}:{}: {} columns, expected {}", path.string(),
                          line_no, cols, allowed);
      }
      t.columns = cols;
    } else if (cols != t.columns) {
      return make_error(ErrorCode::kCorruptData, "{}:{}: {} columns, earlier rows have {}",
                        path.string(), line_no, cols, t.columns);
    }
    for (double v : row)
      if (!std::isfinite(v))
        return make_error(ErrorCode::kCorruptData, "{}:{}: value is not finite", path.string(),
                          line_no);
    t.rows.push_back(std::move(row));
    t.lines.push_back(line_no);
  }
  if (t.rows.empty()) return make_error(ErrorCode::kCorruptData, "{}: no data rows", path.string());
  return t;
}

Result<cv::Mat> read_depth_image(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path))
    return make_error(ErrorCode::kNotFound, "{}: missing depth image", path.string());
  cv::Mat d = cv::imread(path.string(), cv::IMREAD_ANYDEPTH);
  if (d.empty())
    return make_error(ErrorCode::kCorruptData, "{}: unreadable depth image", path.string());
  if (d.channels() != 1 || (d.depth() != CV_16U && d.depth() != CV_32F))
    return make_error(ErrorCode::kUnsupported,
                      "{}: depth must be one channel, 16-bit (mm) or 32-bit float (m)",
                      path.string());
  return d;
}

Result<cv::Vec3d> lift_front_pixel(const cv::Mat& depth, const CameraModel& front,
                                   const cv::Point2d& px) {
  if (depth.size() != front.image_size)
    return make_error(ErrorCode::kInvalidArgument,
                      "depth image is {}x{} but the front colour model is {}x{} (depth must be "
                      "registered to colour)",
                      depth.cols, depth.rows, front.image_size.width, front.image_size.height);
  const int u = static_cast<int>(std::lround(px.x)), v = static_cast<int>(std::lround(px.y));
  if (!std::isfinite(px.x) || !std::isfinite(px.y) || u < 0 || v < 0 || u >= depth.cols ||
      v >= depth.rows)
    return make_error(ErrorCode::kInvalidArgument,
                      "front pixel ({:.1f}, {:.1f}) is outside the "
                      "{}x{} image",
                      px.x, px.y, depth.cols, depth.rows);
  double z = 0;
  if (depth.depth() == CV_16U)
    z = depth.at<uint16_t>(v, u) * 0.001;
  else
    z = static_cast<double>(depth.at<float>(v, u));
  if (!std::isfinite(z) || z <= 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "no depth at front pixel ({:.1f}, {:.1f}) (value {}): click a pixel with "
                      "a valid depth reading",
                      px.x, px.y, z);
  const cv::Vec3d ray = front.pixel_ray(px);
  return front.to_world(ray * (z / ray[2]));
}

Result<Correspondences> make_correspondences(const CsvTable& table, double unit_to_m,
                                             const cv::Mat* depth, const CameraModel* front) {
  Correspondences c;
  if (table.columns == 5) {
    for (const auto& r : table.rows) {
      c.pixels.emplace_back(r[0], r[1]);
      c.world.emplace_back(r[2] * unit_to_m, r[3] * unit_to_m, r[4] * unit_to_m);
    }
    return c;
  }
  if (table.columns != 4)
    return make_error(ErrorCode::kInvalidArgument,
                      "correspondences need 5 (u,v,x,y,z) or 4 (u,v,u_front,v_front) columns, "
                      "got {}",
                      table.columns);
  if (depth == nullptr || front == nullptr)
    return make_error(ErrorCode::kInvalidArgument,
                      "2-D/2-D correspondences (4 columns) need the front depth image and the "
                      "front colour calibration (--depth, --front)");
  c.lifted = true;
  for (size_t i = 0; i < table.rows.size(); ++i) {
    const auto& r = table.rows[i];
    auto X = lift_front_pixel(*depth, *front, {r[2], r[3]});
    if (!X)
      return make_error(ErrorCode::kInvalidArgument, "line {}: {}", table.lines[i],
                        X.error().message);
    c.pixels.emplace_back(r[0], r[1]);
    c.world.emplace_back((*X)[0], (*X)[1], (*X)[2]);
  }
  return c;
}

}  // namespace dreamsense::geometry
