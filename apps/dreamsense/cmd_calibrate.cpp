// `dreamsense calibrate intrinsics|extrinsics|desk|import-dream` and `dreamsense eval calibration`
// (docs/calibration.md). Flags -> geometry options -> library -> files written atomically.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/geometry/calibration_eval.hpp"
#include "dreamsense/geometry/calibration_io.hpp"
#include "dreamsense/geometry/correspondences.hpp"
#include "dreamsense/geometry/dream_import.hpp"
#include "dreamsense/geometry/intrinsics.hpp"
#include "dreamsense/geometry/plane.hpp"
#include "dreamsense/geometry/pnp.hpp"
#include "dreamsense/sim/demo_session.hpp"

#include <algorithm>
#include <cstdio>
#include <regex>

#include "commands.hpp"

namespace dreamsense::app {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace dreamsense::geometry;

json to_json(const cv::Matx33d& m) {
  return json::array({json::array({m(0, 0), m(0, 1), m(0, 2)}),
                      json::array({m(1, 0), m(1, 1), m(1, 2)}),
                      json::array({m(2, 0), m(2, 1), m(2, 2)})});
}
json to_json(const cv::Vec3d& v) { return json::array({v[0], v[1], v[2]}); }
json to_json(const cv::Mat& m) {
  json a = json::array();
  cv::Mat d;
  m.convertTo(d, CV_64F);
  for (int i = 0; i < static_cast<int>(d.total()); ++i) a.push_back(d.at<double>(i));
  return a;
}

Result<cv::Size> parse_size(const std::string& text, const char* what) {
  std::smatch m;
  static const std::regex re(R"(^\s*(\d+)\s*[xX]\s*(\d+)\s*$)");
  if (!std::regex_match(text, m, re))
    return make_error(ErrorCode::kInvalidArgument, "{} '{}': expected WxH, e.g. 9x6", what, text);
  return cv::Size(std::stoi(m[1]), std::stoi(m[2]));
}

// Length with an optional unit: "0.03", "0.03m", "30mm", "3cm" -> metres.
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

Result<double> unit_scale(const std::string& unit) {
  if (unit == "m") return 1.0;
  if (unit == "mm") return 0.001;
  return make_error(ErrorCode::kInvalidArgument, "--unit '{}': expected m or mm", unit);
}

// ---------------------------------------------------------------- calibrate intrinsics
struct IntrinsicsFlags {
  std::vector<std::string> images;
  std::string board = "9x6", square = "0.030", model = "standard5", out, frame, json;
  bool fix_aspect = false;
  double reject_factor = 3.0, reject_min_px = 1.0;
  int min_views = 3;
};

void add_intrinsics(CLI::App& cal, int& exit_code) {
  auto f = std::make_shared<IntrinsicsFlags>();
  CLI::App* cmd = cal.add_subcommand(
      "intrinsics", "Chessboard calibration: K, distortion, image size, RMS (OpenCV YAML)");
  cmd->add_option("images", f->images, "Chessboard images (one camera, one resolution)")
      ->required();
  cmd->add_option("--board", f->board, "Inner corners COLSxROWS")->capture_default_str();
  cmd->add_option("--square", f->square, "Square side: metres, or with a unit (30mm)")
      ->capture_default_str();
  cmd->add_option("--model", f->model,
                  "Distortion model: standard5 (k1 k2 p1 p2 k3) or radial2 (k1 k2, Zhang)")
      ->capture_default_str();
  cmd->add_flag("--fix-aspect", f->fix_aspect, "Constrain fx = fy");
  cmd->add_option("--reject-factor", f->reject_factor,
                  "Reject views whose RMS exceeds this times the median RMS ...")
      ->capture_default_str();
  cmd->add_option("--reject-min-px", f->reject_min_px, "... and this many pixels")
      ->capture_default_str();
  cmd->add_option("--min-views", f->min_views, "Fewest usable views")->capture_default_str();
  cmd->add_option("--frame", f->frame, "Frame name stored in the file (e.g. camera_left)");
  cmd->add_option("--out", f->out, "Output calibration YAML")->required();
  cmd->add_option("--json", f->json, "Also write a JSON report to FILE (- for stdout)");
  cmd->callback([f, &exit_code] {
    IntrinsicsOptions o;
    auto board = parse_size(f->board, "--board");
    if (!board) return void(exit_code = fail(board.error()));
    auto square = parse_length(f->square, "--square");
    if (!square) return void(exit_code = fail(square.error()));
    auto model = parse_distortion_model(f->model);
    if (!model) return void(exit_code = fail(model.error()));
    o.board = *board;
    o.square_size = *square;
    o.model = *model;
    o.fix_aspect_ratio = f->fix_aspect;
    o.reject_factor = f->reject_factor;
    o.reject_min_px = f->reject_min_px;
    o.min_views = f->min_views;
    if (auto s = o.check(); !s) return void(exit_code = fail(s.error()));
    std::vector<fs::path> paths(f->images.begin(), f->images.end());
    auto r = calibrate_from_images(paths, o);
    if (!r) return void(exit_code = fail(r.error()));
    r->camera.frame = f->frame;
    const auto& views = r->views;
    auto s = write_camera_yaml(f->out, r->camera, [&](cv::FileStorage& fs) {
      fs << "rms_px" << r->rms_px;
      fs << "distortion_model" << to_string(o.model);
      fs << "calibration_flags" << r->flags;
      fs << "board_cols" << o.board.width << "board_rows" << o.board.height;
      fs << "square_size_m" << o.square_size;
      fs << "views"
         << "[";
      for (const auto& v : views)
        fs << "{"
           << "file" << v.name << "board_found" << static_cast<int>(v.board_found) << "used"
           << static_cast<int>(v.used) << "rms_px" << v.rms_px << "}";
      fs << "]";
    });
    if (!s) return void(exit_code = fail(s.error()));
    const cv::Matx33d& K = r->camera.K;
    std::fprintf(stderr,
                 "intrinsics: %d of %zu views used, RMS %.3f px, fx %.2f fy %.2f cx %.2f cy "
                 "%.2f -> %s\n",
                 r->views_used, views.size(), r->rms_px, K(0, 0), K(1, 1), K(0, 2), K(1, 2),
                 f->out.c_str());
    json jv = json::array();
    for (const auto& v : views)
      jv.push_back({{"file", v.name},
                    {"board_found", v.board_found},
                    {"used", v.used},
                    {"rms_px", v.rms_px}});
    json j = {{"camera_matrix", to_json(K)},
              {"distortion_coefficients", to_json(r->camera.distortion)},
              {"image_size", {r->camera.image_size.width, r->camera.image_size.height}},
              {"rms_px", r->rms_px},
              {"views_used", r->views_used},
              {"views", jv},
              {"out", f->out}};
    if (auto w = write_json(f->json, j); !w) exit_code = fail(w.error());
  });
}

// ---------------------------------------------------------------- calibrate extrinsics
struct ExtrinsicsFlags {
  std::string intrinsics, points, front, depth, unit = "m", method = "ransac", out, frame, json;
  double threshold = 4.0;
  uint64_t seed = 1;
  int max_iterations = 1000;
  bool compare = false, no_refine = false;
};

json pnp_json(const PnpResult& r, PnpMethod m) {
  json inl = json::array(), err = json::array();
  for (size_t i = 0; i < r.inliers.size(); ++i) {
    inl.push_back(static_cast<bool>(r.inliers[i]));
    err.push_back(std::isfinite(r.errors_px[i]) ? json(r.errors_px[i]) : json(nullptr));
  }
  return {{"method", to_string(m)},
          {"camera_from_world_R", to_json(r.R)},
          {"camera_from_world_t", to_json(r.t)},
          {"camera_centre_world", to_json(r.centre_world())},
          {"inliers", r.inlier_count},
          {"reprojection_rms_px", r.rms_px},
          {"iterations", r.iterations},
          {"inlier_mask", inl},
          {"errors_px", err}};
}

void add_extrinsics(CLI::App& cal, int& exit_code) {
  auto f = std::make_shared<ExtrinsicsFlags>();
  CLI::App* cmd = cal.add_subcommand(
      "extrinsics",
      "camera_from_world from >= 6 (typically ~20) 2-D/3-D or 2-D/front-pixel correspondences "
      "(EPnP + RANSAC + Levenberg-Marquardt)");
  cmd->add_option("--intrinsics", f->intrinsics, "Calibration YAML of the camera (K, distortion)")
      ->required();
  cmd->add_option("--points", f->points,
                  "CSV: u,v,x,y,z (pixel <-> world point) or u,v,u_front,v_front (pixel <-> "
                  "front colour pixel, lifted through --depth)")
      ->required();
  cmd->add_option("--front", f->front, "Front colour calibration YAML (4-column CSV)");
  cmd->add_option("--depth", f->depth,
                  "Front depth image registered to colour: 16-bit mm or 32-bit float m");
  cmd->add_option("--unit", f->unit, "Unit of x,y,z in the CSV: m or mm")->capture_default_str();
  cmd->add_option("--method", f->method,
                  "ransac (ours), seed (DREAM's 60 % down-sampling loop) or all (no outlier "
                  "handling)")
      ->capture_default_str();
  cmd->add_flag("--compare", f->compare, "Also run the other methods and report them in --json");
  cmd->add_option("--threshold", f->threshold, "Inlier reprojection threshold (px)")
      ->capture_default_str();
  cmd->add_option("--max-iterations", f->max_iterations, "RANSAC iteration cap")
      ->capture_default_str();
  cmd->add_flag("--no-refine", f->no_refine, "Skip the Levenberg-Marquardt refinement");
  cmd->add_option("--seed", f->seed, "RNG seed")->capture_default_str();
  cmd->add_option("--frame", f->frame, "Frame name to store (default: the intrinsics file's)");
  cmd->add_option("--out", f->out, "Output calibration YAML (intrinsics + camera_from_world)")
      ->required();
  cmd->add_option("--json", f->json, "Also write a JSON report to FILE (- for stdout)");
  cmd->callback([f, &exit_code] {
    auto cam = read_camera_model(f->intrinsics);
    if (!cam) return void(exit_code = fail(cam.error()));
    auto scale = unit_scale(f->unit);
    if (!scale) return void(exit_code = fail(scale.error()));
    auto method = parse_pnp_method(f->method);
    if (!method) return void(exit_code = fail(method.error()));
    auto table = read_numeric_csv(f->points, {4, 5});
    if (!table) return void(exit_code = fail(table.error()));
    std::optional<CameraModel> front;
    cv::Mat depth;
    if (table->columns == 4) {
      if (f->front.empty() || f->depth.empty())
        return void(exit_code = fail(f->points +
                                     ": 4 columns (u,v,u_front,v_front) need --front and --depth"));
      auto fr = read_camera_model(f->front);
      if (!fr) return void(exit_code = fail(fr.error()));
      front = *fr;
      auto d = read_depth_image(f->depth);
      if (!d) return void(exit_code = fail(d.error()));
      depth = *d;
    }
    auto corr = make_correspondences(*table, *scale, depth.empty() ? nullptr : &depth,
                                     front ? &*front : nullptr);
    if (!corr) return void(exit_code = fail(f->points + ": " + corr.error().message));
    PnpOptions o;
    o.method = *method;
    o.inlier_threshold_px = f->threshold;
    o.max_iterations = f->max_iterations;
    o.refine_lm = !f->no_refine;
    o.seed = f->seed;
    if (auto s = o.check(); !s) return void(exit_code = fail(s.error()));
    auto r = estimate_pose(corr->world, corr->pixels, cam->K, cam->distortion, o);
    if (!r) return void(exit_code = fail(f->points + ": " + r.error().message));
    json others = json::array();
    if (f->compare) {
      for (PnpMethod m :
           {PnpMethod::kRansacEpnp, PnpMethod::kSeedDownsample, PnpMethod::kEpnpAll}) {
        if (m == o.method) continue;
        PnpOptions om = o;
        om.method = m;
        om.require_consensus = false;
        auto rm = estimate_pose(corr->world, corr->pixels, cam->K, cam->distortion, om);
        if (!rm) continue;
        json jm = pnp_json(*rm, m);
        jm["rotation_diff_deg"] = rotation_angle_deg(rm->R, r->R);
        jm["centre_diff_m"] = cv::norm(rm->centre_world() - r->centre_world());
        others.push_back(jm);
      }
    }
    CameraModel out = *cam;
    out.R = r->R;
    out.t = r->t;
    if (!f->frame.empty()) out.frame = f->frame;
    const int n = static_cast<int>(corr->pixels.size());
    auto s = write_camera_yaml(f->out, out, [&](cv::FileStorage& fs) {
      fs << "world_frame"
         << "world";
      fs << "extrinsics_method" << to_string(o.method);
      fs << "correspondences" << n << "inliers" << r->inlier_count;
      fs << "inlier_threshold_px" << o.inlier_threshold_px;
      fs << "reprojection_rms_px" << r->rms_px;
      fs << "correspondence_file" << f->points;
    });
    if (!s) return void(exit_code = fail(s.error()));
    const cv::Vec3d c = r->centre_world();
    std::fprintf(stderr,
                 "extrinsics (%s): %d of %d inliers, RMS %.2f px, camera centre in world (%.3f, "
                 "%.3f, %.3f) m -> %s\n",
                 to_string(o.method), r->inlier_count, n, r->rms_px, c[0], c[1], c[2],
                 f->out.c_str());
    json j = pnp_json(*r, o.method);
    j["correspondences"] = n;
    j["lifted_through_depth"] = corr->lifted;
    j["convention"] = "camera_from_world: X_cam = R * X_world + t (metres)";
    j["compared"] = others;
    j["out"] = f->out;
    if (auto w = write_json(f->json, j); !w) exit_code = fail(w.error());
  });
}

// ---------------------------------------------------------------- calibrate desk
struct DeskFlags {
  std::string points, front, depth, unit = "m", out, json;
};

void add_desk(CLI::App& cal, int& exit_code) {
  auto f = std::make_shared<DeskFlags>();
  CLI::App* cmd = cal.add_subcommand(
      "desk", "Table plane and table frame from three (or more) points on the table top");
  cmd->add_option("--points", f->points,
                  "CSV: x,y,z world points, or u_front,v_front pixels lifted through --depth")
      ->required();
  cmd->add_option("--front", f->front, "Front colour calibration YAML (2-column CSV)");
  cmd->add_option("--depth", f->depth, "Front depth image registered to colour (2-column CSV)");
  cmd->add_option("--unit", f->unit, "Unit of x,y,z in the CSV: m or mm")->capture_default_str();
  cmd->add_option("--out", f->out, "Output table YAML")->required();
  cmd->add_option("--json", f->json, "Also write a JSON report to FILE (- for stdout)");
  cmd->callback([f, &exit_code] {
    auto scale = unit_scale(f->unit);
    if (!scale) return void(exit_code = fail(scale.error()));
    auto table = read_numeric_csv(f->points, {2, 3});
    if (!table) return void(exit_code = fail(table.error()));
    std::vector<cv::Vec3d> pts;
    if (table->columns == 2) {
      if (f->front.empty() || f->depth.empty())
        return void(exit_code = fail(f->points + ": 2 columns (u,v) need --front and --depth"));
      auto front = read_camera_model(f->front);
      if (!front) return void(exit_code = fail(front.error()));
      auto depth = read_depth_image(f->depth);
      if (!depth) return void(exit_code = fail(depth.error()));
      for (size_t i = 0; i < table->rows.size(); ++i) {
        auto X = lift_front_pixel(*depth, *front, {table->rows[i][0], table->rows[i][1]});
        if (!X)
          return void(exit_code = fail(
                          fmt::format("{}:{}: {}", f->points, table->lines[i], X.error().message)));
        pts.push_back(*X);
      }
    } else {
      for (const auto& r : table->rows)
        pts.emplace_back(r[0] * *scale, r[1] * *scale, r[2] * *scale);
    }
    auto tf = table_frame_from_points(pts);
    if (!tf) return void(exit_code = fail(f->points + ": " + tf.error().message));
    if (auto s = write_table_frame(f->out, *tf); !s) return void(exit_code = fail(s.error()));
    double worst = 0;
    for (const auto& p : pts) worst = std::max(worst, tf->plane.distance(p));
    std::fprintf(stderr,
                 "desk: normal (%.3f, %.3f, %.3f), sensor %.3f m above the table, %zu points "
                 "(max off-plane %.4f m) -> %s\n",
                 tf->plane.normal[0], tf->plane.normal[1], tf->plane.normal[2],
                 tf->height({0, 0, 0}), pts.size(), worst, f->out.c_str());
    json j = {{"plane_normal", to_json(tf->plane.normal)},
              {"plane_offset", tf->plane.offset},
              {"world_from_table_R", to_json(tf->world_from_table.R)},
              {"world_from_table_t", to_json(tf->world_from_table.t)},
              {"world_origin_height_m", tf->height({0, 0, 0})},
              {"max_point_plane_distance_m", worst},
              {"out", f->out}};
    if (auto w = write_json(f->json, j); !w) exit_code = fail(w.error());
  });
}

// ---------------------------------------------------------------- calibrate import-dream
struct ImportFlags {
  std::string intrinsics, extrinsics, object_file, image_size, frame, out, json;
};

void add_import(CLI::App& cal, int& exit_code) {
  auto f = std::make_shared<ImportFlags>();
  CLI::App* cmd = cal.add_subcommand(
      "import-dream",
      "Convert DREAM's *KMatDMat.xml / *RMatTMat.xml (and read ObjectFile.xml), warning about "
      "each known defect");
  cmd->add_option("--intrinsics", f->intrinsics, "DREAM *KMatDMat.xml");
  cmd->add_option("--extrinsics", f->extrinsics, "DREAM *RMatTMat.xml (mm, camera_from_world)");
  cmd->add_option("--object-file", f->object_file, "DREAM ObjectFile.xml (report only)");
  cmd->add_option("--image-size", f->image_size, "WxH of the camera's images (e.g. 1280x960)");
  cmd->add_option("--frame", f->frame, "Frame name to store (e.g. camera_left)");
  cmd->add_option("--out", f->out, "Output calibration YAML (needs --intrinsics, --image-size)");
  cmd->add_option("--json", f->json, "Write a JSON report with the warnings (- for stdout)");
  cmd->callback([f, &exit_code] {
    if (f->intrinsics.empty() && f->extrinsics.empty() && f->object_file.empty())
      return void(exit_code =
                      fail("import-dream: give --intrinsics, --extrinsics or --object-file"));
    if (!f->out.empty() && (f->intrinsics.empty() || f->image_size.empty()))
      return void(exit_code = fail("import-dream: --out needs --intrinsics and --image-size"));
    std::optional<cv::Size> size;
    if (!f->image_size.empty()) {
      auto s = parse_size(f->image_size, "--image-size");
      if (!s) return void(exit_code = fail(s.error()));
      size = *s;
    }
    json j = json::object();
    CameraModel cam;
    cam.frame = f->frame;
    if (size) cam.image_size = *size;
    if (!f->intrinsics.empty()) {
      auto k = read_dream_intrinsics(f->intrinsics, size);
      if (!k) return void(exit_code = fail(k.error()));
      cam.K = k->K;
      cam.distortion = k->distortion;
      j["intrinsics"] = {{"camera_matrix", to_json(k->K)},
                         {"distortion_coefficients", to_json(k->distortion)},
                         {"warnings", k->warnings}};
    }
    if (!f->extrinsics.empty()) {
      auto e = read_dream_extrinsics(f->extrinsics);
      if (!e) return void(exit_code = fail(e.error()));
      cam.R = e->camera_from_world.R;
      cam.t = e->camera_from_world.t;
      j["extrinsics"] = {{"camera_from_world_R", to_json(e->camera_from_world.R)},
                         {"camera_from_world_t_m", to_json(e->camera_from_world.t)},
                         {"camera_centre_world_m", to_json(e->camera_from_world.inverse().t)},
                         {"orthonormality_error", e->orthonormality_error},
                         {"warnings", e->warnings}};
    }
    if (!f->object_file.empty()) {
      auto o = read_dream_object_file(f->object_file);
      if (!o) return void(exit_code = fail(o.error()));
      json jo = {{"desk_from_world_R", to_json(o->desk_from_world.R)},
                 {"desk_from_world_t_m", to_json(o->desk_from_world.t)},
                 {"warnings", o->warnings},
                 {"frame_note", "DREAM's Kinect0-centred frame (y up, z towards the child), m"}};
      jo["point_c_m"] = o->point_c_m ? to_json(*o->point_c_m) : json(nullptr);
      jo["robot_head_m"] = o->robot_head_m ? to_json(*o->robot_head_m) : json(nullptr);
      jo["gaze_radius_m"] = o->gaze_radius_m ? json(*o->gaze_radius_m) : json(nullptr);
      j["object_file"] = jo;
    }
    if (!f->out.empty()) {
      if (auto s = cam.check(); !s) return void(exit_code = fail(s.error()));
      auto s = write_camera_yaml(f->out, cam, [&](cv::FileStorage& fs) {
        fs << "imported_from"
           << (f->intrinsics + (f->extrinsics.empty() ? "" : " " + f->extrinsics));
      });
      if (!s) return void(exit_code = fail(s.error()));
      std::fprintf(stderr, "import-dream: -> %s\n", f->out.c_str());
    }
    if (auto w = write_json(f->json, j); !w) exit_code = fail(w.error());
  });
}

// ---------------------------------------------------------------- eval calibration
struct EvalFlags {
  std::vector<std::string> dataset;
  std::string json;
  uint64_t seed = 1;
  int points = 20;
  double noise_px = 1.0, outliers = 0.2;
};

json eval_zhang(const ZhangDataset& d, const ZhangEval& e) {
  json per = json::object();
  for (const auto& v : e.views)
    per[v.name] = {{"rms_px", v.rms_px},
                   {"published_rms_px", v.published_rms_px},
                   {"rot_err_deg", v.rot_err_deg},
                   {"trans_rel_err", v.trans_rel_err}};
  const auto& c = e.calibration.camera;
  return {{"task", "calibration"},
          {"dataset", {{"name", "zhang"}, {"items", d.views.size()}}},
          {"protocol",
           "intrinsics from Zhang's published corners (dataN.txt) and model points (Model.txt) "
           "with cv::calibrateCamera, k1 k2 only (CALIB_ZERO_TANGENT_DIST | CALIB_FIX_K3, no "
           "skew), compared with completecalibration.txt; rms_px over all points"},
          {"metrics",
           {{"rms_px", e.rms_px},
            {"fx_rel_err", e.fx_rel_err},
            {"rot_err_deg_max", e.rot_err_deg_max},
            {"trans_rel_err_max", e.trans_rel_err_max},
            {"fy_rel_err", e.fy_rel_err},
            {"cx_err_px", e.cx_err_px},
            {"cy_err_px", e.cy_err_px},
            {"published_rms_px", e.published_rms_px}}},
          {"timing", {{"seconds", e.seconds}}},
          {"per_class", per},
          {"estimate",
           {{"camera_matrix", to_json(c.K)}, {"distortion_coefficients", to_json(c.distortion)}}},
          {"published",
           {{"alpha", d.alpha},
            {"gamma", d.gamma},
            {"beta", d.beta},
            {"u0", d.u0},
            {"v0", d.v0},
            {"k1", d.k1},
            {"k2", d.k2}}}};
}

Result<std::vector<CameraModel>> session_cameras(const fs::path& session) {
  const fs::path dir = session / "calib";
  if (!fs::is_directory(dir))
    return make_error(ErrorCode::kNotFound, "{}: no calib/ folder (not a session?)",
                      session.string());
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".yaml" && e.path().stem() != "mic_array")
      files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<CameraModel> cams;
  for (const auto& p : files) {
    auto m = read_camera_model(p);
    if (!m) return tl::unexpected(m.error());
    if (m->frame.empty()) m->frame = p.stem().string();
    cams.push_back(*m);
  }
  if (cams.empty())
    return make_error(ErrorCode::kNotFound, "{}: no camera calibration files", dir.string());
  return cams;
}

}  // namespace

