#include "dreamsense/face_identity/face_identity_analyzer.hpp"

#include "dreamsense/perception/face_identity.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/vision/face_alignment.hpp"

#include <optional>
#include <set>

namespace dreamsense::face_identity {
namespace {

class FaceIdentityAnalyzer : public Analyzer {
 public:
  FaceIdentityAnalyzer(FaceIdentityAnalyzerOptions o, IdentityFeatureExtractor e, FaceIdentifier id)
      : options_(std::move(o)), extractor_(std::move(e)), identifier_(std::move(id)) {}

  std::string_view name() const override { return "face_identity"; }
  AnalyzerContract contract() const override {
    return {{},
            options_.cameras,
            {keys::kFaceLandmarks.name},
            {keys::kFaceIdentity.name},
            {keys::kFaceTracks.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto lm = prior.get(keys::kFaceLandmarks);
    if (!lm || lm->stamp != in.stamp) return ok_status();
    if (!lm->present()) {
      last_.reset();
      out.set_absent(keys::kFaceIdentity, in.stamp);
      return ok_status();
    }
    const FaceLandmarks& l = *lm->value;
    int track = -1;
    if (const auto tracks = prior.get(keys::kFaceTracks);
        tracks && tracks->present() && !tracks->value->tracks.empty())
      track = tracks->value->tracks.front().id;
    const FramePtr f = in.frame(l.camera);
    const ColorImage* img = f ? f->as<ColorImage>() : nullptr;
    if (img == nullptr) {
      out.set_absent(keys::kFaceIdentity, in.stamp);
      return ok_status();
    }
    if (last_ && last_->track_id == track &&
        (f->stamp - last_->frame_stamp).seconds() < options_.refresh_s &&
        f->stamp >= last_->frame_stamp) {
      FaceIdentity reused = *last_;
      reused.refreshed = false;
      out.set(keys::kFaceIdentity, std::move(reused), in.stamp, lm->confidence);
      return ok_status();
    }
    DS_ASSIGN_OR_RETURN(vision::FaceRegion region, vision::face_region(img->image, l.points_px));
    const cv::Mat& grey = region.grey;
    std::optional<vision::AlignedFace> face;
    if (!grey.empty()) {
      DS_ASSIGN_OR_RETURN(
          face, vision::align_face(grey, region.landmarks, extractor_.method().alignment));
    }
    if (!face) {
      out.set_absent(keys::kFaceIdentity, in.stamp);
      return ok_status();
    }
    const IdentityResult r = identifier_.identify(extractor_.extract(grey, *face));
    FaceIdentity id;
    id.id = r.id;
    if (options_.include_names) id.name = r.name;  // ids only by default (privacy)
    id.score = r.score;
    id.best_id = r.best_id;
    id.track_id = track;
    id.method = extractor_.method().name;
    id.camera = l.camera;
    id.frame_stamp = f->stamp;
    id.refreshed = true;
    last_ = id;
    out.set(keys::kFaceIdentity, std::move(id), in.stamp, lm->confidence);
    return ok_status();
  }

  void reset() override { last_.reset(); }

 private:
  FaceIdentityAnalyzerOptions options_;
  IdentityFeatureExtractor extractor_;
  FaceIdentifier identifier_;
  std::optional<FaceIdentity> last_;
};

}  // namespace

Status FaceIdentityAnalyzerOptions::check() const {
  std::set<SensorId> seen;
  for (const SensorId& c : cameras)
    if (c.empty() || !seen.insert(c).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "FaceIdentityAnalyzerOptions: empty or repeated camera id '{}'", c);
  if (gallery.empty())
    return make_error(ErrorCode::kInvalidArgument, "FaceIdentityAnalyzerOptions: no gallery file");
  if (!(refresh_s >= 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "FaceIdentityAnalyzerOptions: refresh_s must be >= 0");
  return ok_status();
}

Result<std::unique_ptr<Analyzer>> make_face_identity_analyzer(
    const FaceIdentityAnalyzerOptions& options) {
  DS_RETURN_IF_ERROR(options.check());
  DS_ASSIGN_OR_RETURN(auto gallery, FaceGallery::load(options.gallery));
  if (gallery.empty())
    return make_error(ErrorCode::kInvalidArgument, "{}: the face gallery is empty (enroll faces)",
                      options.gallery.string());
  DS_ASSIGN_OR_RETURN(auto extractor,
                      IdentityFeatureExtractor::create(gallery.method(), options.face_api_dir));
  if (auto s = check_compatible(gallery, extractor); !s)
    return make_error(s.error().code, "{}: {}", options.gallery.string(), s.error().message);
  DS_ASSIGN_OR_RETURN(auto identifier, FaceIdentifier::create(std::move(gallery)));
  {  // The network's first run sets up its layers (~1 s): done here, not on the first live face.
    auto lm = vision::mean_face_landmarks(100);
    for (auto& p : lm) p += cv::Point2d(50, 50);
    const cv::Mat blank(200, 200, CV_8UC1, cv::Scalar(128));
    DS_ASSIGN_OR_RETURN(auto face, vision::align_face(blank, lm, extractor.method().alignment));
    if (face) (void)extractor.extract(blank, *face);
  }
  return std::unique_ptr<Analyzer>(
      new FaceIdentityAnalyzer(options, std::move(extractor), std::move(identifier)));
}

}  // namespace dreamsense::face_identity
