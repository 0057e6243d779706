#include "dreamsense/face_detection/face_detector.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace dreamsense::face_detection {
namespace {

struct Cluster {
  cv::Rect2d box;  // detection-image pixels
  int neighbours = 0;
};

// Groups raw cascade windows as cv::groupRectangles does (similarity eps 0.2, clusters of at least
// `min_neighbors` windows, small clusters inside a stronger one dropped), but keeps the counts.
std::vector<Cluster> group_windows(const std::vector<cv::Rect>& windows, int min_neighbors) {
  if (windows.empty()) return {};  // cv::partition indexes element 0 of its input
  std::vector<int> labels;
  const int n = cv::partition(windows, labels, [](const cv::Rect& a, const cv::Rect& b) {
    const double d = 0.2 * 0.5 * (std::min(a.width, b.width) + std::min(a.height, b.height));
    return std::abs(a.x - b.x) <= d && std::abs(a.y - b.y) <= d &&
           std::abs(a.x + a.width - b.x - b.width) <= d &&
           std::abs(a.y + a.height - b.y - b.height) <= d;
  });
  std::vector<cv::Vec4d> sums(n, cv::Vec4d(0, 0, 0, 0));
  std::vector<int> counts(n, 0);
  for (size_t i = 0; i < windows.size(); ++i) {
    const cv::Rect& r = windows[i];
    sums[labels[i]] += cv::Vec4d(r.x, r.y, r.width, r.height);
    ++counts[labels[i]];
  }
  std::vector<Cluster> clusters;
  for (int k = 0; k < n; ++k) {
    if (counts[k] < min_neighbors) continue;
    const cv::Vec4d m = sums[k] / counts[k];
    clusters.push_back({cv::Rect2d(m[0], m[1], m[2], m[3]), counts[k]});
  }
  std::vector<Cluster> kept;
  for (size_t i = 0; i < clusters.size(); ++i) {
    const cv::Rect2d& r1 = clusters[i].box;
    bool inside = false;
    for (size_t j = 0; j < clusters.size() && !inside; ++j) {
      if (i == j) continue;
      const cv::Rect2d& r2 = clusters[j].box;
      const double dx = r2.width * 0.2, dy = r2.height * 0.2;
      inside = clusters[j].neighbours > std::max(3, clusters[i].neighbours) && r1.x >= r2.x - dx &&
               r1.y >= r2.y - dy && r1.x + r1.width <= r2.x + r2.width + dx &&
               r1.y + r1.height <= r2.y + r2.height + dy;
    }
    if (!inside) kept.push_back(clusters[i]);
  }
  return kept;
}

cv::Mat to_grey(const cv::Mat& m) {
  if (m.channels() == 1) return m;
  cv::Mat g;
  cv::cvtColor(m, g, m.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return g;
}

// Raw windows of `cascade` on `grey` with sizes in [min_size, max_size] (detection pixels).
std::vector<cv::Rect> raw_windows(cv::CascadeClassifier& cascade, const cv::Mat& grey,
                                  double scale_factor, int min_size, int max_size) {
  std::vector<cv::Rect> windows;
  std::vector<int> levels;
  std::vector<double> weights;
  if (grey.empty() || max_size < min_size) return windows;
  // outputRejectLevels with minNeighbors 0: every window that passed all stages, ungrouped.
  cascade.detectMultiScale(grey, windows, levels, weights, scale_factor, 0, 0,
                           cv::Size(min_size, min_size), cv::Size(max_size, max_size), true);
  // OpenCV's parallel search appends windows in the order its threads finish: sorted, the
  // clusters' sums (and so the boxes, to the last bit) do not depend on the scheduling.
  std::sort(windows.begin(), windows.end(), [](const cv::Rect& a, const cv::Rect& b) {
    return std::tie(a.y, a.x, a.width, a.height) < std::tie(b.y, b.x, b.width, b.height);
  });
  return windows;
}

}  // namespace

double box_iou(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

Status FaceDetectorOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (frontal_cascade.empty()) add("frontal_cascade is empty");
  if (use_profile && profile_cascade.empty()) add("use_profile with an empty profile_cascade");
  if (detection_width < 32) add(fmt::format("detection_width {} < 32", detection_width));
  if (!(scale_factor > 1.0 && scale_factor < 2.0))
    add(fmt::format("scale_factor {} not in (1, 2)", scale_factor));
  if (min_neighbors < 1) add(fmt::format("min_neighbors {} < 1", min_neighbors));
  if (!(min_face_px > 0)) add(fmt::format("min_face_px {} <= 0", min_face_px));
  if (max_face_px != 0 && max_face_px < min_face_px)
    add(fmt::format("max_face_px {} < min_face_px {}", max_face_px, min_face_px));
  if (!(score_neighbours > 0)) add(fmt::format("score_neighbours {} <= 0", score_neighbours));
  if (!(min_score >= 0 && min_score <= 1))
    add(fmt::format("min_score {} not in [0, 1]", min_score));
  if (estimate_frontalness) {
    if (frontalness_stretches.empty()) add("frontalness_stretches is empty");
    for (double s : frontalness_stretches)
      if (!(s >= 0.25 && s <= 4)) add(fmt::format("frontalness stretch {} not in [0.25, 4]", s));
    if (!(frontalness_patch_px >= 24))
      add(fmt::format("frontalness_patch_px {} < 24", frontalness_patch_px));
    if (!(frontalness_log_range > 0))
      add(fmt::format("frontalness_log_range {} <= 0", frontalness_log_range));
  }
  if (!(profile_frontalness >= 0 && profile_frontalness <= 1))
    add(fmt::format("profile_frontalness {} not in [0, 1]", profile_frontalness));
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "FaceDetectorOptions: " + bad);
  return ok_status();
}

