#include "dreamsense/face_tracks/face_tracks_analyzer.hpp"

#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/perception/head_pose.hpp"

namespace dreamsense::face_tracks {
namespace {

class FaceTracksAnalyzer : public Analyzer {
 public:
  explicit FaceTracksAnalyzer(FaceTracksAnalyzerOptions o)
      : options_(std::move(o)), tracker_(options_.tracker) {}

  std::string_view name() const override { return "face_tracks"; }
  AnalyzerContract contract() const override {
    AnalyzerContract c{
        {}, {}, {keys::kFaceDetections.name, keys::kSelectedCamera.name}, {keys::kFaceTracks.name}};
    if (options_.use_head_pose) c.reads.push_back(keys::kHeadPose.name);
    return c;
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto det = prior.get(keys::kFaceDetections);
    if (!det || det->stamp != in.stamp) return ok_status();
    std::vector<cv::Vec3d> positions;
    float confidence = 0.f;
    if (det->present()) {
      const auto sel = prior.get(keys::kSelectedCamera);
      const SelectedCamera* selected =
          sel && sel->stamp == in.stamp && sel->present() ? sel->value.get() : nullptr;
      std::optional<Entry<HeadPose>> head;
      if (options_.use_head_pose) head = prior.get(keys::kHeadPose);
      const HeadPose* pose =
          head && head->stamp == in.stamp && head->present() ? head->value.get() : nullptr;
      auto obs =
          face_observations(*det->value, selected, pose, options_.cameras, options_.observations);
      if (!obs) return tl::unexpected(obs.error());
      for (const FaceObservation3d& o : *obs) positions.push_back(o.position_world_m);
      confidence = det->confidence;
    }
    tracker_.update(in.stamp, positions);
    out.set(keys::kFaceTracks, tracker_.tracks(), in.stamp, confidence);
    return ok_status();
  }

  void reset() override { tracker_.reset(); }

 private:
  FaceTracksAnalyzerOptions options_;
  FaceTracker3d tracker_;
};

}  // namespace

Status FaceTracksAnalyzerOptions::check() const {
  if (cameras.empty())
    return make_error(ErrorCode::kInvalidArgument, "FaceTracksAnalyzerOptions: no camera models");
  for (const auto& [id, c] : cameras)
    if (auto s = c.check(); !s)
      return make_error(ErrorCode::kInvalidArgument, "FaceTracksAnalyzerOptions: camera '{}': {}",
                        id, s.error().message);
  if (auto s = observations.check(); !s) return s;
  return tracker.check();
}

Result<std::unique_ptr<Analyzer>> make_face_tracks_analyzer(
    const FaceTracksAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  return std::unique_ptr<Analyzer>(new FaceTracksAnalyzer(options));
}

}  // namespace dreamsense::face_tracks
