#pragma once
// Face identity (F17 identifyFace): descriptors of an aligned face, the enrolment gallery (a
// versioned file of features, not photos; ids, not names, unless a name map is added) and the
// identifier with unknown rejection. Methods (README.md has the numbers):
//   lbp_svm  DREAM's seed (FaceIDClassifier.xml): uniform LBP(8,1) histograms on an 8x8 grid of
//            the aligned face, linear SVMs (C = 0.1; one-vs-rest here), best margin as the score
//   lbp_tt   classical improvement: Tan-Triggs illumination normalisation, multi-scale uniform
//            LBP (R = 1, 2) grid histograms, square-rooted (Hellinger) and L2-normalised, nearest
//            enrolment image by cosine similarity
//   face_api pretrained metric network (face-api.js's port of dlib's ResNet face descriptor,
//            npm @vladmandic/face-api, vision/face_api_net.hpp): 128-D descriptor of the aligned
//            face re-sampled at 150 px, nearest enrolment image by Euclidean distance (score =
//            minus the distance; dlib's same-person rule is distance < 0.6)
// Unknown rejection (both): a threshold on the score chosen on the enrolment data only, by
// leave-one-out: every enrolment image is scored against the rest of the gallery as a genuine
// probe (its own person, minus itself) and as an impostor probe (its person removed); the
// threshold minimises false rejections + false accepts of those probes (midpoint of the best
// interval). A gallery too small for that (no person with two images, or one person) uses the
// method's default threshold.

#include "dreamsense/core/status.hpp"
#include "dreamsense/vision/descriptors.hpp"
#include "dreamsense/vision/face_alignment.hpp"
#include "dreamsense/vision/linear_classifier.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::face_identity {

inline constexpr int kFaceGalleryVersion = 1;

struct IdentityMethod {
  std::string name;  // "lbp_svm" | "lbp_tt" (+ ":modifier" in experiments)
  vision::AlignmentOptions alignment;
  bool tan_triggs = false;
  std::vector<double> lbp_radii{1.0};
  int lbp_grid = 8;
  bool lbp_sqrt = false;
  bool l2_normalise = false;
  bool face_api = false;  // descriptor of the pretrained network instead of LBP
  enum class Matcher { kSvm, kNearestCosine, kNearestEuclidean } matcher = Matcher::kSvm;
  vision::SvmOptions svm;
  // Score of a probe: the best person's similarity (or SVM margin), or with `margin_score` its
  // lead over the second-best person (an unknown face resembles several people about equally).
  bool margin_score = false;
  double default_threshold = 0;  // when the gallery cannot give one
  Status check() const;
};
inline constexpr const char* kIdentityMethods[] = {"face_api", "lbp_tt", "lbp_svm"};
Result<IdentityMethod> identity_method(const std::string& spec);
size_t identity_feature_length(const IdentityMethod& method);

// Descriptors of aligned faces (the method's alignment geometry). Holds the network when the
// method uses it: not thread-safe, one per thread.
class IdentityFeatureExtractor {
 public:
  // `face_api_dir` empty: vision::default_face_api_model_dir().
  static Result<IdentityFeatureExtractor> create(const IdentityMethod& method,
                                                 const std::filesystem::path& face_api_dir = {});
  IdentityFeatureExtractor(IdentityFeatureExtractor&&) noexcept;
  IdentityFeatureExtractor& operator=(IdentityFeatureExtractor&&) noexcept;
  ~IdentityFeatureExtractor();
  // `image_grey`: the image `face` was aligned from.
  std::vector<float> extract(const cv::Mat& image_grey, const vision::AlignedFace& face);
  const IdentityMethod& method() const { return method_; }
  std::string weights_hash() const;  // of the network; empty for LBP methods

 private:
  struct Net;
  IdentityFeatureExtractor(IdentityMethod m, std::unique_ptr<Net> net);
  IdentityMethod method_;
  std::unique_ptr<Net> net_;
};

struct EnrolledPerson {
  int id = -1;
  std::vector<std::vector<float>> features;  // one per enrolment image
};

class FaceGallery {
 public:
  // `weights_hash`: IdentityFeatureExtractor::weights_hash() of the enrolling extractor.
  explicit FaceGallery(IdentityMethod method = {}, std::string weights_hash = {})
      : method_(std::move(method)), weights_hash_(std::move(weights_hash)) {}
  // Adds descriptors (identity_features of the gallery's method) to person `id` (>= 0).
  Status add(int id, std::vector<float> features);
  // Optional id -> name map (names are only stored when given).
  void set_name(int id, std::string name) { names_[id] = std::move(name); }
  std::optional<std::string> name(int id) const;

  Status save(const std::filesystem::path& path) const;
  // Errors name the file: missing, not a gallery, another version or method (re-enrol).
  static Result<FaceGallery> load(const std::filesystem::path& path);

  const IdentityMethod& method() const { return method_; }
  const std::string& weights_hash() const { return weights_hash_; }
  const std::vector<EnrolledPerson>& persons() const { return persons_; }
  size_t images() const;
  bool empty() const { return persons_.empty(); }

 private:
  IdentityMethod method_;
  std::string weights_hash_;
  std::vector<EnrolledPerson> persons_;  // sorted by id
  std::map<int, std::string> names_;
};

// A gallery can only be matched with descriptors of its own method and network weights: an
// error naming both otherwise (enrol again).
Status check_compatible(const FaceGallery& gallery, const IdentityFeatureExtractor& extractor);

struct IdentityResult {
  int id = -1;       // -1 = unknown (score below the threshold, or empty gallery)
  std::string name;  // from the name map, else empty
  double score = 0;  // best person's score (SVM margin or cosine similarity)
  int best_id = -1;  // best person even when rejected
};

class FaceIdentifier {
 public:
  // Trains the matcher and chooses the threshold on the gallery (enrolment data only). An empty
  // gallery is an error (nothing to identify against).
  static Result<FaceIdentifier> create(FaceGallery gallery);
  // `features` from an extractor of the gallery's method (another length: unknown).
  IdentityResult identify(const std::vector<float>& features) const;
  double threshold() const { return threshold_; }
  bool threshold_from_enrolment() const { return threshold_from_enrolment_; }
  const FaceGallery& gallery() const { return gallery_; }

 private:
  explicit FaceIdentifier(FaceGallery g) : gallery_(std::move(g)) {}
  // Best person and score of `x` against the gallery, optionally without one person or image.
  std::pair<int, double> best_match(const std::vector<float>& x, int skip_person = -1,
                                    int skip_image_person = -1, size_t skip_image = 0) const;
  FaceGallery gallery_;
  vision::LinearClassifier svm_;  // kSvm: one row per person (gallery order)
  double threshold_ = 0;
  bool threshold_from_enrolment_ = false;
};

// The threshold rule (exposed for tests): minimises #(genuine < t) + #(impostor >= t), midpoint
// of the best interval; nullopt when either list is empty.
std::optional<double> choose_threshold(std::vector<double> genuine, std::vector<double> impostor);

}  // namespace dreamsense::face_identity
