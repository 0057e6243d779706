// dlib 68-point landmarker. dlib headers stay in this file (they are slow to compile).
//
// dlib::shape_predictor::operator() rounds its output to integer pixels (dlib::point). To keep
// sub-pixel landmarks (they matter for head pose on ~100 px faces) the model is deserialised
// into the same members, in the same order, as dlib's own deserialize(shape_predictor&), the
// trees are flattened into contiguous arrays (speed), and the cascade is evaluated with dlib's
// public impl:: functions and the same arithmetic as operator(), without the final rounding.

#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/perception/face_landmarks.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <dlib/image_processing/shape_predictor.h>
#include <dlib/opencv/cv_image.h>
#include <fstream>
#include <mutex>
#include <utility>
#include <vector>

namespace dreamsense::face_landmarks {
namespace {

// One cascade level's regression trees, flattened: every tree has the same number of splits and
// leaves (dlib trains complete trees of one depth; checked at load), so a tree's splits and its
// leaves are found by arithmetic, without the pointer chasing of dlib's vectors of vectors.
struct TreeLevel {
  struct Split {
    uint32_t idx1 = 0, idx2 = 0;  // feature pixels compared
    float thresh = 0;
  };
  size_t trees = 0, splits_per_tree = 0, leaves_per_tree = 0;
  std::vector<Split> splits;  // trees x splits_per_tree, dlib's node order
  std::vector<float> leaves;  // trees x leaves_per_tree x shape size (empty when quantised)
  // DlibLandmarkerOptions::quantized_leaves: the same leaves as int16, one scale per leaf (its
  // largest |value| maps to 32767): value = quantized x leaf_scales[leaf].
  std::vector<int16_t> quantized;
  std::vector<float> leaf_scales;  // trees x leaves_per_tree

  // Replaces `leaves` by `quantized` and `leaf_scales`.
  void quantize(size_t n) {
    quantized.resize(leaves.size());
    leaf_scales.resize(leaves.size() / n);
    for (size_t l = 0; l < leaf_scales.size(); ++l) {
      const float* v = &leaves[l * n];
      float largest = 0;
      for (size_t j = 0; j < n; ++j) largest = std::max(largest, std::abs(v[j]));
      const float scale = largest > 0 ? largest / 32767.f : 1.f;
      leaf_scales[l] = scale;
      for (size_t j = 0; j < n; ++j)
        quantized[l * n + j] = static_cast<int16_t>(std::lround(v[j] / scale));
    }
    std::vector<float>().swap(leaves);
  }
};

struct ShapeModel {
  dlib::matrix<float, 0, 1> initial_shape;  // mean shape in box-normalised coordinates
  std::vector<TreeLevel> levels;
  std::vector<std::vector<unsigned long>> anchor_idx;
  std::vector<std::vector<dlib::vector<float, 2>>> deltas;
  cv::Rect2d mean_extent;  // bounding box of the mean shape (box-normalised)

  bool quantized = false;  // levels hold int16 leaves (TreeLevel::quantize)

