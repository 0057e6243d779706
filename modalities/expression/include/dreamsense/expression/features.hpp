#pragma once
// Descriptors of an aligned face for expression recognition, in named blocks that a model lists:
//   lbp1     uniform LBP(8,1) histograms (59 bins) on a grid x grid layout of the crop (DREAM's
//            FaceAnalysis descriptor: elbp + spatial_histogram, 8 x 8 grid)
//   lbp2     the same with radius 2 (multi-scale LBP)
//   hog      histograms of oriented gradients of the crop (vision/descriptors.hpp)
//   geometry the 68 landmarks in crop coordinates (136 values) and a 0/1 "landmarks known" flag
//   face_api the 256 pooled features and 7 logits of face-api.js's expression network
//            (vision/face_api_net.hpp) on the same alignment re-sampled at 112 px; with
//            face_api_flip the mean of the face and its mirror image
//   face_api_box  the same network outputs on the package's own face crop (face_api_crop: the
//            landmarks' bounding box grown by 10 %, upright, padded to a square) instead of the
//            eye-aligned crop: a second view of the face (issue 20); without landmarks the
//            aligned crop

#include "dreamsense/core/status.hpp"
#include "dreamsense/vision/descriptors.hpp"
#include "dreamsense/vision/face_alignment.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::vision {
class FaceApiExpressionNet;
class FerXceptionNet;
}  // namespace dreamsense::vision

namespace dreamsense::expression {

inline constexpr const char* kFeatureBlocks[] = {"lbp1",     "lbp2",     "hog",
                                                 "geometry", "face_api", "face_api_box"};

struct ExpressionFeatureOptions {
  vision::AlignmentOptions alignment;  // canonical crop of the classical descriptors
  std::vector<std::string> blocks{"lbp1"};
  int lbp_grid = 8;       // cells per side
  bool lbp_sqrt = false;  // square root of the normalised histograms (Hellinger)
  vision::HogOptions hog;
  bool face_api_flip = true;
  // The network's folder (TF.js manifest + binary); empty: vision::default_face_api_model_dir().
  // A model file names it (`face_api_network`, relative to the model) when it ships its own
  // fine-tuned network (tools/train_fer_net.py).
  std::filesystem::path face_api_dir;
  Status check() const;
  bool uses(const std::string& block) const;
  bool uses_network() const { return uses("face_api") || uses("face_api_box"); }
};

// A small change of a face's crop for feature-level augmentation and test-time averaging: the
// mirror image, then a similarity about the crop centre (rotation, scale > 1 zooms in, shift in
// fractions of the crop side).
struct FaceJitter {
  bool mirror = false;
  double rotation_deg = 0, scale = 1, shift_x = 0, shift_y = 0;
  bool identity() const {
    return !mirror && rotation_deg == 0 && scale == 1 && shift_x == 0 && shift_y == 0;
  }
  bool operator==(const FaceJitter&) const = default;
};
// The face re-warped from `image_grey` (the image it was aligned from) with the jitter; landmarks
// follow. The identity returns `face`.
vision::AlignedFace jitter_face(const cv::Mat& image_grey, const vision::AlignedFace& face,
                                const FaceJitter& jitter);
// Named sets, joined by '+': "flip" (mirror image), "rot" (+-10 deg), "scale" (x1.1, x0.9),
// "shift" (+-5 % in x and in y). The result always starts with the identity and holds every
// combination of the mirror (when "flip") with the identity and each geometric jitter
// (e.g. flip+rot: 6 jitters). Unknown names are an error.
Result<std::vector<FaceJitter>> face_jitters(const std::string& sets);

// The `face_api_box` view's pixels: the package's crop (vision::face_api_crop) of the face's
// landmarks, cut from `image_grey` (the image `face` was aligned from); mirrored when `face`'s
// crop_from_image is. Without landmarks or with a degenerate box: the eye-aligned crop at the
// network's input size. Public so training tools see exactly the analyser's crop.
cv::Mat face_api_box_crop(const cv::Mat& image_grey, const vision::AlignedFace& face);

// Not thread-safe (the network): one per thread.
class ExpressionFeatureExtractor {
 public:
  // Loads the network when a block needs it (an error names the missing weights).
  static Result<ExpressionFeatureExtractor> create(const ExpressionFeatureOptions& options);
  ExpressionFeatureExtractor(ExpressionFeatureExtractor&&) noexcept;
  ExpressionFeatureExtractor& operator=(ExpressionFeatureExtractor&&) noexcept;
  ~ExpressionFeatureExtractor();

  // `image_grey`: the CV_8UC1 image `face` was aligned from (options().alignment geometry).
  std::vector<float> block(const std::string& name, const cv::Mat& image_grey,
                           const vision::AlignedFace& face);
  // The blocks of options().blocks, concatenated in that order.
  std::vector<float> extract(const cv::Mat& image_grey, const vision::AlignedFace& face);
  size_t block_length(const std::string& name) const;
  size_t length() const;
  const ExpressionFeatureOptions& options() const { return options_; }
  // Hash of the network weights (empty when no block uses it).
  std::string face_api_hash() const;

 private:
  ExpressionFeatureExtractor(ExpressionFeatureOptions options,
                             std::unique_ptr<vision::FaceApiExpressionNet> net);
  ExpressionFeatureOptions options_;
  std::unique_ptr<vision::FaceApiExpressionNet> net_;
};

}  // namespace dreamsense::expression
