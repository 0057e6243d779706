#include "dreamsense/geometry/calibration_tasks.hpp"

#include "dreamsense/geometry/calibration_io.hpp"
#include "dreamsense/geometry/correspondences.hpp"
#include "dreamsense/geometry/transform.hpp"

#include <algorithm>
#include <optional>
#include <regex>

namespace dreamsense::geometry {
namespace fs = std::filesystem;

Result<cv::Size> parse_board_size(const std::string& text, const char* what) {
  std::smatch m;
  static const std::regex re(R"(^\s*(\d+)\s*[xX]\s*(\d+)\s*$)");
  if (!std::regex_match(text, m, re))
    return make_error(ErrorCode::kInvalidArgument, "{} '{}': expected WxH, e.g. 9x6", what, text);
  return cv::Size(std::stoi(m[1]), std::stoi(m[2]));
}

Result<double> parse_length(const std::string& text, const char* what) {
  std::smatch m;
  static const std::regex re(R"(^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(mm|cm|m)?\s*$)");
  if (!std::regex_match(text, m, re))
    return make_error(ErrorCode::kInvalidArgument, "{} '{}': expected a length like 0.03 or 30mm",
                      what, text);
  double v = std::stod(m[1]);
  if (m[2] == "mm") v *= 0.001;
  if (m[2] == "cm") v *= 0.01;
  if (!(v > 0)) return make_error(ErrorCode::kInvalidArgument, "{} must be > 0", what);
  return v;
}

Result<double> parse_unit_scale(const std::string& unit) {
  if (unit == "m") return 1.0;
  if (unit == "mm") return 0.001;
  return make_error(ErrorCode::kInvalidArgument, "--unit '{}': expected m or mm", unit);
}

Status write_intrinsics_yaml(const fs::path& path, const IntrinsicsResult& r,
                             const IntrinsicsOptions& o) {
  return write_camera_yaml(path, r.camera, [&](cv::FileStorage& fs) {
    fs << "rms_px" << r.rms_px;
    fs << "distortion_model" << to_string(o.model);
    fs << "calibration_flags" << r.flags;
    fs << "board_cols" << o.board.width << "board_rows" << o.board.height;
    fs << "square_size_m" << o.square_size;
    fs << "views"
       << "[";
    for (const auto& v : r.views)
      fs << "{"
         << "file" << v.name << "board_found" << static_cast<int>(v.board_found) << "used"
         << static_cast<int>(v.used) << "rms_px" << v.rms_px << "}";
    fs << "]";
  });
}

Result<ExtrinsicsCalibration> calibrate_extrinsics(const ExtrinsicsRequest& q) {
  DS_ASSIGN_OR_RETURN(CameraModel cam, read_camera_model(q.intrinsics));
  DS_ASSIGN_OR_RETURN(const CsvTable table, read_numeric_csv(q.points, {4, 5}));
  std::optional<CameraModel> front;
  cv::Mat depth;
  if (table.columns == 4) {
    if (q.front.empty() || q.depth.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: 4 columns (u,v,u_front,v_front) need --front and --depth",
                        q.points.string());
    DS_ASSIGN_OR_RETURN(front, read_camera_model(q.front));
    DS_ASSIGN_OR_RETURN(depth, read_depth_image(q.depth));
  }
  auto corr = make_correspondences(table, q.unit_to_m, depth.empty() ? nullptr : &depth,
                                   front ? &*front : nullptr);
  if (!corr)
    return make_error(corr.error().code, "{}: {}", q.points.string(), corr.error().message);
  DS_RETURN_IF_ERROR(q.pnp.check());
  auto r = estimate_pose(corr->world, corr->pixels, cam.K, cam.distortion, q.pnp);
  if (!r) return make_error(r.error().code, "{}: {}", q.points.string(), r.error().message);
  ExtrinsicsCalibration c;
  c.pose = *r;
  c.correspondences = static_cast<int>(corr->pixels.size());
  c.lifted = corr->lifted;
  if (q.compare) {
    for (PnpMethod m : {PnpMethod::kRansacEpnp, PnpMethod::kSeedDownsample, PnpMethod::kEpnpAll}) {
      if (m == q.pnp.method) continue;
      PnpOptions om = q.pnp;
      om.method = m;
      om.require_consensus = false;
      auto rm = estimate_pose(corr->world, corr->pixels, cam.K, cam.distortion, om);
      if (!rm) continue;
      c.compared.push_back({m, *rm, rotation_angle_deg(rm->R, r->R),
                            cv::norm(rm->centre_world() - r->centre_world())});
    }
  }
  c.camera = cam;
  c.camera.R = r->R;
  c.camera.t = r->t;
  if (!q.frame.empty()) c.camera.frame = q.frame;
  return c;
}

Status write_extrinsics_yaml(const fs::path& path, const ExtrinsicsCalibration& c,
                             const ExtrinsicsRequest& q) {
  return write_camera_yaml(path, c.camera, [&](cv::FileStorage& fs) {
    fs << "world_frame"
       << "world";
    fs << "extrinsics_method" << to_string(q.pnp.method);
    fs << "correspondences" << c.correspondences << "inliers" << c.pose.inlier_count;
    fs << "inlier_threshold_px" << q.pnp.inlier_threshold_px;
    fs << "reprojection_rms_px" << c.pose.rms_px;
    fs << "correspondence_file" << q.points.string();
  });
}

Result<DeskCalibration> calibrate_desk(const DeskRequest& q) {
  DS_ASSIGN_OR_RETURN(const CsvTable table, read_numeric_csv(q.points, {2, 3}));
  DeskCalibration d;
  if (table.columns == 2) {
    if (q.front.empty() || q.depth.empty())
      return make_error(ErrorCode::kInvalidArgument, "{}: 2 columns (u,v) need --front and --depth",
                        q.points.string());
    DS_ASSIGN_OR_RETURN(const CameraModel front, read_camera_model(q.front));
    DS_ASSIGN_OR_RETURN(const cv::Mat depth, read_depth_image(q.depth));
    for (size_t i = 0; i < table.rows.size(); ++i) {
      auto X = lift_front_pixel(depth, front, {table.rows[i][0], table.rows[i][1]});
      if (!X)
        return make_error(X.error().code, "{}:{}: {}", q.points.string(), table.lines[i],
                          X.error().message);
      d.points.push_back(*X);
    }
  } else {
    for (const auto& r : table.rows)
      d.points.emplace_back(r[0] * q.unit_to_m, r[1] * q.unit_to_m, r[2] * q.unit_to_m);
  }
  auto tf = table_frame_from_points(d.points);
  if (!tf) return make_error(tf.error().code, "{}: {}", q.points.string(), tf.error().message);
  d.table = *tf;
  for (const auto& p : d.points)
    d.max_point_plane_distance_m = std::max(d.max_point_plane_distance_m, tf->plane.distance(p));
  return d;
}

}  // namespace dreamsense::geometry
