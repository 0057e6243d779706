// Development probe: the eye-centre methods on a recorded session's own landmarks, one JSON line
// per eye, for error analysis against the session's truth (tools: see README "Session probe").
// Runs face detection (with the calibrated cameras' selection), landmarks and head pose exactly
// as `dreamsense analyze` wires them, then, per tick with landmarks, every method variant below
// on the selected camera's frame. Only the locators differ between variants, so their errors are
// compared on identical inputs.
// Run: <build>/bench/eye_centers_session_probe SESSION_DIR OUT.jsonl

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/pipeline.hpp"
#include "dreamsense/eye_centers/eye_center_locator.hpp"
#include "dreamsense/face_detection/face_detection_analyzer.hpp"
#include "dreamsense/face_landmarks/face_landmarks_analyzer.hpp"
#include "dreamsense/head_pose/head_pose_analyzer.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "eye_eval.hpp"

namespace ds = dreamsense;
namespace ec = dreamsense::eye_centers;

namespace {

nlohmann::json location_json(const ec::EyeLocation& r) {
  return {{"found", r.found},
          {"x", r.center_px.x},
          {"y", r.center_px.y},
          {"ix", r.iris_center_px.x},
          {"iy", r.iris_center_px.y},
          {"radius", r.radius_px},
          {"score", r.score},
          {"pupil_found", r.pupil_found},
          {"pupil_radius", r.pupil_radius_px},
          {"pupil_score", r.pupil_score},
          {"rejection", std::string(ec::to_string(r.rejection))}};
}

std::vector<std::pair<std::string, ec::EyeCenterLocatorOptions>> variants() {
  std::vector<std::pair<std::string, ec::EyeCenterLocatorOptions>> v;
  ec::EyeCenterLocatorOptions o;
  v.emplace_back("improved", o);
  {
    auto x = o;
    x.improved.pupil.enabled = false;
    v.emplace_back("improved_limbus_only", x);
  }
  {
    auto x = o;
    x.improved.min_step_of_range = 0.15;
    v.emplace_back("improved_msr0.15", x);
  }
  {  // no image-based closed-eye test
    auto x = o;
    x.improved.min_step_of_range = 0;
    v.emplace_back("improved_no_closed_test", x);
  }
  {  // the previous default: limbus only, exhaustive search, iris radius prior from 0.12 x width
    auto x = o;
    x.region.min_iris_radius = 0.12;
    x.improved.pupil.enabled = false;
    x.improved.coarse_step = 1;
    x.improved.min_step_of_range = 0;
    v.emplace_back("improved_previous", x);
  }
  {
    auto x = o;
    x.method = ec::EyeCenterMethod::kDaugman;
    v.emplace_back("daugman", x);
  }
  {
    auto x = o;
    x.method = ec::EyeCenterMethod::kTimmBarth;
    v.emplace_back("timm_barth", x);
  }
  return v;
}

// The synthetic BioID-layout set (already written into `dir`) with every improved variant.
int run_synthetic(const std::string& dir) {
  for (auto& [name, o] : variants()) {
    if (name.rfind("improved", 0) != 0) continue;
    ec::EyeEvalOptions e;
    e.dataset = "synthetic-eyes";
    e.dir = dir;
    e.locator = o;
    auto r = ec::run_eye_eval(e);
    if (!r) return std::fprintf(stderr, "%s\n", r.error().message.c_str()), 1;
    const auto& m = (*r)["metrics"];
    std::printf("%-36s acc_e005 %.3f acc_e010 %.3f median_e %.4f ms/eye %.3f\n", name.c_str(),
                m["acc_e005"].get<double>(), m["acc_e010"].get<double>(),
                m["median_e"].get<double>(), (*r)["timing"]["ms_per_eye_median"].get<double>());
    std::fflush(stdout);
  }
  return 0;
}

int run(const std::string& session, const std::string& out_path) {
  auto full = ds::sources::SessionReader::open(session);
  if (!full) {
    std::fprintf(stderr, "%s\n", full.error().message.c_str());
    return 1;
  }
  auto calibrated = ds::sources::read_color_calibrations((*full)->dir(), (*full)->manifest());
  if (!calibrated) return std::fprintf(stderr, "%s\n", calibrated.error().message.c_str()), 1;
  std::map<ds::SensorId, ds::CameraModel> cams;
  std::vector<ds::SensorId> ids;
  for (const auto& [id, m] : *calibrated) {
    if (id.rfind("camera", 0) != 0) continue;
    cams[id] = m;
    ids.push_back(id);
  }
  const double rate = (*full)->manifest().frame_rate > 0 ? (*full)->manifest().frame_rate : 25.0;
  const auto start = (*full)->info().start;
  full = {};
  std::vector<std::unique_ptr<ds::Analyzer>> analyzers;
  ds::face_detection::FaceDetectionAnalyzerOptions fo;
  fo.cameras = ids;
  fo.camera_models = cams;
  ds::face_landmarks::FaceLandmarksAnalyzerOptions lo;
  lo.cameras = ids;
  ds::head_pose::HeadPoseAnalyzerOptions ho;
  ho.cameras = cams;
  auto a = ds::face_detection::make_face_detection_analyzer(fo);
  auto l = ds::face_landmarks::make_face_landmarks_analyzer(lo);
  auto h = ds::head_pose::make_head_pose_analyzer(ho);
  if (!a || !l || !h) return std::fprintf(stderr, "analysers\n"), 1;
  analyzers.push_back(std::move(*a));
  analyzers.push_back(std::move(*l));
  analyzers.push_back(std::move(*h));
  ds::sources::SessionReaderOptions ro;
  ro.only = ids;
  auto reader = ds::sources::SessionReader::open(session, ro);
  if (!reader) return std::fprintf(stderr, "%s\n", reader.error().message.c_str()), 1;
  ds::PipelineOptions po;
  po.sync.tick_period = ds::period_from_rate(rate);
  po.sync.tolerance = po.sync.tick_period / 2;
  po.sync.start = start;
  auto pipeline = ds::Pipeline::build(po, (*reader)->info(), std::move(analyzers));
  if (!pipeline) return std::fprintf(stderr, "%s\n", pipeline.error().message.c_str()), 1;

  std::vector<std::pair<std::string, ec::EyeCenterLocator>> locators;
  for (auto& [name, o] : variants()) {
    auto loc = ec::EyeCenterLocator::create(o);
    if (!loc) return std::fprintf(stderr, "%s\n", loc.error().message.c_str()), 1;
    locators.emplace_back(name, *loc);
  }
  std::ofstream out(out_path);
  auto on_tick = [&](const ds::MultiFrame& tick, const ds::BlackboardView& view) -> ds::Status {
    const auto lm = view.get(ds::keys::kFaceLandmarks);
    if (!lm || lm->stamp != tick.stamp || !lm->present()) return ds::ok_status();
    const ds::FaceLandmarks& f = *lm->value;
    const ds::FramePtr frame = tick.frame(f.camera);
    if (!frame || f.points_px.size() != static_cast<size_t>(ds::kFaceLandmarkCount))
      return ds::ok_status();
    const cv::Mat& img = frame->as<ds::ColorImage>()->image;
    nlohmann::json rec;
    rec["stamp_ns"] = tick.stamp.ns();
    rec["camera"] = f.camera;
    for (const auto& [eye, base] : {std::pair{"right", 36}, std::pair{"left", 42}}) {
      nlohmann::json e;
      std::span<const cv::Point2d> contour(f.points_px.data() + base, 6);
      for (const auto& p : contour) e["contour"].push_back({p.x, p.y});
      for (const auto& [name, loc] : locators) {
        auto r = loc.locate(img, contour);
        if (!r) return tl::unexpected(r.error());
        e[name] = location_json(*r);
      }
      // The default locator as the analyser runs it with a head pose: the iris sized from the
      // head's depth in this camera (the probe's own pose of this tick; analyze uses the last
      // tick's, from the self-calibrated or subject model).
      const auto hp = view.get(ds::keys::kHeadPose);
      if (hp && hp->stamp == tick.stamp && hp->present()) {
        const cv::Vec3d& head = hp->value->position_world_m;
        auto r = locators.front().second.locate(img, contour,
                                                ec::pixels_per_mm_at(cams.at(f.camera), head));
        if (!r) return tl::unexpected(r.error());
        e["improved_iris_sized"] = location_json(*r);
        e["improved_iris_sized"]["depth_m"] = cams.at(f.camera).to_camera(head)[2];
      }
      rec[eye] = e;
    }
    out << rec.dump() << '\n';
    return ds::ok_status();
  };
  if (auto s = (*pipeline)->run(**reader, on_tick); !s)
    return std::fprintf(stderr, "%s\n", s.error().message.c_str()), 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr,
                 "usage: eye_centers_session_probe SESSION_DIR OUT.jsonl\n"
                 "       eye_centers_session_probe --synthetic SYNTHETIC_SET_DIR\n");
    return 2;
  }
  if (std::string(argv[1]) == "--synthetic") return run_synthetic(argv[2]);
  return run(argv[1], argv[2]);
}
