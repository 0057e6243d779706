// `dreamsense calibrate intrinsics|extrinsics|desk|import-dream` and `dreamsense eval calibration`
// (docs/calibration.md). Flags -> geometry options -> library -> files written atomically.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/eval/calibration_eval.hpp"
#include "dreamsense/geometry/calibration_io.hpp"
#include "dreamsense/geometry/calibration_tasks.hpp"
#include "dreamsense/geometry/correspondences.hpp"
#include "dreamsense/geometry/dream_import.hpp"
#include "dreamsense/geometry/intrinsics.hpp"
#include "dreamsense/geometry/plane.hpp"
#include "dreamsense/geometry/pnp.hpp"

#include <algorithm>
#include <cstdio>

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
    auto board = parse_board_size(f->board, "--board");
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
    if (auto s = write_intrinsics_yaml(f->out, *r, o); !s) return void(exit_code = fail(s.error()));
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
    ExtrinsicsRequest q;
    q.intrinsics = f->intrinsics;
    q.points = f->points;
    q.front = f->front;
    q.depth = f->depth;
    auto scale = parse_unit_scale(f->unit);
    if (!scale) return void(exit_code = fail(scale.error()));
    q.unit_to_m = *scale;
    auto method = parse_pnp_method(f->method);
    if (!method) return void(exit_code = fail(method.error()));
    q.pnp.method = *method;
    q.pnp.inlier_threshold_px = f->threshold;
    q.pnp.max_iterations = f->max_iterations;
    q.pnp.refine_lm = !f->no_refine;
    q.pnp.seed = f->seed;
    q.compare = f->compare;
    q.frame = f->frame;
    auto c = calibrate_extrinsics(q);
    if (!c) return void(exit_code = fail(c.error()));
    if (auto s = write_extrinsics_yaml(f->out, *c, q); !s) return void(exit_code = fail(s.error()));
    const PnpResult& r = c->pose;
    const cv::Vec3d centre = r.centre_world();
    std::fprintf(stderr,
                 "extrinsics (%s): %d of %d inliers, RMS %.2f px, camera centre in world (%.3f, "
                 "%.3f, %.3f) m -> %s\n",
                 to_string(q.pnp.method), r.inlier_count, c->correspondences, r.rms_px, centre[0],
                 centre[1], centre[2], f->out.c_str());
    json others = json::array();
    for (const auto& m : c->compared) {
      json jm = pnp_json(m.pose, m.method);
      jm["rotation_diff_deg"] = m.rotation_diff_deg;
      jm["centre_diff_m"] = m.centre_diff_m;
      others.push_back(jm);
    }
    json j = pnp_json(r, q.pnp.method);
    j["correspondences"] = c->correspondences;
    j["lifted_through_depth"] = c->lifted;
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
    DeskRequest q;
    q.points = f->points;
    q.front = f->front;
    q.depth = f->depth;
    auto scale = parse_unit_scale(f->unit);
    if (!scale) return void(exit_code = fail(scale.error()));
    q.unit_to_m = *scale;
    auto d = calibrate_desk(q);
    if (!d) return void(exit_code = fail(d.error()));
    const TableFrame* tf = &d->table;
    const auto& pts = d->points;
    const double worst = d->max_point_plane_distance_m;
    if (auto s = write_table_frame(f->out, *tf); !s) return void(exit_code = fail(s.error()));
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
      auto s = parse_board_size(f->image_size, "--image-size");
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
    Result<eval::EvalReport> r;
    if (name == "zhang") {
      if (f->dataset.size() < 2) return void(exit_code = fail("--dataset zhang needs DIR"));
      r = eval::run_zhang_calibration_eval(f->dataset[1]);
    } else if (name == "demo") {
      eval::DemoExtrinsicsEvalOptions o;
      if (f->dataset.size() > 1) o.session = f->dataset[1];
      o.points = f->points;
      o.noise_px = f->noise_px;
      o.outliers = f->outliers;
      o.seed = f->seed;
      r = eval::run_demo_extrinsics_eval(o);
    } else {
      return void(exit_code = fail("--dataset '" + name + "': expected zhang or demo"));
    }
    if (!r) return void(exit_code = fail(r.error()));
    if (!g.quiet)
      for (const auto& [k, v] : r->metrics.items())
        std::fprintf(stderr, "  %-20s %s\n", k.c_str(), v.dump().c_str());
    if (auto w = eval::write_report(*r, f->json); !w) exit_code = fail(w.error());
  });
}

}  // namespace dreamsense::app