  // dlib's shape_predictor::operator() without the rounding, on the flattened trees. The trees of
  // one level depend only on that level's feature pixels, so all of them are walked first (the
  // same comparisons as dlib's regression_tree::operator()) and their leaves prefetched, then the
  // leaves are added in tree order: the same float additions in the same order as dlib's
  // `shape += tree(...)`, i.e. identical output, but the leaf loads (~65 MB of leaves, nearly
  // every one a cache miss) overlap instead of stalling one after the other. Quantised leaves
  // (half the bytes to load) are scaled and added in the same order.
  template <typename Image>
  std::vector<cv::Point2d> predict(const Image& img, const dlib::rectangle& rect) const {
    dlib::matrix<float, 0, 1> shape = initial_shape;
    const size_t n = static_cast<size_t>(shape.size());
    std::vector<float> feature_pixel_values;
    std::vector<size_t> leaf_offsets;  // of each tree's leaf in the level, in values
    for (size_t iter = 0; iter < levels.size(); ++iter) {
      dlib::impl::extract_feature_pixel_values(img, rect, shape, initial_shape, anchor_idx[iter],
                                               deltas[iter], feature_pixel_values);
      const TreeLevel& level = levels[iter];
      const float* values = feature_pixel_values.data();
      leaf_offsets.resize(level.trees);
      for (size_t t = 0; t < level.trees; ++t) {
        const TreeLevel::Split* split = &level.splits[t * level.splits_per_tree];
        size_t i = 0;
        while (i < level.splits_per_tree)
          i = values[split[i].idx1] - values[split[i].idx2] > split[i].thresh ? 2 * i + 1
                                                                              : 2 * i + 2;
        const size_t offset = (t * level.leaves_per_tree + (i - level.splits_per_tree)) * n;
        leaf_offsets[t] = offset;
        if (quantized) {
          for (size_t j = 0; j < n; j += 32) __builtin_prefetch(&level.quantized[offset + j]);
        } else {
          for (size_t j = 0; j < n; j += 16) __builtin_prefetch(&level.leaves[offset + j]);
        }
      }
      float* __restrict s = &shape(0);
      if (quantized) {
        for (size_t offset : leaf_offsets) {
          const int16_t* __restrict leaf = &level.quantized[offset];
          const float scale = level.leaf_scales[offset / n];
          for (size_t j = 0; j < n; ++j) s[j] += scale * static_cast<float>(leaf[j]);
        }
      } else {
        for (size_t offset : leaf_offsets) {
          const float* __restrict leaf = &level.leaves[offset];
          for (size_t j = 0; j < n; ++j) s[j] += leaf[j];
        }
      }
    }
    const dlib::point_transform_affine to_img = dlib::impl::unnormalizing_tform(rect);
    std::vector<cv::Point2d> out(shape.size() / 2);
    for (size_t i = 0; i < out.size(); ++i) {
      const dlib::vector<double, 2> p = to_img(dlib::impl::location(shape, i));
      out[i] = {p.x(), p.y()};
    }
    return out;
  }
};

// dlib rectangles are inclusive integer boxes.
dlib::rectangle to_dlib(const cv::Rect2d& b) {
  return dlib::rectangle(std::lround(b.x), std::lround(b.y), std::lround(b.x + b.width - 1),
                         std::lround(b.y + b.height - 1));
}

// iBUG 68-point index of each point's mirror image (left/right swapped).
constexpr std::array<int, 68> kMirror68{
    16, 15, 14, 13, 12, 11, 10, 9,  8,  7,  6,  5,  4, 3, 2, 1, 0,  // jaw
    26, 25, 24, 23, 22, 21, 20, 19, 18, 17,                         // brows
    27, 28, 29, 30, 35, 34, 33, 32, 31,                             // nose
    45, 44, 43, 42, 47, 46, 39, 38, 37, 36, 41, 40,                 // eyes
    54, 53, 52, 51, 50, 49, 48, 59, 58, 57, 56, 55,                 // outer lips
    64, 63, 62, 61, 60, 67, 66, 65};                                // inner lips

double median_of(std::vector<double>& v) {
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(m), v.end());
  if (v.size() % 2 == 1) return v[m];
  return 0.5 * (v[m] + *std::max_element(v.begin(), v.begin() + static_cast<long>(m)));
}

class DlibLandmarker final : public Landmarker {
 public:
  DlibLandmarker(DlibLandmarkerOptions o, ShapeModel m)
      : options_(std::move(o)), model_(std::move(m)) {}
  std::string_view name() const override { return "dlib_68"; }
  int point_count() const override { return static_cast<int>(model_.initial_shape.size() / 2); }

  Result<std::optional<std::vector<cv::Point2d>>> fit(const cv::Mat& image,
                                                      const cv::Rect2d& box) const override {
    auto f = fit_with_spread(image, box);
    if (!f) return tl::unexpected(f.error());
    if (!*f) return std::optional<std::vector<cv::Point2d>>{};
    return std::optional<std::vector<cv::Point2d>>{std::move((*f)->points)};
  }

