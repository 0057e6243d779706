#include "dreamsense/body/body_analyzer.hpp"

#include "dreamsense/perception/body.hpp"

namespace dreamsense::body {
namespace {

class BodyAnalyzer : public Analyzer {
 public:
  explicit BodyAnalyzer(BodyAnalyzerOptions o) : options_(std::move(o)) {}
  std::string_view name() const override { return "body"; }
  AnalyzerContract contract() const override {
    return {{options_.skeleton_sensor}, {}, {}, {keys::kChildBody.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView&, BlackboardWriter& out) override {
    const FramePtr frame = in.frame(options_.skeleton_sensor);
    if (!frame) return ok_status();  // no skeleton frame near this tick: nothing observed
    const Skeleton* skeleton = frame->as<Skeleton>();
    if (skeleton == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "body: stream '{}' is not a skeleton stream",
                        options_.skeleton_sensor);
    std::vector<SkeletonBody> bodies = skeleton->bodies;
    for (auto& b : bodies)
      for (auto& j : b.joints)
        if (j.valid())
          j.position_m = options_.world_from_sensor_R * j.position_m + options_.world_from_sensor_t;
    const auto chosen = select_child(bodies, previous_, options_.selection);
    if (!chosen) {
      out.set_absent(keys::kChildBody, frame->stamp);
      return ok_status();
    }
    BodyState state{bodies[*chosen], options_.skeleton_sensor, static_cast<int>(bodies.size())};
    float confidence = 0.f;
    for (int j = 0; j < kDreamJointCount; ++j) confidence += state.body.joints[j].confidence;
    confidence /= kDreamJointCount;
    const JointObservation& anchor = state.body.joint(JointId::kShoulderCenter);
    previous_ = anchor.valid() ? anchor.position_m : state.body.joint(JointId::kHead).position_m;
    out.set(keys::kChildBody, std::move(state), frame->stamp, confidence);
    return ok_status();
  }
  void reset() override { previous_.reset(); }

 private:
  BodyAnalyzerOptions options_;
  std::optional<cv::Vec3d> previous_;
};

}  // namespace

Status BodyAnalyzerOptions::check() const {
  if (skeleton_sensor.empty())
    return make_error(ErrorCode::kInvalidArgument, "BodyAnalyzerOptions: skeleton_sensor is empty");
  const cv::Matx33d I = world_from_sensor_R * world_from_sensor_R.t();
  if (cv::norm(I - cv::Matx33d::eye()) > 1e-6)
    return make_error(ErrorCode::kInvalidArgument,
                      "BodyAnalyzerOptions: world_from_sensor_R is not a rotation");
  return selection.check();
}

Result<std::unique_ptr<Analyzer>> make_body_analyzer(const BodyAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  return std::unique_ptr<Analyzer>(new BodyAnalyzer(options));
}

}  // namespace dreamsense::body
