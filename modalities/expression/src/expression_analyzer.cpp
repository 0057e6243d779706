#include "dreamsense/expression/expression_analyzer.hpp"

#include "dreamsense/perception/expression.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/vision/face_alignment.hpp"

#include <optional>
#include <set>

namespace dreamsense::expression {
namespace {

class ExpressionAnalyzer : public Analyzer {
 public:
  ExpressionAnalyzer(ExpressionAnalyzerOptions o, ExpressionRecognizer r)
      : options_(std::move(o)),
        recognizer_(std::move(r)),
        smoother_(recognizer_.model().labels(), options_.smoothing) {
    const double interval = options_.recognize_interval_s < 0
                                ? auto_recognize_interval_s(recognizer_.model())
                                : options_.recognize_interval_s;
    interval_ns_ = static_cast<int64_t>(interval * 1e9);
  }

  std::string_view name() const override { return "expression"; }
  AnalyzerContract contract() const override {
    return {{},
            options_.cameras,
            {keys::kFaceLandmarks.name},
            {keys::kFaceExpression.name},
            {keys::kFaceTracks.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto lm = prior.get(keys::kFaceLandmarks);
    if (!lm || lm->stamp != in.stamp) return ok_status();
    if (!lm->present()) {
      out.set_absent(keys::kFaceExpression, in.stamp);
      return ok_status();
    }
    const FaceLandmarks& l = *lm->value;
    const FramePtr f = in.frame(l.camera);
    const ColorImage* img = f ? f->as<ColorImage>() : nullptr;
    if (img == nullptr) {
      out.set_absent(keys::kFaceExpression, in.stamp);
      return ok_status();
    }
    int track = -1;
    if (const auto tracks = prior.get(keys::kFaceTracks);
        tracks && tracks->present() && !tracks->value->tracks.empty())
      track = tracks->value->tracks.front().id;
    const int64_t now = f->stamp.ns();
    const bool due = !last_raw_ || track != last_track_ || now < last_recognized_ns_ ||
                     now - last_recognized_ns_ >= interval_ns_;
    if (due) {
      DS_ASSIGN_OR_RETURN(vision::FaceRegion region, vision::face_region(img->image, l.points_px));
      const cv::Mat& grey = region.grey;
      std::optional<vision::AlignedFace> face;
      if (!grey.empty()) {
        DS_ASSIGN_OR_RETURN(face,
                            vision::align_face(grey, region.landmarks,
                                               recognizer_.model().method().features.alignment));
      }
      if (!face) {
        last_raw_.reset();
        out.set_absent(keys::kFaceExpression, in.stamp);
        return ok_status();
      }
      last_raw_ = recognizer_.recognize(grey, *face);
      last_recognized_ns_ = now;
    }
    const ExpressionPrediction raw = *last_raw_;

    if (track != last_track_) smoother_.forget(last_track_);
    last_track_ = track;
    const ExpressionPrediction s = smoother_.update(track, f->stamp.ns(), raw);

    FaceExpression e;
    e.label = s.label;
    e.probability = s.confidence;
    const auto& labels = recognizer_.model().labels();
    for (size_t i = 0; i < labels.size() && i < s.probabilities.size(); ++i)
      e.probabilities[labels[i]] = s.probabilities[i];
    e.raw_label = raw.label;
    e.track_id = track;
    e.camera = l.camera;
    e.frame_stamp = f->stamp;
    out.set(keys::kFaceExpression, std::move(e), in.stamp,
            static_cast<float>(lm->confidence * s.confidence));
    return ok_status();
  }

  void reset() override {
    smoother_.reset();
    last_track_ = -1;
    last_raw_.reset();
    last_recognized_ns_ = 0;
  }

 private:
  ExpressionAnalyzerOptions options_;
  ExpressionRecognizer recognizer_;
  ExpressionSmoother smoother_;
  int last_track_ = -1;
  int64_t interval_ns_ = 0;
  std::optional<ExpressionPrediction> last_raw_;  // of last_track_, computed at last_recognized_ns_
  int64_t last_recognized_ns_ = 0;
};

}  // namespace

std::filesystem::path default_expression_model() {
  return std::filesystem::path(DREAMSENSE_EXPRESSION_MODEL_DIR) /
         "expression_fer2013_xception.yaml";
}

double auto_recognize_interval_s(const ExpressionModel& model) {
  return model.method().features.uses_network() ? kNetworkRecognizeIntervalS : 0.0;
}

Status ExpressionAnalyzerOptions::check() const {
  if (!(recognize_interval_s < 1e6))
    return make_error(ErrorCode::kInvalidArgument,
                      "ExpressionAnalyzerOptions: recognize_interval_s must be a number < 1e6");
  std::set<SensorId> seen;
  for (const SensorId& c : cameras)
    if (c.empty() || !seen.insert(c).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "ExpressionAnalyzerOptions: empty or repeated camera id '{}'", c);
  return smoothing.check();
}

Result<std::unique_ptr<Analyzer>> make_expression_analyzer(
    const ExpressionAnalyzerOptions& options) {
  DS_RETURN_IF_ERROR(options.check());
  DS_ASSIGN_OR_RETURN(
      auto model,
      ExpressionModel::load(options.model.empty() ? default_expression_model() : options.model));
  DS_ASSIGN_OR_RETURN(auto recognizer, ExpressionRecognizer::create(std::move(model)));
  return std::unique_ptr<Analyzer>(new ExpressionAnalyzer(options, std::move(recognizer)));
}

}  // namespace dreamsense::expression
