#include "dreamsense/face_detection/face_detection_analyzer.hpp"

#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <opencv2/core/utility.hpp>

#include <set>

namespace dreamsense::face_detection {
namespace {

// The head as seen by one camera: the projected head position and the head yaw relative to the
// camera (degrees, 0 = facing it), from the last head pose.
struct CameraHeadView {
  cv::Point2d head_px;
  double yaw_deg = 0;
};

// The face a head view applies to: the first face (best score first) whose box, grown by 10 %,
// holds the projected head position.
std::optional<size_t> face_of_head(const std::vector<DetectedFace>& faces, cv::Point2d head_px) {
  for (size_t i = 0; i < faces.size(); ++i) {
    const cv::Rect2d& b = faces[i].box_px;
    const cv::Rect2d grown(b.x - 0.1 * b.width, b.y - 0.1 * b.height, 1.2 * b.width,
                           1.2 * b.height);
    if (grown.contains(head_px)) return i;
  }
  return std::nullopt;
}

class FaceDetectionAnalyzer : public Analyzer {
 public:
  struct Camera {
    SensorId id;
    FaceTracker tracker;
    std::optional<CameraFaces> last;  // result of the last frame searched (reused for repeats)
    bool last_guided = false;         // `last` was placed from landmarks, not searched
    // How the cascade's box sat on the landmarks fitted from it, at the last searched frame
    // whose fit came back (guides of landmark-guided frames are placed with it).
    std::optional<BoxOnExtent> box_on_fit;
  };

  FaceDetectionAnalyzer(FaceDetectionAnalyzerOptions o, std::vector<Camera> cameras)
      : options_(std::move(o)), cameras_(std::move(cameras)), selector_(options_.selection) {}

  std::string_view name() const override { return "face_detection"; }
  AnalyzerContract contract() const override {
    AnalyzerContract c{
        {}, options_.cameras, {}, {keys::kFaceDetections.name, keys::kSelectedCamera.name}};
    if (!options_.camera_models.empty()) c.reads_previous = {keys::kHeadPose.name};
    if (options_.tracker.cascade_interval > 1) {
      c.reads_previous.push_back(keys::kFaceLandmarks.name);
      c.reads_previous.push_back(keys::kFaceLandmarkViews.name);
    }
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

    // The head yaw per camera is known before the search (it comes from the last head pose), so
    // the face it will rate in camera selection skips the frontalness proxy: selection rates that
    // face by the yaw, and its frontalness is set from the yaw.
    const std::map<SensorId, CameraHeadView> heads = head_views(prior, in.stamp);
    const std::vector<std::shared_ptr<const FaceLandmarks>> fits = previous_fits(prior);
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
      KnownFrontalness known;
      std::optional<double> head_yaw_deg;
      if (const auto h = heads.find(cam.id); h != heads.end()) {
        known = [&v = h->second](const std::vector<DetectedFace>& faces,
                                 size_t i) -> std::optional<float> {
          if (face_of_head(faces, v.head_px) != i) return std::nullopt;
          return frontalness_from_yaw(v.yaw_deg);
        };
        head_yaw_deg = h->second.yaw_deg;
      }
      TrackedFrameFaces t = cam.tracker.process(image, known, head_yaw_deg, guides(cam, fits));
      r.faces = std::move(t.faces);
      cam.last = r;
      cam.last_guided = t.guided;
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
      const SensorId& id = cameras_[work[w].first].id;
      if (const auto h = heads.find(id); h != heads.end())
        results[w].head_face = face_of_head(results[w].faces, h->second.head_px);
      detections.cameras.emplace(id, std::move(results[w]));
    }
    const std::optional<SelectedCamera> selected =
        selector_.update(detections, yaw_hints(detections, heads));
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