  cv::Rect2d box_for_extent(const cv::Rect2d& e) const override {
    const cv::Rect2d& m = model_.mean_extent;
    const double w = e.width / m.width, h = e.height / m.height;
    return {e.x - m.x * w, e.y - m.y * h, w, h};
  }

  Result<std::optional<LandmarkFit>> fit_with_spread(const cv::Mat& image,
                                                     const cv::Rect2d& box) const override {
    if (image.type() != CV_8UC3 && image.type() != CV_8UC1)
      return make_error(ErrorCode::kInvalidArgument,
                        "DlibLandmarker: image type {} (need CV_8UC3 BGR or CV_8UC1)",
                        image.type());
    using Out = std::optional<LandmarkFit>;
    if (image.empty() || !(box.width >= options_.min_box_px) || !(box.height > 0)) return Out{};
    const cv::Rect2d inside = box & cv::Rect2d(0, 0, image.cols, image.rows);
    if (inside.area() < options_.min_box_inside * box.area()) return Out{};
    {  // contrast: a uniform patch carries no landmark information
      cv::Mat patch = image(cv::Rect(inside) & cv::Rect(0, 0, image.cols, image.rows));
      if (patch.empty()) return Out{};
      cv::Mat grey;
      if (patch.channels() == 3)
        cv::cvtColor(patch, grey, cv::COLOR_BGR2GRAY);
      else
        grey = patch;
      cv::Scalar mean, sd;
      cv::meanStdDev(grey, mean, sd);
      if (sd[0] < options_.min_contrast) return Out{};
    }
    std::vector<std::vector<cv::Point2d>> fits;
    std::vector<cv::Point2d> previous_pass;
    auto run_on = [&](const cv::Mat& m, const cv::Rect2d& b) {
      // No copy: dlib views the cv::Mat buffer (const use only).
      if (m.type() == CV_8UC3) return run(dlib::cv_image<dlib::bgr_pixel>(m), b, &previous_pass);
      return run(dlib::cv_image<unsigned char>(m), b, &previous_pass);
    };
    std::vector<cv::Rect2d> boxes{box};
    for (double s : options_.box_scales)
      if (s != 1.0) {
        const cv::Point2d c(box.x + box.width / 2, box.y + box.height / 2);
        boxes.emplace_back(c.x - box.width * s / 2, c.y - box.height * s / 2, box.width * s,
                           box.height * s);
      }
    for (const cv::Rect2d& b : boxes) fits.push_back(run_on(image, b));
    const bool mirrored = options_.mirror && point_count() == 68;
    if (mirrored) {
      // Mirror a region around the box only (not the whole frame).
      const cv::Rect roi = cv::Rect(cv::Rect2d(box.x - box.width, box.y - box.height, 3 * box.width,
                                               3 * box.height)) &
                           cv::Rect(0, 0, image.cols, image.rows);
      cv::Mat flipped;
      cv::flip(image(roi), flipped, 1);
      const double right = roi.x + roi.width - 1;  // x -> right - x maps pixel columns
      for (const cv::Rect2d& b : boxes) {
        const cv::Rect2d fb(right - (b.x + b.width - 1), b.y - roi.y, b.width, b.height);
        std::vector<cv::Point2d> p = run_on(flipped, fb);
        std::vector<cv::Point2d> back(p.size());
        for (size_t i = 0; i < p.size(); ++i)
          back[static_cast<size_t>(kMirror68[i])] = {right - p[i].x, p[i].y + roi.y};
        fits.push_back(std::move(back));
      }
    }
    LandmarkFit out;
    if (fits.size() == 1) {
      out.points = std::move(fits.front());
    } else {
      out.points.resize(fits.front().size());
      std::vector<double> xs(fits.size()), ys(fits.size());
      for (size_t i = 0; i < out.points.size(); ++i) {
        for (size_t k = 0; k < fits.size(); ++k) xs[k] = fits[k][i].x, ys[k] = fits[k][i].y;
        out.points[i] = {median_of(xs), median_of(ys)};
      }
    }
    // Spread: the fits against the result; one initialisation: its last two passes.
    std::vector<std::vector<cv::Point2d>> others =
        fits.size() > 1 ? fits : std::vector<std::vector<cv::Point2d>>{};
    if (fits.size() == 1 && !previous_pass.empty()) others.push_back(previous_pass);
    if (!others.empty() && out.points.size() == 68) {
      const double d = cv::norm(out.points[36] - out.points[45]);
      double sum = 0;
      for (const auto& f : others)
        for (size_t i = 0; i < f.size(); ++i) sum += cv::norm(f[i] - out.points[i]);
      if (d > 0) out.spread = sum / static_cast<double>(others.size() * 68) / d;
    }
    return Out{std::move(out)};
  }

