#include "dreamsense/eval/face_model_fit.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "records.hpp"

namespace dreamsense::eval {
namespace {
struct TruthPose {
  cv::Matx33d world_from_head;
  cv::Vec3d position_m;
};
}  // namespace

Status FaceModelFitOptions::check() const {
  if (frame_step < 1)
    return make_error(ErrorCode::kInvalidArgument, "FaceModelFitOptions: frame_step must be >= 1");
  return shape.check();
}

Result<FaceModelFitResult> fit_subject_face_model(
    const std::vector<std::filesystem::path>& sessions, const FaceModelFitOptions& options,
    const std::function<void(int64_t, int64_t)>& progress) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (sessions.empty())
    return make_error(ErrorCode::kInvalidArgument, "train face: no session given");
  auto detector = face_detection::FaceDetector::create({});
  if (!detector) return tl::unexpected(detector.error());
  auto landmarker = face_landmarks::make_dlib_landmarker();
  if (!landmarker) return tl::unexpected(landmarker.error());

  FaceModelFitResult result;
  std::vector<head_pose::LandmarkView> views;
  // Every session is checked before the slow part. Views point at the cameras of `planned`,
  // which is not resized after this loop (map nodes keep their addresses).
  struct Planned {
    std::filesystem::path dir;
    sources::SessionManifest manifest;
    std::map<SensorId, CameraModel> cameras;  // calibrated colour streams used
    std::vector<SensorId> streams;            // their ids
  };
  std::vector<Planned> planned;
  for (const auto& dir : sessions) {
    auto manifest = sources::read_manifest(dir);
    if (!manifest) return tl::unexpected(manifest.error());
    if (manifest->truth.empty())
      return make_error(ErrorCode::kNotFound,
                        "{}: the session has no truth head poses to fit a face model on",
                        dir.string());
    auto calibrated = sources::read_color_calibrations(dir, *manifest);
    if (!calibrated) return tl::unexpected(calibrated.error());
    Planned p{dir, *manifest, {}, {}};
    for (auto& [id, camera] : *calibrated) {
      if (!options.cameras.empty() &&
          std::find(options.cameras.begin(), options.cameras.end(), id) == options.cameras.end())
        continue;
      p.streams.push_back(id);
      p.cameras.emplace(id, std::move(camera));
    }
    if (p.streams.empty())
      return make_error(ErrorCode::kNotFound, "{}: no calibrated camera among the colour streams",
                        dir.string());
    planned.push_back(std::move(p));
  }
  std::string provenance;
  for (const Planned& p : planned) {
    auto truth = sources::read_truth(p.dir / p.manifest.truth);
    if (!truth) return tl::unexpected(truth.error());
    std::map<int64_t, TruthPose> poses;
    for (const auto& t : *truth)
      if (t.value("type", "") == "face" && t.contains("head_position_m"))
        poses[t.value("stamp_ns", int64_t{0})] = {ypr_rotation(t), vec3(t["head_position_m"])};
    sources::SessionReaderOptions ro;
    ro.only = p.streams;
    auto reader = sources::SessionReader::open(p.dir, ro);
    if (!reader) return tl::unexpected(reader.error());
    const int64_t expected = static_cast<int64_t>(poses.size() * p.streams.size());
    int64_t done = 0;
    const int views_before = static_cast<int>(views.size());
    for (;;) {
      auto frame = (*reader)->next();
      if (!frame) {
        if (frame.error().code == ErrorCode::kEndOfStream) break;
        return tl::unexpected(frame.error());
      }
      const SensorFrame& f = **frame;
      ++done;
      if (progress && done % 25 == 0) progress(done, expected);
      if (f.sequence % static_cast<uint64_t>(options.frame_step) != 0) continue;
      const auto pose = poses.find(f.stamp.ns());
      const ColorImage* img = f.as<ColorImage>();
      if (pose == poses.end() || img == nullptr) continue;
      ++result.frames_searched;
      const auto faces = detector->detect(img->image, std::nullopt, false);
      if (faces.empty()) continue;
      auto pts = (*landmarker)->fit(img->image, faces.front().box_px);
      if (!pts) return tl::unexpected(pts.error());
      if (!*pts) continue;
      views.push_back({&p.cameras.at(f.sensor), pose->second.world_from_head,
                       pose->second.position_m, std::move(**pts)});
    }
    provenance += fmt::format("{}{} ({} views)", provenance.empty() ? "" : ", ", p.manifest.name,
                              static_cast<int>(views.size()) - views_before);
  }
  result.views = static_cast<int>(views.size());
  auto fit = head_pose::fit_face_shape(views, options.shape);
  if (!fit) return tl::unexpected(fit.error());
  result.fit = std::move(*fit);
  result.provenance = "fitted by `dreamsense train face` on " + provenance;
  return result;
}

}  // namespace dreamsense::eval
