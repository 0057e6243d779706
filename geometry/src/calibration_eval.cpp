#include "dreamsense/geometry/calibration_eval.hpp"

#include "dreamsense/geometry/transform.hpp"

#include <chrono>
#include <cmath>
#include <fstream>

namespace dreamsense::geometry {

namespace {

Result<std::vector<double>> read_numbers(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: missing (zhang dataset)", path.string());
  std::vector<double> v;
  std::string tok;
  while (in >> tok) {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (end != tok.c_str() + tok.size())
      return make_error(ErrorCode::kCorruptData, "{}: not a number: '{}'", path.string(), tok);
    v.push_back(x);
  }
  return v;
}

// Zhang's projection: radial distortion on ideal normalised coordinates, then the affine K with
// skew gamma.
cv::Point2d zhang_project(const ZhangDataset& d, const cv::Matx33d& R, const cv::Vec3d& t,
                          const cv::Point3f& X) {
  const cv::Vec3d c = R * cv::Vec3d(X.x, X.y, X.z) + t;
  const double x = c[0] / c[2], y = c[1] / c[2], r2 = x * x + y * y;
  const double s = 1 + d.k1 * r2 + d.k2 * r2 * r2;
  const double xd = x * s, yd = y * s;
  return {d.alpha * xd + d.gamma * yd + d.u0, d.beta * yd + d.v0};
}

}  // namespace

Result<ZhangDataset> read_zhang_dataset(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir))
    return make_error(ErrorCode::kNotFound, "{}: not a folder (zhang dataset)", dir.string());
  ZhangDataset d;
  auto model = read_numbers(dir / "Model.txt");
  if (!model) return tl::unexpected(model.error());
  if (model->size() < 8 || model->size() % 2 != 0)
    return make_error(ErrorCode::kCorruptData, "{}: expected pairs of numbers",
                      (dir / "Model.txt").string());
  for (size_t i = 0; i + 1 < model->size(); i += 2)
    d.model.emplace_back(static_cast<float>((*model)[i]), static_cast<float>((*model)[i + 1]), 0.f);
  for (int k = 1; fs::exists(dir / fmt::format("data{}.txt", k)); ++k) {
    auto v = read_numbers(dir / fmt::format("data{}.txt", k));
    if (!v) return tl::unexpected(v.error());
    if (v->size() != model->size())
      return make_error(ErrorCode::kCorruptData, "{}: {} numbers, Model.txt has {}",
                        (dir / fmt::format("data{}.txt", k)).string(), v->size(), model->size());
    std::vector<cv::Point2f> pts;
    for (size_t i = 0; i + 1 < v->size(); i += 2)
      pts.emplace_back(static_cast<float>((*v)[i]), static_cast<float>((*v)[i + 1]));
    d.views.push_back(std::move(pts));
  }
  if (d.views.size() < 2)
    return make_error(ErrorCode::kNotFound, "{}: needs data1.txt, data2.txt, ... (found {})",
                      dir.string(), d.views.size());
  auto c = read_numbers(dir / "completecalibration.txt");
  if (!c) return tl::unexpected(c.error());
  if (c->size() != 7 + 12 * d.views.size())
    return make_error(ErrorCode::kCorruptData, "{}: {} numbers, expected 7 + 12 per view = {}",
                      (dir / "completecalibration.txt").string(), c->size(),
                      7 + 12 * d.views.size());
  const auto& n = *c;
  d.alpha = n[0];
  d.gamma = n[1];
  d.beta = n[2];
  d.u0 = n[3];
  d.v0 = n[4];
  d.k1 = n[5];
  d.k2 = n[6];
  for (size_t v = 0; v < d.views.size(); ++v) {
    const double* p = n.data() + 7 + 12 * v;
    d.R.push_back(nearest_rotation(cv::Matx33d(p)));  // published to 6 digits: not exactly R
    d.t.emplace_back(p[9], p[10], p[11]);
  }
  return d;
}

IntrinsicsOptions zhang_intrinsics_options() {
  IntrinsicsOptions o;
  o.model = DistortionModel::kRadial2;
  o.reject_factor = 1e9;  // compare every published view
  o.min_views = 2;
  return o;
}

