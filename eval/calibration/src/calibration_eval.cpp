#include "dreamsense/eval/calibration_eval.hpp"

#include "dreamsense/geometry/calibration_eval.hpp"
#include "dreamsense/geometry/calibration_io.hpp"
#include "dreamsense/sim/demo_session.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::eval {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json to_json(const cv::Matx33d& m) {
  json j = json::array();
  for (int r = 0; r < 3; ++r) j.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return j;
}
json to_json(const cv::Mat& m) {
  json j = json::array();
  cv::Mat d;
  m.convertTo(d, CV_64F);
  for (int i = 0; i < static_cast<int>(d.total()); ++i) j.push_back(d.at<double>(i));
  return j;
}

}  // namespace

Result<EvalReport> run_zhang_calibration_eval(const fs::path& dir) {
  DS_ASSIGN_OR_RETURN(const geometry::ZhangDataset d, geometry::read_zhang_dataset(dir));
  DS_ASSIGN_OR_RETURN(const geometry::ZhangEval e, geometry::evaluate_zhang(d));
  EvalReport r;
  r.task = "calibration";
  r.dataset = "zhang";
  r.items = d.views.size();
  r.protocol =
      "intrinsics from Zhang's published corners (dataN.txt) and model points (Model.txt) with "
      "cv::calibrateCamera, k1 k2 only (CALIB_ZERO_TANGENT_DIST | CALIB_FIX_K3, no skew), "
      "compared with completecalibration.txt; rms_px over all points";
  r.metrics = {{"rms_px", e.rms_px},
               {"fx_rel_err", e.fx_rel_err},
               {"rot_err_deg_max", e.rot_err_deg_max},
               {"trans_rel_err_max", e.trans_rel_err_max},
               {"fy_rel_err", e.fy_rel_err},
               {"cx_err_px", e.cx_err_px},
               {"cy_err_px", e.cy_err_px},
               {"published_rms_px", e.published_rms_px}};
  r.timing = {{"seconds", e.seconds}};
  for (const auto& v : e.views)
    r.per_class[v.name] = {{"rms_px", v.rms_px},
                           {"published_rms_px", v.published_rms_px},
                           {"rot_err_deg", v.rot_err_deg},
                           {"trans_rel_err", v.trans_rel_err}};
  const auto& c = e.calibration.camera;
  r.extra["estimate"] = {{"camera_matrix", to_json(c.K)},
                         {"distortion_coefficients", to_json(c.distortion)}};
  r.extra["published"] = {{"alpha", d.alpha}, {"gamma", d.gamma}, {"beta", d.beta}, {"u0", d.u0},
                          {"v0", d.v0},       {"k1", d.k1},       {"k2", d.k2}};
  return r;
}

Status DemoExtrinsicsEvalOptions::check() const {
  if (!(outliers >= 0 && outliers <= 0.5) || points < 6 || !(noise_px >= 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "demo: --points >= 6, --noise >= 0, --outliers in [0, 0.5]");
  return ok_status();
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
    DS_ASSIGN_OR_RETURN(CameraModel m, read_camera_model(p));
    if (m.frame.empty()) m.frame = p.stem().string();
    cams.push_back(m);
  }
  if (cams.empty())
    return make_error(ErrorCode::kNotFound, "{}: no camera calibration files", dir.string());
  return cams;
}

Result<EvalReport> run_demo_extrinsics_eval(const DemoExtrinsicsEvalOptions& o) {
  DS_RETURN_IF_ERROR(o.check());
  std::vector<CameraModel> cams;
  std::string source = "built-in demo cameras (make_demo_cameras)";
  if (!o.session.empty()) {
    DS_ASSIGN_OR_RETURN(cams, session_cameras(o.session));
    source = o.session.string();
  } else {
    cams = sim::make_demo_cameras();
  }
  geometry::ExtrinsicsEvalOptions eo;
  eo.synthetic.points = o.points;
  eo.synthetic.noise_px = o.noise_px;
  eo.synthetic.outlier_fraction = o.outliers;
  eo.synthetic.seed = o.seed;
  eo.pnp.seed = o.seed;
  DS_ASSIGN_OR_RETURN(const auto cameras, geometry::evaluate_extrinsics_synthetic(cams, eo));
  double rot_max = 0, trans_rel_max = 0, trans_max = 0, centre_max = 0, rms_sq = 0;
  std::vector<double> ms;
  EvalReport r;
  for (const auto& c : cameras) {
    rot_max = std::max(rot_max, c.rot_err_deg);
    trans_rel_max = std::max(trans_rel_max, c.trans_rel_err);
    trans_max = std::max(trans_max, c.trans_err_m);
    centre_max = std::max(centre_max, c.centre_err_m);
    rms_sq += c.rms_px * c.rms_px;
    ms.push_back(c.ms);
    r.per_class[c.frame] = {{"rot_err_deg", c.rot_err_deg},
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
  if (cameras.empty()) return make_error(ErrorCode::kNotFound, "demo: no cameras to evaluate");
  std::sort(ms.begin(), ms.end());
  r.task = "calibration";
  r.dataset = "demo";
  r.items = cameras.size();
  r.extra["dataset_source"] = source;
  r.protocol = fmt::format(
      "per camera: {} points seen by the true model (depth 0.8-3 m), {} px noise, {:.0f} % "
      "outliers (seed {}); extrinsics by EPnP+RANSAC+LM with the true intrinsics; compared with "
      "the true camera_from_world. fx_rel_err is null: intrinsics are not estimated. "
      "trans_rel_err skips cameras at the world origin",
      o.points, o.noise_px, 100 * o.outliers, o.seed);
  r.metrics = {{"rms_px", std::sqrt(rms_sq / static_cast<double>(cameras.size()))},
               {"fx_rel_err", nullptr},
               {"rot_err_deg_max", rot_max},
               {"trans_rel_err_max", trans_rel_max},
               {"trans_err_m_max", trans_max},
               {"centre_err_m_max", centre_max}};
  r.timing = {{"ms_per_camera_median", ms[ms.size() / 2]}};
  return r;
}

}  // namespace dreamsense::eval