 private:
  // One initialisation: the cascade from `box`, then refit_passes re-derived boxes. The points of
  // the pass before the last are left in *before_last (empty without re-derivation).
  template <typename Image>
  std::vector<cv::Point2d> run(const Image& img, cv::Rect2d box,
                               std::vector<cv::Point2d>* before_last) const {
    std::vector<cv::Point2d> pts = model_.predict(img, to_dlib(box));
    before_last->clear();
    for (int pass = 0; pass < options_.refit_passes; ++pass) {
      // The box that maps the mean shape's extent onto the fitted points' extent.
      const cv::Rect2d next = box_for_extent(points_extent(pts));
      if (!(next.width >= options_.min_box_px) || !(next.height > 0)) break;
      box = next;
      *before_last = std::move(pts);
      pts = model_.predict(img, to_dlib(box));
    }
    return pts;
  }

  DlibLandmarkerOptions options_;
  ShapeModel model_;
};

}  // namespace

double spread_confidence(double spread, double spread_ok, double spread_bad) {
  if (std::isnan(spread)) return 1.0;
  if (!(spread_bad > spread_ok)) return spread <= spread_ok ? 1.0 : 0.0;
  return std::clamp((spread_bad - spread) / (spread_bad - spread_ok), 0.0, 1.0);
}

double mean_point_distance(const std::vector<cv::Point2d>& points,
                           const std::vector<cv::Point2d>& other) {
  DS_CHECK_EQ(points.size(), other.size());
  const double corners = cv::norm(points[36] - points[45]);
  if (!(corners > 0)) return std::numeric_limits<double>::infinity();
  double sum = 0;
  for (size_t i = 0; i < points.size(); ++i) sum += cv::norm(points[i] - other[i]);
  return sum / static_cast<double>(points.size()) / corners;
}

Result<std::optional<LandmarkFit>> Landmarker::fit_with_spread(const cv::Mat& image,
                                                               const cv::Rect2d& box_px) const {
  auto p = fit(image, box_px);
  if (!p) return tl::unexpected(p.error());
  if (!*p) return std::optional<LandmarkFit>{};
  LandmarkFit f;
  f.points = std::move(**p);
  return std::optional<LandmarkFit>{std::move(f)};
}

Status DlibLandmarkerOptions::check() const {
  std::string bad;
  if (model.empty()) bad += " model path empty;";
  if (refit_passes < 0 || refit_passes > 5) bad += " refit_passes must be in [0, 5];";
  if (!(min_box_px >= 8)) bad += " min_box_px must be >= 8;";
  if (!(min_contrast >= 0)) bad += " min_contrast must be >= 0;";
  if (!(min_box_inside > 0 && min_box_inside <= 1)) bad += " min_box_inside must be in (0, 1];";
  for (double s : box_scales)
    if (!(s >= 0.5 && s <= 2)) bad += " box_scales must be in [0.5, 2];";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "DlibLandmarkerOptions:{}", bad);
  return ok_status();
}