Result<ZhangEval> evaluate_zhang(const ZhangDataset& d, const IntrinsicsOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::vector<cv::Point3f>> obj(d.views.size(), d.model);
  std::vector<std::string> names;
  for (size_t i = 0; i < d.views.size(); ++i) names.push_back(fmt::format("image{}", i + 1));
  auto cal = calibrate_from_points(obj, d.views, d.image_size, options, names);
  if (!cal) return tl::unexpected(cal.error());
  ZhangEval e;
  e.calibration = *cal;
  const cv::Matx33d& K = cal->camera.K;
  e.fx_rel_err = std::abs(K(0, 0) - d.alpha) / d.alpha;
  e.fy_rel_err = std::abs(K(1, 1) - d.beta) / d.beta;
  e.cx_err_px = std::abs(K(0, 2) - d.u0);
  e.cy_err_px = std::abs(K(1, 2) - d.v0);
  e.rms_px = cal->rms_px;
  double pub_sq = 0;
  size_t pub_n = 0;
  for (size_t v = 0; v < d.views.size(); ++v) {
    const ViewReport& vr = cal->views[v];
    ZhangViewEval ve;
    ve.name = vr.name;
    ve.rms_px = vr.rms_px;
    ve.rot_err_deg = rotation_angle_deg(vr.R, d.R[v]);
    ve.trans_rel_err = cv::norm(vr.t - d.t[v]) / cv::norm(d.t[v]);
    double sq = 0;
    for (size_t j = 0; j < d.model.size(); ++j) {
      const cv::Point2d p = zhang_project(d, d.R[v], d.t[v], d.model[j]);
      const cv::Point2d q(d.views[v][j].x, d.views[v][j].y);
      sq += (p - q).dot(p - q);
    }
    pub_sq += sq;
    pub_n += d.model.size();
    ve.published_rms_px = std::sqrt(sq / static_cast<double>(d.model.size()));
    e.rot_err_deg_max = std::max(e.rot_err_deg_max, ve.rot_err_deg);
    e.trans_rel_err_max = std::max(e.trans_rel_err_max, ve.trans_rel_err);
    e.views.push_back(ve);
  }
  e.published_rms_px = std::sqrt(pub_sq / static_cast<double>(pub_n));
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

Result<std::vector<CameraExtrinsicsEval>> evaluate_extrinsics_synthetic(
    const std::vector<CameraModel>& truth, const ExtrinsicsEvalOptions& options) {
  if (truth.empty()) return make_error(ErrorCode::kInvalidArgument, "no cameras to evaluate");
  std::vector<CameraExtrinsicsEval> out;
  for (size_t i = 0; i < truth.size(); ++i) {
    const CameraModel& cam = truth[i];
    SyntheticPnpOptions so = options.synthetic;
    so.seed = options.synthetic.seed + i;
    const SyntheticPnp s = make_synthetic_correspondences(cam, so);
    PnpOptions po = options.pnp;
    po.seed = options.pnp.seed + i;
    const auto t0 = std::chrono::steady_clock::now();
    auto r = estimate_pose(s.world, s.pixels, cam.K, cam.distortion, po);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!r) return make_error(r.error().code, "camera {}: {}", cam.frame, r.error().message);
    CameraExtrinsicsEval e;
    e.frame = cam.frame;
    e.rot_err_deg = rotation_angle_deg(r->R, cam.R);
    e.trans_err_m = cv::norm(r->t - cam.t);
    e.trans_rel_err = cv::norm(cam.t) > 0.01 ? e.trans_err_m / cv::norm(cam.t) : 0.0;
    e.centre_err_m = cv::norm(r->centre_world() - cam.centre_world());
    e.points = static_cast<int>(s.world.size());
    e.inliers = r->inlier_count;
    e.rms_px = r->rms_px;
    e.ms = ms;
    for (size_t k = 0; k < s.is_outlier.size(); ++k) {
      if (s.is_outlier[k]) {
        ++e.outliers_injected;
        if (!r->inliers[k]) ++e.true_outliers_rejected;
      }
    }
    out.push_back(e);
  }
  return out;
}

}  // namespace dreamsense::geometry
