#include "dreamsense/eval/gaze_fit.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <map>
#include <optional>
#include <tuple>

#include "records.hpp"

namespace dreamsense::eval {
using nlohmann::json;

Result<gaze::GazeModelFile> fit_gaze_model(const std::vector<GazeFitInput>& inputs) {
  std::vector<gaze::EyeAngleSample> right, left;
  std::optional<std::string> method;
  std::string provenance;
  struct Run {
    std::map<int64_t, json> head, eye, pupils;
    std::map<int64_t, cv::Vec3d> truth_gaze;
    std::map<int64_t, std::pair<cv::Vec3d, cv::Vec3d>> truth_eye_dirs;  // right, left (world)
    std::map<std::string, CameraModel> cameras;
  };
  std::vector<gaze::EyeballSample> right_ball, left_ball;
  std::vector<Run> runs;
  std::vector<std::string> names;
  cv::Matx33d offset_sum = cv::Matx33d::zeros();
  int offset_count = 0;
  for (const auto& in : inputs) {
    auto manifest = sources::read_manifest(in.session_dir);
    if (!manifest) return tl::unexpected(manifest.error());
    if (manifest->truth.empty())
      return make_error(ErrorCode::kNotFound, "{}: the session has no truth to fit gaze on",
                        in.session_dir.string());
    auto truth = sources::read_truth(in.session_dir / manifest->truth);
    if (!truth) return tl::unexpected(truth.error());
    std::map<int64_t, cv::Vec3d> truth_gaze;
    std::map<int64_t, cv::Matx33d> truth_head;
    std::map<int64_t, std::pair<cv::Vec3d, cv::Vec3d>> truth_eye_dirs;
    for (const auto& t : *truth)
      if (t.value("type", "") == "face" && t.contains("eye_gaze_dir")) {
        const int64_t stamp = t.value("stamp_ns", int64_t{0});
        truth_gaze[stamp] = vec3(t["eye_gaze_dir"]);
        truth_head[stamp] = ypr_rotation(t);
        // Per-eye directions (each eye converges on the target); closed eyes are no sample.
        if (t.contains("eye_gaze_dirs") && t.value("eyes_open", true))
          truth_eye_dirs[stamp] = {vec3(t["eye_gaze_dirs"]["right"]),
                                   vec3(t["eye_gaze_dirs"]["left"])};
      }
    auto cameras = sources::read_color_calibrations(in.session_dir, *manifest);
    if (!cameras) return tl::unexpected(cameras.error());

    const auto path = in.analysis_dir / "primitives.jsonl";
    auto records = read_jsonl(path);
    if (!records) return tl::unexpected(records.error());
    std::map<int64_t, json> head, eye, pupils;
    for (const auto& r : *records) {
      if (r.value("status", "") != "ok") continue;
      const std::string p = r.value("primitive", "");
      if (p == "getHeadGaze") head[r.value("stamp_ns", int64_t{0})] = r["value"];
      if (p == "getEyeGaze") eye[r.value("stamp_ns", int64_t{0})] = r["value"];
      if (p == "getEyes") pupils[r.value("stamp_ns", int64_t{0})] = r["value"];
    }
    // The head-model offset of this subject: the rotation R minimising sum |R_est R - R_true|
    // (the orthogonal projection of sum R_est^T R_true).
    for (const auto& [stamp, h] : head) {
      const auto t = truth_head.find(stamp);
      if (t == truth_head.end()) continue;
      offset_sum += ypr_rotation(h).t() * t->second;
      ++offset_count;
    }
    runs.push_back({std::move(head), std::move(eye), std::move(pupils), std::move(truth_gaze),
                    std::move(truth_eye_dirs), std::move(*cameras)});
    names.push_back(manifest->name);
  }
  if (offset_count == 0)
    return make_error(ErrorCode::kNotFound,
                      "train gaze: no tick with an ok getHeadGaze and a truth head pose");
  cv::Mat w, u, vt;
  cv::SVD::compute(cv::Mat(offset_sum), w, u, vt);
  cv::Matx33d offset(cv::Mat(u * vt));
  if (cv::determinant(offset) < 0) {
    cv::Mat u2 = u.clone();
    u2.col(2) *= -1;
    offset = cv::Matx33d(cv::Mat(u2 * vt));
  }
  for (size_t k = 0; k < runs.size(); ++k) {
    auto& [head, eye, pupils, truth_gaze, truth_eye_dirs, cameras] = runs[k];
    // Eyeball samples: the pupil ray in the (offset-corrected) estimated head frame, and the
    // true per-eye direction in that frame.
    for (const auto& [stamp, p] : pupils) {
      const auto h = head.find(stamp);
      const auto t = truth_eye_dirs.find(stamp);
      const auto cam = cameras.find(p.value("camera", ""));
      if (h == head.end() || t == truth_eye_dirs.end() || cam == cameras.end()) continue;
      const cv::Matx33d world_from_head = ypr_rotation(h->second) * offset;
      const cv::Matx33d camera_from_head = cam->second.R * world_from_head;
      const cv::Vec3d position_camera = cam->second.R * vec3(h->second["origin"]) + cam->second.t;
      for (auto [name, truth_dir, samples] :
           {std::tuple{"right_px", t->second.first, &right_ball},
            std::tuple{"left_px", t->second.second, &left_ball}}) {
        if (!p.contains(name) || p[name].is_null()) continue;
        const cv::Point2d px(p[name][0].get<double>(), p[name][1].get<double>());
        samples->push_back(
            {gaze::pixel_ray_head(px, cam->second, camera_from_head, position_camera),
             world_from_head.t() * truth_dir});
      }
    }
    const size_t before = right.size() + left.size();
    for (const auto& [stamp, e] : eye) {
      const auto h = head.find(stamp);
      const auto t = truth_gaze.find(stamp);
      if (h == head.end() || t == truth_gaze.end()) continue;
      const std::string m = e.value("method", "");
      if (method && *method != m)
        return make_error(ErrorCode::kInvalidArgument,
                          "train gaze: analyses use different methods ({} and {})", *method, m);
      method = m;
      const cv::Matx33d R = ypr_rotation(h->second) * offset;
      const gaze::EyeAngles truth_angles = gaze::angles_of_head_direction(R.t() * t->second);
      for (auto [name, samples] : {std::pair{"right", &right}, std::pair{"left", &left}}) {
        const json& ray = e[name];
        if (ray.is_null() || !ray.contains("offset")) continue;
        samples->push_back(
            {{ray["offset"][0].get<double>(), ray["offset"][1].get<double>()}, truth_angles});
      }
    }
    provenance += fmt::format("{}{} ({} eye samples)", provenance.empty() ? "" : ", ", names[k],
                              right.size() + left.size() - before);
  }
  if (!method)
    return make_error(ErrorCode::kNotFound,
                      "train gaze: no tick with both getEyeGaze and getHeadGaze ok and a truth "
                      "eye gaze");
  gaze::GazeModelFile model;
  model.plane =
      *method == "d42_eq4_image" ? gaze::OffsetPlane::kImage : gaze::OffsetPlane::kHeadPlane;
  auto r = gaze::fit_eye_angle_model(right);
  if (!r) return make_error(r.error().code, "right eye: {}", r.error().message);
  auto l = gaze::fit_eye_angle_model(left);
  if (!l) return make_error(l.error().code, "left eye: {}", l.error().message);
  model.model_from_head = offset;
  if (!right_ball.empty() || !left_ball.empty()) {
    auto rb = gaze::fit_eyeball_model(right_ball);
    if (!rb) return make_error(rb.error().code, "right eye: {}", rb.error().message);
    auto lb = gaze::fit_eyeball_model(left_ball);
    if (!lb) return make_error(lb.error().code, "left eye: {}", lb.error().message);
    model.right_eyeball = *rb;
    model.left_eyeball = *lb;
  }
  model.right_eye = *r;
  model.left_eye = *l;
  model.samples = static_cast<int>(right.size() + left.size());
  model.provenance = "fitted by `dreamsense train gaze` on " + provenance;
  return model;
}

}  // namespace dreamsense::eval