void add_calibrate(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  (void)g;
  CLI::App* cal = app.add_subcommand(
      "calibrate", "Camera calibration: intrinsics, extrinsics, desk plane, DREAM import");
  cal->require_subcommand(1);
  add_intrinsics(*cal, exit_code);
  add_extrinsics(*cal, exit_code);
  add_desk(*cal, exit_code);
  add_import(*cal, exit_code);
}

void add_eval_calibration(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto f = std::make_shared<EvalFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "calibration",
      "zhang DIR: intrinsics vs Zhang's published calibration; demo [SESSION]: extrinsics of "
      "the demo cameras from seeded synthetic correspondences vs truth");
  cmd->add_option("--dataset", f->dataset, "zhang DIR | demo [SESSION] (default: built-in demo)")
      ->required()
      ->expected(1, 2);
  cmd->add_option("--json", f->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->add_option("--seed", f->seed, "demo: RNG seed")->capture_default_str();
  cmd->add_option("--points", f->points, "demo: correspondences per camera")->capture_default_str();
  cmd->add_option("--noise", f->noise_px, "demo: pixel noise sigma")->capture_default_str();
  cmd->add_option("--outliers", f->outliers, "demo: outlier fraction [0, 0.5]")
      ->capture_default_str();
  cmd->callback([f, &g, &exit_code] {
    const std::string name = f->dataset.front();
    if (name == "zhang") {
      if (f->dataset.size() < 2) return void(exit_code = fail("--dataset zhang needs DIR"));
      auto d = read_zhang_dataset(f->dataset[1]);
      if (!d) return void(exit_code = fail(d.error()));
      auto e = evaluate_zhang(*d);
      if (!e) return void(exit_code = fail(e.error()));
      const json j = eval_zhang(*d, *e);
      if (!g.quiet)
        for (const auto& [k, v] : j["metrics"].items())
          std::fprintf(stderr, "  %-20s %s\n", k.c_str(), v.dump().c_str());
      if (auto w = write_json(f->json, j); !w) exit_code = fail(w.error());
      return;
    }
    if (name != "demo")
      return void(exit_code = fail("--dataset '" + name + "': expected zhang or demo"));
    if (!(f->outliers >= 0 && f->outliers <= 0.5) || f->points < 6 || !(f->noise_px >= 0))
      return void(exit_code = fail("demo: --points >= 6, --noise >= 0, --outliers in [0, 0.5]"));
    std::vector<CameraModel> cams;
    std::string source = "built-in demo cameras (make_demo_cameras)";
    if (f->dataset.size() > 1) {
      auto c = session_cameras(f->dataset[1]);
      if (!c) return void(exit_code = fail(c.error()));
      cams = *c;
      source = f->dataset[1];
    } else {
      cams = sim::make_demo_cameras();
    }
    ExtrinsicsEvalOptions o;
    o.synthetic.points = f->points;
    o.synthetic.noise_px = f->noise_px;
    o.synthetic.outlier_fraction = f->outliers;
    o.synthetic.seed = f->seed;
    o.pnp.seed = f->seed;
    auto r = evaluate_extrinsics_synthetic(cams, o);
    if (!r) return void(exit_code = fail(r.error()));
    double rot_max = 0, trans_rel_max = 0, trans_max = 0, centre_max = 0, rms_sq = 0;
    std::vector<double> ms;
    json per = json::object();
    for (const auto& c : *r) {
      rot_max = std::max(rot_max, c.rot_err_deg);
      trans_rel_max = std::max(trans_rel_max, c.trans_rel_err);
      trans_max = std::max(trans_max, c.trans_err_m);
      centre_max = std::max(centre_max, c.centre_err_m);
      rms_sq += c.rms_px * c.rms_px;
      ms.push_back(c.ms);
      per[c.frame] = {{"rot_err_deg", c.rot_err_deg},
                      {"trans_err_m", c.trans_err_m},
                      {"trans_rel_err", c.trans_rel_err},
                      {"centre_err_m", c.centre_err_m},
                      {"points", c.points},
                      {"outliers_injected", c.outliers_injected},
                      {"outliers_rejected", c.true_outliers_rejected},
                      {"inliers", c.inliers},
                      {"rms_px", c.rms_px},
                      {"ms", c.ms}};
    }
    std::sort(ms.begin(), ms.end());
    json j = {
        {"task", "calibration"},
        {"dataset", {{"name", "demo"}, {"items", r->size()}, {"source", source}}},
        {"protocol",
         fmt::format("per camera: {} points seen by the true model (depth 0.8-3 m), {} px "
                     "noise, {:.0f} % outliers (seed {}); extrinsics by EPnP+RANSAC+LM with the "
                     "true intrinsics; compared with the true camera_from_world. fx_rel_err is "
                     "null: intrinsics are not estimated. trans_rel_err skips cameras at the "
                     "world origin",
                     f->points, f->noise_px, 100 * f->outliers, f->seed)},
        {"metrics",
         {{"rms_px", std::sqrt(rms_sq / static_cast<double>(r->size()))},
          {"fx_rel_err", nullptr},
          {"rot_err_deg_max", rot_max},
          {"trans_rel_err_max", trans_rel_max},
          {"trans_err_m_max", trans_max},
          {"centre_err_m_max", centre_max}}},
        {"timing", {{"ms_per_camera_median", ms[ms.size() / 2]}}},
        {"per_class", per}};
    if (!g.quiet)
      for (const auto& [k, v] : j["metrics"].items())
        std::fprintf(stderr, "  %-20s %s\n", k.c_str(), v.dump().c_str());
    if (auto w = write_json(f->json, j); !w) exit_code = fail(w.error());
  });
}

}  // namespace dreamsense::app
