#include "dreamsense/face_detection/face_detection_analyzer.hpp"

#include <opencv2/core/utility.hpp>

#include <set>

namespace dreamsense::face_detection {
namespace {

class FaceDetectionAnalyzer : public Analyzer {
 public:
  struct Camera {
    SensorId id;
    FaceTracker tracker;
    std::optional<CameraFaces> last;  // result of the last frame searched (reused for repeats)
  };

  FaceDetectionAnalyzer(FaceDetectionAnalyzerOptions o, std::vector<Camera> cameras)
      : options_(std::move(o)), cameras_(std::move(cameras)), selector_(options_.selection) {}

  std::string_view name() const override { return "face_detection"; }
  AnalyzerContract contract() const override {
    AnalyzerContract c{
        {}, options_.cameras, {}, {keys::kFaceDetections.name, keys::kSelectedCamera.name}};
    if (!options_.camera_models.empty()) c.reads_previous = {keys::kHeadPose.name};
    return c;
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    // Collect the frames of this tick; check them before any work.
    std::vector<std::pair<size_t, FramePtr>> work;
    for (size_t i = 0; i < cameras_.size(); ++i) {
      FramePtr f = in.frame(cameras_[i].id);
      if (!f) continue;
      if (f->as<ColorImage>() == nullptr)
        return make_error(ErrorCode::kInvalidArgument,
                          "face_detection: stream '{}' is not a colour stream", cameras_[i].id);
      work.emplace_back(i, std::move(f));
    }
    if (work.empty()) return ok_status();  // no camera frame near this tick: nothing observed

    std::vector<CameraFaces> results(work.size());
    auto run = [&](size_t w) {
      Camera& cam = cameras_[work[w].first];
      const SensorFrame& f = *work[w].second;
      if (cam.last && cam.last->frame_sequence == f.sequence && cam.last->frame_stamp == f.stamp) {
        results[w] = *cam.last;  // the same frame as in an earlier tick
        return;
      }
      const cv::Mat& image = f.as<ColorImage>()->image;
      CameraFaces r;
      r.frame_stamp = f.stamp;
      r.frame_sequence = f.sequence;
      r.image_size = image.size();
      r.faces = cam.tracker.process(image).faces;
      cam.last = r;
      results[w] = std::move(r);
    };
    if (options_.parallel && work.size() > 1) {
      // One task per camera: each camera's tracker is used by exactly one task, and results land
      // in fixed slots, so the output does not depend on scheduling.
      cv::parallel_for_(
          cv::Range(0, static_cast<int>(work.size())),
          [&](const cv::Range& r) {
            for (int w = r.start; w < r.end; ++w) run(static_cast<size_t>(w));
          },
          static_cast<double>(work.size()));
    } else {
      for (size_t w = 0; w < work.size(); ++w) run(w);
    }

    FaceDetections detections;
    float best_score = 0.f;
    for (size_t w = 0; w < work.size(); ++w) {
      for (const DetectedFace& f : results[w].faces) best_score = std::max(best_score, f.score);
      detections.cameras.emplace(cameras_[work[w].first].id, std::move(results[w]));
    }
    const std::optional<SelectedCamera> selected =
        selector_.update(detections, yaw_hints(detections, prior, in.stamp));
    if (detections.face_count() == 0) {
      out.set_absent(keys::kFaceDetections, in.stamp);
      out.set_absent(keys::kSelectedCamera, in.stamp);
      return ok_status();
    }
    out.set(keys::kFaceDetections, std::move(detections), in.stamp, best_score);
    if (selected)
      out.set(keys::kSelectedCamera, *selected, in.stamp, selected->face.score);
    else
      out.set_absent(keys::kSelectedCamera, in.stamp);
    return ok_status();
  }

  // Head yaw relative to each camera from the last head pose, for the face (per camera) whose
  // box holds the projected head position.
  std::vector<HeadYawHint> yaw_hints(const FaceDetections& detections, const BlackboardView& prior,
                                     Timestamp now) const {
    std::vector<HeadYawHint> hints;
    if (options_.camera_models.empty()) return hints;
    const auto pose = prior.get(keys::kHeadPose);
    if (!pose || !pose->present() || now - pose->stamp > options_.head_pose_max_age) return hints;
    const HeadPose& p = *pose->value;
    for (const auto& [id, cam] : detections.cameras) {
      const auto model = options_.camera_models.find(id);
      if (model == options_.camera_models.end()) continue;
      const auto px = model->second.project(p.position_world_m);
      if (!px) continue;
      for (const DetectedFace& f : cam.faces) {
        const cv::Rect2d grown(f.box_px.x - 0.1 * f.box_px.width,
                               f.box_px.y - 0.1 * f.box_px.height, 1.2 * f.box_px.width,
                               1.2 * f.box_px.height);
        if (!grown.contains(*px)) continue;
        const cv::Vec3d g = model->second.R * p.gaze_direction_world;
        hints.push_back({id, f.box_px, std::atan2(-g[0], -g[2]) * 180.0 / CV_PI});
        break;
      }
    }
    return hints;
  }

  void reset() override {
    for (Camera& c : cameras_) {
      c.tracker.reset();
      c.last.reset();
    }
    selector_.reset();
  }

 private:
  FaceDetectionAnalyzerOptions options_;
  std::vector<Camera> cameras_;
  CameraSelector selector_;
};

}  // namespace

Status FaceDetectionAnalyzerOptions::check() const {
  if (cameras.empty())
    return make_error(ErrorCode::kInvalidArgument, "FaceDetectionAnalyzerOptions: no cameras");
  std::set<SensorId> seen;
  for (const SensorId& c : cameras) {
    if (c.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "FaceDetectionAnalyzerOptions: empty camera id");
    if (!seen.insert(c).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "FaceDetectionAnalyzerOptions: camera '{}' listed twice", c);
  }
  if (auto s = detector.check(); !s) return s;
  if (auto s = tracker.check(); !s) return s;
  return selection.check();
}

Result<std::unique_ptr<Analyzer>> make_face_detection_analyzer(
    const FaceDetectionAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  std::vector<FaceDetectionAnalyzer::Camera> cameras;
  const int n = static_cast<int>(options.cameras.size());
  for (int i = 0; i < n; ++i) {
    auto detector = FaceDetector::create(options.detector);
    if (!detector) return tl::unexpected(detector.error());
    FaceTrackerOptions t = options.tracker;
    // Spread the periodic full searches of the cameras over the interval.
    t.full_search_phase = options.tracker.full_search_phase +
                          i * options.tracker.full_search_interval / std::max(1, n);
    cameras.push_back({options.cameras[i], FaceTracker(std::move(*detector), t), std::nullopt});
  }
  return std::unique_ptr<Analyzer>(new FaceDetectionAnalyzer(options, std::move(cameras)));
}

}  // namespace dreamsense::face_detection
