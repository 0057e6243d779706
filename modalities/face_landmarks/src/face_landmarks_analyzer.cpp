#include "dreamsense/face_landmarks/face_landmarks_analyzer.hpp"

#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/face_landmarks.hpp"

#include <opencv2/core/utility.hpp>

#include <optional>
#include <set>

namespace dreamsense::face_landmarks {
namespace {

class FaceLandmarksAnalyzer : public Analyzer {
 public:
  FaceLandmarksAnalyzer(FaceLandmarksAnalyzerOptions o, std::shared_ptr<const Landmarker> l,
                        std::shared_ptr<const Landmarker> cnn)
      : options_(std::move(o)), landmarker_(std::move(l)), cnn_(std::move(cnn)) {}

  std::string_view name() const override { return "face_landmarks"; }
  AnalyzerContract contract() const override {
    return {{},
            options_.cameras,
            {keys::kSelectedCamera.name, keys::kFaceDetections.name},
            {keys::kFaceLandmarks.name, keys::kFaceLandmarkViews.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto sel = prior.get(keys::kSelectedCamera);
    if (!sel || sel->stamp != in.stamp) return ok_status();  // no camera frame this tick
    if (!sel->present()) {
      return absent(in.stamp, out);
    }
    const SelectedCamera& s = *sel->value;
    const FramePtr f = in.frame(s.camera);
    const ColorImage* img = f ? f->as<ColorImage>() : nullptr;
    if (img == nullptr) {
      if (f)
        return make_error(ErrorCode::kInvalidArgument,
                          "face_landmarks: stream '{}' is not a colour stream", s.camera);
      return absent(in.stamp, out);
    }
    // The selected face and the other views are independent fits: with options_.parallel they
    // run at once (each result in its own slot, so the output does not depend on scheduling).
    const std::vector<OtherView> views = other_view_faces(in, prior, s.camera);
    Result<std::optional<LandmarkFit>> fit = std::optional<LandmarkFit>{};
    std::vector<Result<std::optional<std::vector<cv::Point2d>>>> view_fits(views.size());
    auto run = [&](size_t job) {
      if (job == 0)
        fit = landmarker_->fit_with_spread(img->image, s.face.box_px);
      else
        view_fits[job - 1] = landmarker_->fit(views[job - 1].image(), views[job - 1].box);
    };
    const size_t jobs = 1 + views.size();
    if (options_.parallel && jobs > 1) {
      cv::parallel_for_(
          cv::Range(0, static_cast<int>(jobs)),
          [&](const cv::Range& r) {
            for (int j = r.start; j < r.end; ++j) run(static_cast<size_t>(j));
          },
          static_cast<double>(jobs));
    } else {
      for (size_t j = 0; j < jobs; ++j) run(j);
    }
    if (!fit) return tl::unexpected(fit.error());
    if (!*fit) {
      return absent(in.stamp, out);
    }
    FaceLandmarkViews others;
    for (size_t v = 0; v < views.size(); ++v) {
      if (!view_fits[v]) return tl::unexpected(view_fits[v].error());
      if (!*view_fits[v]) continue;
      others.others.push_back(landmarks_of(views[v].camera, *views[v].frame, views[v].image(),
                                           views[v].box, std::move(**view_fits[v])));
    }
    out.set(keys::kFaceLandmarkViews, std::move(others), in.stamp, sel->confidence);
    double fit_confidence =
        spread_confidence((*fit)->spread, options_.spread_ok, options_.spread_bad);
    std::vector<cv::Point2d> points = std::move((*fit)->points);
    if (cnn_ && fit_confidence < options_.cnn_fallback_below) {
      auto cnn_fit = cnn_->fit(img->image, s.face.box_px);
      if (!cnn_fit) return tl::unexpected(cnn_fit.error());
      if (*cnn_fit && (*cnn_fit)->size() == points.size()) {
        fit_confidence = spread_confidence(mean_point_distance(**cnn_fit, points),
                                           options_.spread_ok, options_.spread_bad);
        points = std::move(**cnn_fit);
      }
    }
    out.set(keys::kFaceLandmarks,
            landmarks_of(s.camera, *f, img->image, s.face.box_px, std::move(points)), in.stamp,
            static_cast<float>(sel->confidence * fit_confidence));
    return ok_status();
  }

 private:
  static Status absent(Timestamp tick, BlackboardWriter& out) {
    out.set_absent(keys::kFaceLandmarks, tick);
    out.set_absent(keys::kFaceLandmarkViews, tick);
    return ok_status();
  }

  static FaceLandmarks landmarks_of(const SensorId& camera, const SensorFrame& frame,
                                    const cv::Mat& image, const cv::Rect2d& box,
                                    std::vector<cv::Point2d> points) {
    FaceLandmarks lm;
    lm.camera = camera;
    lm.frame_stamp = frame.stamp;
    lm.frame_sequence = frame.sequence;
    lm.image_size = image.size();
    lm.box_px = box;
    lm.points_px = std::move(points);
    return lm;
  }

  struct OtherView {
    SensorId camera;
    FramePtr frame;  // a colour frame (other_view_faces checks)
    cv::Rect2d box;
    const cv::Mat& image() const { return frame->as<ColorImage>()->image; }
  };

  // Each other camera's face of the child this tick, to be fitted (CameraFaces::head_face, else
  // the best-scored face; only where that face is frontal enough), in the detections' order.
  std::vector<OtherView> other_view_faces(const MultiFrame& in, const BlackboardView& prior,
                                          const SensorId& selected) const {
    std::vector<OtherView> views;
    if (!options_.other_views) return views;
    const auto det = prior.get(keys::kFaceDetections);
    if (!det || det->stamp != in.stamp || !det->present()) return views;
    for (const auto& [camera, faces] : det->value->cameras) {
      // The child's face in that camera where the last head pose says which it is (another
      // person may score higher), else the best-scored one.
      const size_t i = faces.head_face.value_or(0);
      if (camera == selected || i >= faces.faces.size() ||
          faces.faces[i].frontalness < options_.other_view_min_frontalness)
        continue;
      FramePtr f = in.frame(camera);
      const ColorImage* img = f ? f->as<ColorImage>() : nullptr;
      if (img == nullptr || f->stamp != faces.frame_stamp) continue;
      views.push_back(OtherView{camera, std::move(f), faces.faces[i].box_px});
    }
    return views;
  }

  FaceLandmarksAnalyzerOptions options_;
  std::shared_ptr<const Landmarker> landmarker_;
  std::shared_ptr<const Landmarker> cnn_;  // null: no fallback
};

}  // namespace

Status FaceLandmarksAnalyzerOptions::check() const {
  std::set<SensorId> seen;
  for (const SensorId& c : cameras)
    if (c.empty() || !seen.insert(c).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "FaceLandmarksAnalyzerOptions: empty or repeated camera id '{}'", c);
  if (!(spread_ok >= 0 && spread_bad > spread_ok))
    return make_error(ErrorCode::kInvalidArgument,
                      "FaceLandmarksAnalyzerOptions: need 0 <= spread_ok < spread_bad");
  if (!(other_view_min_frontalness >= 0 && other_view_min_frontalness <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "FaceLandmarksAnalyzerOptions: other_view_min_frontalness must be in [0, 1]");
  if (!(cnn_fallback_below >= 0 && cnn_fallback_below <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "FaceLandmarksAnalyzerOptions: cnn_fallback_below must be in [0, 1]");
  if (cnn_fallback)
    if (auto s = cnn.check(); !s) return s;
  return dlib.check();
}

Result<std::unique_ptr<Analyzer>> make_face_landmarks_analyzer(
    const FaceLandmarksAnalyzerOptions& options, std::shared_ptr<const Landmarker> landmarker,
    std::shared_ptr<const Landmarker> cnn) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (!landmarker)
    return make_error(ErrorCode::kInvalidArgument, "make_face_landmarks_analyzer: no landmarker");
  for (const Landmarker* l : {landmarker.get(), cnn.get()})
    if (l && l->point_count() != kFaceLandmarkCount)
      return make_error(ErrorCode::kInvalidArgument,
                        "make_face_landmarks_analyzer: landmarker '{}' gives {} points, need {}",
                        l->name(), l->point_count(), kFaceLandmarkCount);
  if (!options.cnn_fallback) cnn.reset();
  return std::unique_ptr<Analyzer>(
      new FaceLandmarksAnalyzer(options, std::move(landmarker), std::move(cnn)));
}

Result<std::unique_ptr<Analyzer>> make_face_landmarks_analyzer(
    const FaceLandmarksAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto l = shared_dlib_landmarker(options.dlib);
  if (!l) return tl::unexpected(l.error());
  std::shared_ptr<const Landmarker> cnn;
  if (options.cnn_fallback) {
    auto c = make_face_api_landmarker(options.cnn);
    if (!c) return tl::unexpected(c.error());
    cnn = std::move(*c);
  }
  return make_face_landmarks_analyzer(options, *l, std::move(cnn));
}

}  // namespace dreamsense::face_landmarks
