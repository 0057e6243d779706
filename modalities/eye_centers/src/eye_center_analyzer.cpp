#include "dreamsense/eye_centers/eye_center_analyzer.hpp"

#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <set>

namespace dreamsense::eye_centers {
namespace {

class EyeCenterAnalyzer : public Analyzer {
 public:
  EyeCenterAnalyzer(EyeCenterAnalyzerOptions o, EyeCenterLocator l)
      : options_(std::move(o)), locator_(l) {}

  std::string_view name() const override { return "eye_centers"; }
  AnalyzerContract contract() const override {
    AnalyzerContract c{{}, options_.cameras, {keys::kFaceLandmarks.name}, {keys::kEyeCenters.name}};
    if (uses_depth()) c.reads_previous = {keys::kHeadPose.name};
    return c;
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto lm = prior.get(keys::kFaceLandmarks);
    if (!lm || lm->stamp != in.stamp) return ok_status();  // landmarks did not run this tick
    if (!lm->present()) {
      out.set_absent(keys::kEyeCenters, in.stamp);
      return ok_status();
    }
    const FaceLandmarks& l = *lm->value;
    if (l.points_px.size() != static_cast<size_t>(kFaceLandmarkCount))
      return make_error(ErrorCode::kInvalidArgument, "eye_centers: {} landmarks, need {}",
                        l.points_px.size(), kFaceLandmarkCount);
    const FramePtr f = in.frame(l.camera);
    if (!f) {
      out.set_absent(keys::kEyeCenters, in.stamp);
      return ok_status();
    }
    const ColorImage* img = f->as<ColorImage>();
    if (img == nullptr)
      return make_error(ErrorCode::kInvalidArgument,
                        "eye_centers: stream '{}' is not a colour stream", l.camera);
    if (img->image.size() != l.image_size)
      return make_error(ErrorCode::kInvalidArgument,
                        "eye_centers: frame of '{}' is {}x{}, landmarks were fitted on {}x{}",
                        l.camera, img->image.cols, img->image.rows, l.image_size.width,
                        l.image_size.height);
    auto eyes = locator_.locate_both(img->image, l, pixels_per_mm(prior, l.camera, in.stamp));
    if (!eyes) return tl::unexpected(eyes.error());
    const double eye_conf = 0.5 * (eyes->right.confidence + eyes->left.confidence);
    out.set(keys::kEyeCenters, std::move(*eyes), in.stamp,
            static_cast<float>(lm->confidence * eye_conf));
    return ok_status();
  }

 private:
  bool uses_depth() const {
    return options_.iris_size_from_depth && !options_.camera_models.empty();
  }

  // The image scale at the head in `camera` (focal length / depth of the head's origin) from the
  // last tick's head pose; nullopt without a recent pose or a model of that camera.
  std::optional<double> pixels_per_mm(const BlackboardView& prior, const SensorId& camera,
                                      Timestamp now) const {
    if (!uses_depth()) return std::nullopt;
    const auto model = options_.camera_models.find(camera);
    const auto pose = prior.get(keys::kHeadPose);
    if (model == options_.camera_models.end() || !pose || !pose->present() ||
        !(now - pose->stamp <= options_.head_pose_max_age))
      return std::nullopt;
    return pixels_per_mm_at(model->second, pose->value->position_world_m);
  }

  EyeCenterAnalyzerOptions options_;
  EyeCenterLocator locator_;
};

}  // namespace

Status EyeCenterAnalyzerOptions::check() const {
  std::set<SensorId> seen;
  for (const SensorId& c : cameras)
    if (c.empty() || !seen.insert(c).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "EyeCenterAnalyzerOptions: empty or repeated camera id '{}'", c);
  if (!(head_pose_max_age > Duration::from_ns(0)))
    return make_error(ErrorCode::kInvalidArgument,
                      "EyeCenterAnalyzerOptions: head_pose_max_age must be > 0");
  for (const auto& [id, m] : camera_models)
    if (auto s = m.check(); !s)
      return make_error(ErrorCode::kInvalidArgument, "EyeCenterAnalyzerOptions: camera '{}': {}",
                        id, s.error().message);
  return locator.check();
}

Result<std::unique_ptr<Analyzer>> make_eye_center_analyzer(
    const EyeCenterAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto l = EyeCenterLocator::create(options.locator);
  if (!l) return tl::unexpected(l.error());
  return std::unique_ptr<Analyzer>(new EyeCenterAnalyzer(options, *l));
}

}  // namespace dreamsense::eye_centers
