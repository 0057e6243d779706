#include "dreamsense/expression/features.hpp"

#include "dreamsense/vision/face_api_net.hpp"
#include "dreamsense/vision/lbp.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::expression {

Status ExpressionFeatureOptions::check() const {
  if (auto s = alignment.check(); !s) return s;
  if (blocks.empty())
    return make_error(ErrorCode::kInvalidArgument, "expression features: no block");
  for (const std::string& b : blocks)
    if (std::find_if(std::begin(kFeatureBlocks), std::end(kFeatureBlocks),
                     [&](const char* k) { return b == k; }) == std::end(kFeatureBlocks))
      return make_error(ErrorCode::kInvalidArgument,
                        "expression features: unknown block '{}' (lbp1, lbp2, hog, geometry, "
                        "face_api, face_api_box)",
                        b);
  if (lbp_grid < 1 || lbp_grid > alignment.size / 4)
    return make_error(ErrorCode::kInvalidArgument, "expression features: lbp_grid {} out of range",
                      lbp_grid);
  if (uses("hog"))
    if (auto s = hog.check(cv::Size(alignment.size, alignment.size)); !s) return s;
  return ok_status();
}

bool ExpressionFeatureOptions::uses(const std::string& block) const {
  return std::find(blocks.begin(), blocks.end(), block) != blocks.end();
}

vision::AlignedFace jitter_face(const cv::Mat& image_grey, const vision::AlignedFace& face,
                                const FaceJitter& j) {
  if (j.identity()) return face;
  vision::AlignedFace g = j.mirror ? vision::mirror_face(face) : face;
  if (j.rotation_deg == 0 && j.scale == 1 && j.shift_x == 0 && j.shift_y == 0) return g;
  const double side = face.grey.cols, c = (side - 1) / 2.0;
  const double a = j.rotation_deg * CV_PI / 180.0;
  const double ca = j.scale * std::cos(a), sa = j.scale * std::sin(a);
  const cv::Matx33d m(ca, -sa, c - ca * c + sa * c + j.shift_x * side, sa, ca,
                      c - sa * c - ca * c + j.shift_y * side, 0, 0, 1);
  const cv::Matx23d& t = g.crop_from_image;
  const cv::Matx33d r =
      m * cv::Matx33d(t(0, 0), t(0, 1), t(0, 2), t(1, 0), t(1, 1), t(1, 2), 0, 0, 1);
  const cv::Matx23d crop_from_image(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2));
  vision::AlignedFace out = vision::warp_face(image_grey, crop_from_image,
                                              vision::AlignmentOptions{face.grey.cols}, g.source);
  out.landmarks = vision::transform_points(
      cv::Matx23d(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2)), g.landmarks);
  return out;
}

cv::Mat face_api_box_crop(const cv::Mat& image_grey, const vision::AlignedFace& face) {
  if (face.landmarks.size() == static_cast<size_t>(vision::kLandmarkCount68)) {
    cv::Matx23d image_from_crop;
    cv::invertAffineTransform(face.crop_from_image, image_from_crop);
    const cv::Rect box = vision::face_api_crop(
        vision::transform_points(image_from_crop, face.landmarks), image_grey.size());
    if (box.width >= 4 && box.height >= 4) {
      cv::Mat crop = image_grey(box).clone();
      const cv::Matx23d& t = face.crop_from_image;
      if (t(0, 0) * t(1, 1) - t(0, 1) * t(1, 0) < 0) cv::flip(crop, crop, 1);
      return crop;
    }
  }
  return vision::resample_face(image_grey, face, vision::kFaceApiInputPx);
}

Result<std::vector<FaceJitter>> face_jitters(const std::string& sets) {
  bool flip = false;
  std::vector<FaceJitter> geometric{FaceJitter{}};
  for (size_t start = 0; !sets.empty();) {
    const size_t plus = sets.find('+', start);
    const std::string name = sets.substr(start, plus - start);
    if (name == "flip") {
      flip = true;
    } else if (name == "rot") {
      for (double d : {10.0, -10.0}) geometric.push_back({false, d, 1, 0, 0});
    } else if (name == "scale") {
      for (double s : {1.1, 0.9}) geometric.push_back({false, 0, s, 0, 0});
    } else if (name == "shift") {
      for (double s : {0.05, -0.05}) geometric.push_back({false, 0, 1, s, 0});
      for (double s : {0.05, -0.05}) geometric.push_back({false, 0, 1, 0, s});
    } else {
      return make_error(ErrorCode::kInvalidArgument,
                        "unknown face jitter set '{}' (flip, rot, scale, shift)", name);
    }
    if (plus == std::string::npos) break;
    start = plus + 1;
  }
  std::vector<FaceJitter> out = geometric;
  if (flip)
    for (FaceJitter j : geometric) {
      j.mirror = true;
      out.push_back(j);
    }
  return out;
}