struct FaceDetector::Impl {
  FaceDetectorOptions options;
  cv::CascadeClassifier frontal, profile;
  int frontal_window = 20, profile_window = 20;

  // Faces in a detection-scale grey image `small` (offset `origin` and factor k to full
  // resolution), sizes [min_px, max_px] in full-resolution pixels.
  void detect_small(const cv::Mat& small, cv::Point origin, int k, double min_px, double max_px,
                    std::vector<DetectedFace>& out) {
    const int min_frontal = std::max(frontal_window, static_cast<int>(std::floor(min_px / k)));
    const int max_size = static_cast<int>(std::ceil(max_px / k));
    auto to_full = [&](const cv::Rect2d& r) {
      return cv::Rect2d((r.x + origin.x) * k, (r.y + origin.y) * k, r.width * k, r.height * k);
    };
    auto score_of = [&](int n) {
      return static_cast<float>(1.0 - std::exp(-n / options.score_neighbours));
    };
    const size_t before = out.size();
    for (const Cluster& c :
         group_windows(raw_windows(frontal, small, options.scale_factor, min_frontal, max_size),
                       options.min_neighbors))
      out.push_back({to_full(c.box), score_of(c.neighbours), FaceView::kFrontal, 1.f});
    if (!options.use_profile || out.size() > before) return;
    const int min_profile = std::max(profile_window, static_cast<int>(std::floor(min_px / k)));
    for (const Cluster& c :
         group_windows(raw_windows(profile, small, options.scale_factor, min_profile, max_size),
                       options.min_neighbors))
      out.push_back({to_full(c.box), score_of(c.neighbours), FaceView::kProfileNoseLeft,
                     options.profile_frontalness});
    cv::Mat mirrored;
    cv::flip(small, mirrored, 1);
    for (const Cluster& c :
         group_windows(raw_windows(profile, mirrored, options.scale_factor, min_profile, max_size),
                       options.min_neighbors)) {
      cv::Rect2d r = c.box;
      r.x = small.cols - r.x - r.width;
      out.push_back({to_full(r), score_of(c.neighbours), FaceView::kProfileNoseRight,
                     options.profile_frontalness});
    }
  }
};

Result<FaceDetector> FaceDetector::create(const FaceDetectorOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  auto load = [](cv::CascadeClassifier& c, const std::filesystem::path& p) -> Status {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec))
      return make_error(ErrorCode::kNotFound,
                        "face detector: cascade '{}' not found (install the Debian package "
                        "opencv-data)",
                        p.string());
    DS_ASSIGN_OR_RETURN(const cv::FileStorage file, open_file_storage(p));
    bool loaded = false;
    try {
      loaded = c.read(file.getFirstTopLevelNode());
    } catch (const std::exception&) {
      loaded = false;
    }
    if (!loaded || c.empty())
      return make_error(ErrorCode::kCorruptData, "face detector: cannot read cascade '{}'",
                        p.string());
    return ok_status();
  };
  if (auto s = load(impl->frontal, options.frontal_cascade); !s) return tl::unexpected(s.error());
  impl->frontal_window = std::max(impl->frontal.getOriginalWindowSize().width,
                                  impl->frontal.getOriginalWindowSize().height);
  if (options.use_profile) {
    if (auto s = load(impl->profile, options.profile_cascade); !s) return tl::unexpected(s.error());
    impl->profile_window = std::max(impl->profile.getOriginalWindowSize().width,
                                    impl->profile.getOriginalWindowSize().height);
  }
  return FaceDetector(std::move(impl));
}

FaceDetector::FaceDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FaceDetector::FaceDetector(FaceDetector&&) noexcept = default;
FaceDetector& FaceDetector::operator=(FaceDetector&&) noexcept = default;
FaceDetector::~FaceDetector() = default;
const FaceDetectorOptions& FaceDetector::options() const { return impl_->options; }