  // Projected head position and head yaw per calibrated camera, from the last head pose (none
  // without camera models or a recent pose, or for a camera the head projects outside of).
  // With predict_head_yaw, each camera's yaw is extrapolated from the last two poses to `now`
  // (the pose is one frame old; during a turn that lag alone picks the wrong camera near a tie).
  std::map<SensorId, CameraHeadView> head_views(const BlackboardView& prior, Timestamp now) {
    std::map<SensorId, CameraHeadView> views;
    if (options_.camera_models.empty()) return views;
    const auto pose = prior.get(keys::kHeadPose);
    if (!pose || !pose->present() || now - pose->stamp > options_.head_pose_max_age) {
      last_pose_.reset();
      previous_pose_.reset();
      return views;
    }
    const HeadPose& p = *pose->value;
    if (!last_pose_ || last_pose_->stamp != p.frame_stamp) {
      previous_pose_ = last_pose_;
      last_pose_ = PoseSample{p.frame_stamp, p.gaze_direction_world};
    }
    // Poses without a frame stamp (unset) are not extrapolated.
    const bool stamped =
        last_pose_->stamp.is_set() && previous_pose_ && previous_pose_->stamp.is_set();
    const double step_s = stamped ? (last_pose_->stamp - previous_pose_->stamp).seconds() : 0.0;
    const double ahead_s = stamped ? (now - last_pose_->stamp).seconds() : 0.0;
    const bool predict = options_.predict_head_yaw && stamped && step_s > 0 &&
                         step_s <= options_.head_pose_max_age.seconds() && ahead_s > 0;
    for (const auto& [id, model] : options_.camera_models) {
      const auto px = model.project(p.position_world_m);
      if (!px) continue;
      double yaw = model.yaw_towards_deg(p.gaze_direction_world);
      if (predict) {
        double change = yaw - model.yaw_towards_deg(previous_pose_->gaze);
        change = std::remainder(change, 360.0);
        yaw += std::clamp(change * ahead_s / step_s, -options_.max_yaw_prediction_deg,
                          options_.max_yaw_prediction_deg);
      }
      views[id] = {*px, yaw};
    }
    return views;
  }

  // The landmark fits of the last tick, all cameras (empty unless landmark-guided frames are on).
  std::vector<std::shared_ptr<const FaceLandmarks>> previous_fits(
      const BlackboardView& prior) const {
    std::vector<std::shared_ptr<const FaceLandmarks>> fits;
    if (options_.tracker.cascade_interval <= 1) return fits;
    if (const auto lm = prior.get(keys::kFaceLandmarks); lm && lm->present())
      fits.push_back(lm->value);
    if (const auto views = prior.get(keys::kFaceLandmarkViews); views && views->present())
      for (const FaceLandmarks& v : views->value->others)
        fits.push_back(std::shared_ptr<const FaceLandmarks>(views->value, &v));
    return fits;
  }

  // Guides for this camera's next frame: the fits of its last frame. A fit of a searched frame
  // first teaches how the cascade box sits on the fitted points (cam.box_on_fit).
  static std::vector<FaceGuide> guides(
      Camera& cam, const std::vector<std::shared_ptr<const FaceLandmarks>>& fits) {
    std::vector<FaceGuide> out;
    if (!cam.last) return out;
    for (const auto& fit : fits) {
      if (fit->camera != cam.id || fit->frame_sequence != cam.last->frame_sequence ||
          fit->frame_stamp != cam.last->frame_stamp)
        continue;
      const cv::Rect2d extent = points_extent(fit->points_px);
      if (!cam.last_guided)
        if (auto r = box_on_extent(fit->box_px, extent)) cam.box_on_fit = r;
      if (cam.box_on_fit && extent.area() > 0)
        out.push_back(
            {fit->box_px, place_box(*cam.box_on_fit, extent), eye_line_roll_deg(fit->points_px)});
    }
    return out;
  }

  // Head yaw relative to each camera, for the face (per camera) whose box holds the projected
  // head position (CameraFaces::head_face, set only where `heads` has the camera).
  static std::vector<HeadYawHint> yaw_hints(const FaceDetections& detections,
                                            const std::map<SensorId, CameraHeadView>& heads) {
    std::vector<HeadYawHint> hints;
    for (const auto& [id, cam] : detections.cameras)
      if (cam.head_face)
        hints.push_back({id, cam.faces[*cam.head_face].box_px, heads.at(id).yaw_deg});
    return hints;
  }

  void reset() override {
    last_pose_.reset();
    previous_pose_.reset();
    for (Camera& c : cameras_) {
      c.tracker.reset();
      c.last.reset();
      c.last_guided = false;
      c.box_on_fit.reset();
    }
    selector_.reset();
  }

 private:
  FaceDetectionAnalyzerOptions options_;
  std::vector<Camera> cameras_;
  CameraSelector selector_;
  struct PoseSample {
    Timestamp stamp;
    cv::Vec3d gaze;  // head-gaze direction, world
  };
  std::optional<PoseSample> last_pose_, previous_pose_;  // the last two head poses seen
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
  if (!(max_yaw_prediction_deg >= 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "FaceDetectionAnalyzerOptions: max_yaw_prediction_deg must be >= 0");
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
    cameras.push_back(
        {options.cameras[i], FaceTracker(std::move(*detector), t), std::nullopt, false, {}});
  }
  return std::unique_ptr<Analyzer>(new FaceDetectionAnalyzer(options, std::move(cameras)));
}

}  // namespace dreamsense::face_detection