ExpressionFeatureExtractor::ExpressionFeatureExtractor(
    ExpressionFeatureOptions options, std::unique_ptr<vision::FaceApiExpressionNet> net)
    : options_(std::move(options)), net_(std::move(net)) {}
ExpressionFeatureExtractor::ExpressionFeatureExtractor(ExpressionFeatureExtractor&&) noexcept =
    default;
ExpressionFeatureExtractor& ExpressionFeatureExtractor::operator=(
    ExpressionFeatureExtractor&&) noexcept = default;
ExpressionFeatureExtractor::~ExpressionFeatureExtractor() = default;

Result<ExpressionFeatureExtractor> ExpressionFeatureExtractor::create(
    const ExpressionFeatureOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  std::unique_ptr<vision::FaceApiExpressionNet> net;
  if (options.uses_network()) {
    auto n = vision::FaceApiExpressionNet::load(
        options.face_api_dir.empty() ? vision::default_face_api_model_dir() : options.face_api_dir);
    if (!n) return tl::unexpected(n.error());
    net = std::make_unique<vision::FaceApiExpressionNet>(std::move(*n));
  }
  return ExpressionFeatureExtractor(options, std::move(net));
}

std::string ExpressionFeatureExtractor::face_api_hash() const {
  return net_ ? net_->weights_hash() : std::string();
}

size_t ExpressionFeatureExtractor::block_length(const std::string& name) const {
  const size_t cells = static_cast<size_t>(options_.lbp_grid * options_.lbp_grid);
  if (name == "lbp1" || name == "lbp2") return cells * vision::kUniformLbpBins;
  if (name == "hog")
    return vision::hog_length(cv::Size(options_.alignment.size, options_.alignment.size),
                              options_.hog);
  if (name == "geometry") return vision::kLandmarkGeometryLength + 1;
  if (name == "face_api" || name == "face_api_box") return vision::kFaceApiFeatures + 7;
  DS_CHECK(false);
  return 0;
}

size_t ExpressionFeatureExtractor::length() const {
  size_t n = 0;
  for (const std::string& b : options_.blocks) n += block_length(b);
  return n;
}

std::vector<float> ExpressionFeatureExtractor::block(const std::string& name,
                                                     const cv::Mat& image_grey,
                                                     const vision::AlignedFace& face) {
  const ExpressionFeatureOptions& o = options_;
  std::vector<float> out;
  out.reserve(block_length(name));
  if (name == "lbp1" || name == "lbp2") {
    const cv::Mat labels = vision::uniform_lbp_labels(face.grey, name == "lbp1" ? 1.0 : 2.0);
    vision::grid_histograms(labels, vision::kUniformLbpBins, o.lbp_grid, o.lbp_grid, o.lbp_sqrt,
                            out);
  } else if (name == "hog") {
    vision::hog_descriptor(face.grey, o.hog, out);
  } else if (name == "geometry") {
    vision::landmark_geometry(face.landmarks, o.alignment.size, o.alignment.eye_row, out);
    out.push_back(face.landmarks.empty() ? 0.f : 1.f);
  } else if (name == "face_api" || name == "face_api_box") {
    DS_CHECK(net_ != nullptr);
    const cv::Mat crop = name == "face_api"
                             ? vision::resample_face(image_grey, face, vision::kFaceApiInputPx)
                             : face_api_box_crop(image_grey, face);
    vision::FaceApiOutput r = net_->run(crop);
    if (o.face_api_flip) {
      cv::Mat mirrored;
      cv::flip(crop, mirrored, 1);
      const vision::FaceApiOutput m = net_->run(mirrored);
      for (size_t i = 0; i < r.features.size(); ++i)
        r.features[i] = 0.5f * (r.features[i] + m.features[i]);
      for (size_t i = 0; i < r.logits.size(); ++i) r.logits[i] = 0.5f * (r.logits[i] + m.logits[i]);
    }
    out = std::move(r.features);
    out.insert(out.end(), r.logits.begin(), r.logits.end());
  } else {
    DS_CHECK(false);
  }
  DS_CHECK_EQ(out.size(), block_length(name));
  return out;
}

std::vector<float> ExpressionFeatureExtractor::extract(const cv::Mat& image_grey,
                                                       const vision::AlignedFace& face) {
  std::vector<float> all;
  all.reserve(length());
  for (const std::string& b : options_.blocks) {
    const std::vector<float> v = block(b, image_grey, face);
    all.insert(all.end(), v.begin(), v.end());
  }
  return all;
}

}  // namespace dreamsense::expression