Result<std::unique_ptr<Landmarker>> make_dlib_landmarker(const DlibLandmarkerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (!std::filesystem::exists(options.model))
    return make_error(ErrorCode::kNotFound,
                      "{}: dlib landmark model not found (install the Debian package "
                      "libdlib-data, or set DlibLandmarkerOptions::model)",
                      options.model.string());
  std::ifstream in(options.model, std::ios::binary);
  if (!in)
    return make_error(ErrorCode::kIoError, "{}: cannot open the dlib landmark model",
                      options.model.string());
  ShapeModel m;
  std::vector<std::vector<dlib::impl::regression_tree>> forests;
  try {
    int version = 0;
    dlib::deserialize(version, in);
    if (version != 1)
      return make_error(ErrorCode::kUnsupported, "{}: shape_predictor version {} (expected 1)",
                        options.model.string(), version);
    dlib::deserialize(m.initial_shape, in);
    dlib::deserialize(forests, in);
    dlib::deserialize(m.anchor_idx, in);
    dlib::deserialize(m.deltas, in);
  } catch (const dlib::serialization_error& e) {
    return make_error(ErrorCode::kCorruptData, "{}: not a dlib shape_predictor ({})",
                      options.model.string(), e.what());
  }
  const auto n = static_cast<size_t>(m.initial_shape.size());
  bool consistent = n >= 2 && n % 2 == 0 && forests.size() == m.anchor_idx.size() &&
                    forests.size() == m.deltas.size();
  // Flatten every level (predict() relies on: complete trees of one shape per level, leaves of n
  // floats, split indices inside the level's feature pixels).
  for (size_t iter = 0; consistent && iter < forests.size(); ++iter) {
    TreeLevel level;
    level.trees = forests[iter].size();
    if (level.trees > 0) {
      level.splits_per_tree = forests[iter][0].splits.size();
      level.leaves_per_tree = forests[iter][0].leaf_values.size();
    }
    consistent = level.leaves_per_tree == level.splits_per_tree + 1;
    const size_t features = m.anchor_idx[iter].size();
    level.splits.reserve(level.trees * level.splits_per_tree);
    level.leaves.reserve(level.trees * level.leaves_per_tree * n);
    for (const auto& tree : forests[iter]) {
      consistent = consistent && tree.splits.size() == level.splits_per_tree &&
                   tree.leaf_values.size() == level.leaves_per_tree;
      for (const auto& sp : tree.splits) {
        consistent = consistent && sp.idx1 < features && sp.idx2 < features;
        level.splits.push_back(
            {static_cast<uint32_t>(sp.idx1), static_cast<uint32_t>(sp.idx2), sp.thresh});
      }
      for (const auto& leaf : tree.leaf_values) {
        consistent = consistent && static_cast<size_t>(leaf.size()) == n;
        if (consistent) level.leaves.insert(level.leaves.end(), leaf.begin(), leaf.end());
      }
    }
    std::vector<dlib::impl::regression_tree>().swap(forests[iter]);  // free as we go
    if (consistent && options.quantized_leaves) level.quantize(n);
    m.levels.push_back(std::move(level));
  }
  if (!consistent)
    return make_error(ErrorCode::kCorruptData, "{}: inconsistent shape_predictor",
                      options.model.string());
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (long i = 0; i < m.initial_shape.size() / 2; ++i) {
    x0 = std::min<double>(x0, m.initial_shape(2 * i)),
    x1 = std::max<double>(x1, m.initial_shape(2 * i));
    y0 = std::min<double>(y0, m.initial_shape(2 * i + 1));
    y1 = std::max<double>(y1, m.initial_shape(2 * i + 1));
  }
  m.mean_extent = cv::Rect2d(x0, y0, x1 - x0, y1 - y0);
  m.quantized = options.quantized_leaves;
  return std::unique_ptr<Landmarker>(new DlibLandmarker(options, std::move(m)));
}

Result<std::shared_ptr<const Landmarker>> shared_dlib_landmarker(
    const DlibLandmarkerOptions& options) {
  static std::mutex mutex;
  // A few entries at most (one per distinct options): a list compared with the options' ==.
  static std::vector<std::pair<DlibLandmarkerOptions, std::shared_ptr<const Landmarker>>> loaded;
  const std::lock_guard lock(mutex);
  for (const auto& [o, l] : loaded)
    if (o == options) return l;
  DS_ASSIGN_OR_RETURN(std::unique_ptr<Landmarker> made, make_dlib_landmarker(options));
  std::shared_ptr<const Landmarker> shared = std::move(made);
  loaded.emplace_back(options, shared);
  return shared;
}

}  // namespace dreamsense::face_landmarks