std::vector<DetectedFace> FaceDetector::detect(const cv::Mat& image,
                                               const std::optional<SearchRegion>& search,
                                               std::optional<bool> with_frontalness) {
  std::vector<DetectedFace> faces;
  if (image.empty() || image.depth() != CV_8U ||
      (image.channels() != 1 && image.channels() != 3 && image.channels() != 4))
    return faces;
  const FaceDetectorOptions& o = impl_->options;
  int k = std::max(1, (image.cols + o.detection_width - 1) / o.detection_width);
  // Around a tracked face: shrink so that the smallest face searched is ~ the cascade window
  // (cost grows with the face's size in pixels, not with the region's area).
  if (search && search->shrink_to_min_face && search->min_face_px > 0)
    k = std::max(k, static_cast<int>(std::floor(search->min_face_px / impl_->frontal_window)));
  // Work on a region aligned to the k x k grid, so a region is shrunk exactly as the full frame.
  cv::Rect region(0, 0, image.cols / k * k, image.rows / k * k);
  if (search) {
    const cv::Rect r = search->region_px;
    const int x0 = std::max(0, r.x / k * k), y0 = std::max(0, r.y / k * k);
    const int x1 = std::min(region.width, (r.x + r.width + k - 1) / k * k);
    const int y1 = std::min(region.height, (r.y + r.height + k - 1) / k * k);
    region = cv::Rect(x0, y0, std::max(0, x1 - x0), std::max(0, y1 - y0));
  }
  if (region.width < k * impl_->frontal_window || region.height < k * impl_->frontal_window)
    return faces;
  double min_px = o.min_face_px;
  double max_px = o.max_face_px > 0 ? o.max_face_px : image.rows;
  if (search && search->min_face_px > 0) min_px = std::max(min_px, search->min_face_px);
  if (search && search->max_face_px > 0) max_px = std::min(max_px, search->max_face_px);
  if (max_px < min_px) return faces;
  cv::Mat small;
  if (k == 1) {
    small = to_grey(image(region));
  } else {
    cv::Mat shrunk;
    cv::resize(image(region), shrunk, cv::Size(region.width / k, region.height / k), 0, 0,
               cv::INTER_AREA);
    small = to_grey(shrunk);
  }
  impl_->detect_small(small, cv::Point(region.x / k, region.y / k), k, min_px, max_px, faces);
  if (search) {
    const cv::Rect2d r(search->region_px);
    std::erase_if(faces, [&](const DetectedFace& f) {
      return !r.contains(
          cv::Point2d(f.box_px.x + f.box_px.width / 2, f.box_px.y + f.box_px.height / 2));
    });
  }
  for (DetectedFace& f : faces)
    if (f.view == FaceView::kFrontal)
      f.frontalness =
          with_frontalness.value_or(o.estimate_frontalness) ? frontalness(image, f.box_px) : 1.f;
  std::erase_if(faces, [&](const DetectedFace& f) { return f.score < o.min_score; });
  std::stable_sort(faces.begin(), faces.end(), [](const DetectedFace& a, const DetectedFace& b) {
    if (a.score != b.score) return a.score > b.score;
    if (a.box_px.x != b.box_px.x) return a.box_px.x < b.box_px.x;
    return a.box_px.y < b.box_px.y;
  });
  return faces;
}

float FaceDetector::frontalness(const cv::Mat& image, const cv::Rect2d& box) {
  const FaceDetectorOptions& o = impl_->options;
  if (image.empty() || box.width <= 0 || box.height <= 0) return 0.f;
  // The face with half a face of context left and right, a quarter above and below.
  const cv::Rect2d grown(box.x - 0.5 * box.width, box.y - 0.25 * box.height, 2.0 * box.width,
                         1.5 * box.height);
  const cv::Rect crop = cv::Rect(grown) & cv::Rect(0, 0, image.cols, image.rows);
  if (crop.width < 8 || crop.height < 8) return 0.f;
  const double sc = o.frontalness_patch_px / box.width;
  cv::Mat patch;
  cv::resize(image(crop), patch, cv::Size(), sc, sc, sc < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  patch = to_grey(patch);
  const int min_size =
      std::max(impl_->frontal_window, static_cast<int>(std::floor(0.625 * o.frontalness_patch_px)));
  const int max_size = static_cast<int>(std::ceil(1.45 * o.frontalness_patch_px));
  double sum_n = 0, sum_log = 0;
  for (double s : o.frontalness_stretches) {
    cv::Mat stretched;
    cv::resize(patch, stretched,
               cv::Size(std::max(1, static_cast<int>(std::lround(patch.cols * s))), patch.rows), 0,
               0, s < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
    const double n = static_cast<double>(
        raw_windows(impl_->frontal, stretched, 1.05, min_size, max_size).size());
    sum_n += n;
    sum_log += n * std::log(s);
  }
  if (sum_n <= 0) return 0.5f;  // no answer at any stretch: unknown
  const double c = std::max(0.0, sum_log / sum_n);
  return static_cast<float>(std::clamp(1.0 - c / o.frontalness_log_range, 0.0, 1.0));
}

}  // namespace dreamsense::face_detection
