// Table region, background model and blob detection in the top camera (see the header).

#include "dreamsense/objects/table_detector.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace dreamsense::objects {
namespace {

// Sum of absolute BGR differences to a colour.
cv::Mat l1_to_colour(const cv::Mat& bgr, const cv::Vec3f& c) {
  cv::Mat out(bgr.size(), CV_32F);
  for (int y = 0; y < bgr.rows; ++y) {
    const cv::Vec3b* p = bgr.ptr<cv::Vec3b>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < bgr.cols; ++x)
      o[x] = std::abs(p[x][0] - c[0]) + std::abs(p[x][1] - c[1]) + std::abs(p[x][2] - c[2]);
  }
  return out;
}

cv::Mat ellipse(int size) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                   cv::Size(std::max(1, size), std::max(1, size)));
}

}  // namespace

Status TableTopDetectorOptions::check() const {
  std::string bad;
  auto need = [&bad](bool ok, const char* what) {
    if (!ok) bad += bad.empty() ? what : std::string("; ") + what;
  };
  need(downscale == 1 || downscale == 2 || downscale == 4, "downscale must be 1, 2 or 4");
  need(foreground_threshold > 0, "foreground_threshold must be > 0");
  need(table_colour_tolerance > 0, "table_colour_tolerance must be > 0");
  need(background_rate >= 0 && background_rate <= 1, "background_rate must be in [0, 1]");
  need(min_area_px >= 1 && max_area_px > min_area_px, "need 1 <= min_area_px < max_area_px");
  need(edge_margin_px >= 0, "edge_margin_px must be >= 0");
  need(open_px >= 1 && close_px >= 1, "open_px and close_px must be >= 1");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "table-top detector: {}", bad);
  return ok_status();
}

TableTopDetector::TableTopDetector(TableTopDetectorOptions options) : o_(options) {}

void TableTopDetector::reset() {
  table_.release();
  inner_.release();
  background_.release();
  frame_size_ = {};
}

cv::Mat TableTopDetector::shrink(const cv::Mat& bgr) const {
  if (o_.downscale == 1) return bgr;
  cv::Mat s;
  cv::resize(bgr, s, cv::Size(bgr.cols / o_.downscale, bgr.rows / o_.downscale), 0, 0,
             cv::INTER_AREA);
  return s;
}

cv::Mat TableTopDetector::table_mask() const {
  if (table_.empty()) return {};
  cv::Mat m;
  cv::resize(table_, m, frame_size_, 0, 0, cv::INTER_NEAREST);
  return m;
}

Status TableTopDetector::initialise(const cv::Mat& bgr, const std::vector<cv::Point2f>& polygon) {
  if (auto s = o_.check(); !s) return s;
  if (bgr.empty() || bgr.type() != CV_8UC3)
    return make_error(ErrorCode::kInvalidArgument, "table-top detector: need a BGR frame");
  frame_size_ = bgr.size();
  const cv::Mat small = shrink(bgr);
  const int ds = o_.downscale;
  // The table's colour: the most frequent colour (16 levels per channel) of the image centre.
  const cv::Rect centre(small.cols / 4, small.rows / 4, small.cols / 2, small.rows / 2);
  std::vector<int> hist(4096, 0);
  for (int y = centre.y; y < centre.br().y; ++y) {
    const cv::Vec3b* p = small.ptr<cv::Vec3b>(y);
    for (int x = centre.x; x < centre.br().x; ++x)
      ++hist[static_cast<size_t>((p[x][0] >> 4) << 8 | (p[x][1] >> 4) << 4 | (p[x][2] >> 4))];
  }
  const int mode = static_cast<int>(std::max_element(hist.begin(), hist.end()) - hist.begin());
  cv::Vec3d sum(0, 0, 0);
  int n = 0;
  for (int y = centre.y; y < centre.br().y; ++y) {
    const cv::Vec3b* p = small.ptr<cv::Vec3b>(y);
    for (int x = centre.x; x < centre.br().x; ++x)
      if (((p[x][0] >> 4) << 8 | (p[x][1] >> 4) << 4 | (p[x][2] >> 4)) == mode)
        sum += cv::Vec3d(p[x][0], p[x][1], p[x][2]), ++n;
  }
  const cv::Vec3f table_colour(static_cast<float>(sum[0] / n), static_cast<float>(sum[1] / n),
                               static_cast<float>(sum[2] / n));
  cv::Mat coloured = l1_to_colour(small, table_colour) < o_.table_colour_tolerance;
  if (polygon.size() >= 3) {
    table_ = cv::Mat::zeros(small.size(), CV_8U);
    std::vector<cv::Point> poly;
    for (const auto& p : polygon)
      poly.emplace_back(static_cast<int>(std::lround((p.x + 0.5) / ds - 0.5)),
                        static_cast<int>(std::lround((p.y + 0.5) / ds - 0.5)));
    cv::fillConvexPoly(table_, poly, cv::Scalar(255));
  } else {
    cv::Mat closed;
    cv::morphologyEx(coloured, closed, cv::MORPH_CLOSE, ellipse(5));
    cv::Mat labels, stats, centroids;
    const int count = cv::connectedComponentsWithStats(closed, labels, stats, centroids, 8, CV_32S);
    int best = 0, best_area = 0;
    for (int i = 1; i < count; ++i)
      if (stats.at<int>(i, cv::CC_STAT_AREA) > best_area)
        best = i, best_area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (best == 0 || best_area < static_cast<int>(small.total() / 20))
      return make_error(ErrorCode::kNotFound,
                        "table-top detector: no table-coloured region covering 5% of the image");
    std::vector<cv::Point> pts;
    cv::findNonZero(labels == best, pts);
    std::vector<cv::Point> hull;
    cv::convexHull(pts, hull);
    table_ = cv::Mat::zeros(small.size(), CV_8U);
    cv::fillConvexPoly(table_, hull, cv::Scalar(255));
  }
  const int margin =
      std::max(1, static_cast<int>(std::lround(static_cast<double>(o_.edge_margin_px) / ds)));
  // The image border counts as the table's edge too (a table that fills the view).
  cv::erode(table_, inner_, ellipse(2 * margin + 1), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
            cv::Scalar(0));
  // Background: table-coloured pixels, holes filled from their neighbourhood.
  cv::Mat known = coloured & table_;
  cv::Mat img, w;
  small.convertTo(img, CV_32FC3);
  known.convertTo(w, CV_32F, 1.0 / 255);
  cv::Mat weighted;
  cv::Mat w3;
  cv::merge(std::vector<cv::Mat>{w, w, w}, w3);
  cv::multiply(img, w3, weighted);
  const int k = std::max(9, (small.cols / 8) | 1);
  cv::Mat num, den;
  cv::boxFilter(weighted, num, CV_32F, cv::Size(k, k), cv::Point(-1, -1), false);
  cv::boxFilter(w, den, CV_32F, cv::Size(k, k), cv::Point(-1, -1), false);
  background_.create(small.size(), CV_32FC3);
  for (int y = 0; y < small.rows; ++y) {
    const float* kn = w.ptr<float>(y);
    const cv::Vec3f* im = img.ptr<cv::Vec3f>(y);
    const cv::Vec3f* nu = num.ptr<cv::Vec3f>(y);
    const float* de = den.ptr<float>(y);
    cv::Vec3f* b = background_.ptr<cv::Vec3f>(y);
    for (int x = 0; x < small.cols; ++x)
      b[x] = kn[x] > 0.5f ? im[x] : de[x] > 0.5f ? nu[x] / de[x] : table_colour;
  }
  return ok_status();
}

Result<std::vector<ObjectCandidate>> TableTopDetector::detect(
    const cv::Mat& bgr, const std::vector<cv::Rect>& occupied) {
  if (bgr.empty() || bgr.type() != CV_8UC3)
    return make_error(ErrorCode::kInvalidArgument, "table-top detector: need a BGR frame");
  if (!initialised()) {
    if (auto s = initialise(bgr); !s) return tl::unexpected(s.error());
  } else if (bgr.size() != frame_size_) {
    return make_error(ErrorCode::kInvalidArgument,
                      "table-top detector: frame {}x{} differs from the first {}x{}", bgr.cols,
                      bgr.rows, frame_size_.width, frame_size_.height);
  }
  const int ds = o_.downscale;
  small_ = shrink(bgr);
  // Foreground: colour far from the background, inside the table.
  fg_.create(small_.size(), CV_8U);
  const float thr = static_cast<float>(o_.foreground_threshold);
  for (int y = 0; y < small_.rows; ++y) {
    const cv::Vec3b* p = small_.ptr<cv::Vec3b>(y);
    const cv::Vec3f* b = background_.ptr<cv::Vec3f>(y);
    const uchar* t = table_.ptr<uchar>(y);
    uchar* f = fg_.ptr<uchar>(y);
    for (int x = 0; x < small_.cols; ++x) {
      const float d =
          std::abs(p[x][0] - b[x][0]) + std::abs(p[x][1] - b[x][1]) + std::abs(p[x][2] - b[x][2]);
      f[x] = t[x] && d > thr ? 255 : 0;
    }
  }
  cv::morphologyEx(fg_, fg_, cv::MORPH_OPEN, ellipse(o_.open_px));
  cv::morphologyEx(fg_, fg_, cv::MORPH_CLOSE, ellipse(o_.close_px));
  const int count = cv::connectedComponentsWithStats(fg_, labels_, stats_, centroids_, 8, CV_32S);
  // Components that reach the table's border band.
  std::vector<char> edge(static_cast<size_t>(count), 0);
  for (int y = 0; y < labels_.rows; ++y) {
    const int* l = labels_.ptr<int>(y);
    const uchar* in = inner_.ptr<uchar>(y);
    for (int x = 0; x < labels_.cols; ++x)
      if (l[x] > 0 && !in[x]) edge[static_cast<size_t>(l[x])] = 1;
  }
  std::vector<ObjectCandidate> out;
  const double area_scale = static_cast<double>(ds) * ds;
  for (int i = 1; i < count; ++i) {
    const double area = stats_.at<int>(i, cv::CC_STAT_AREA) * area_scale;
    if (area < o_.min_area_px || area > o_.max_area_px) continue;
    const cv::Rect sb(stats_.at<int>(i, cv::CC_STAT_LEFT), stats_.at<int>(i, cv::CC_STAT_TOP),
                      stats_.at<int>(i, cv::CC_STAT_WIDTH), stats_.at<int>(i, cv::CC_STAT_HEIGHT));
    ObjectCandidate c;
    c.box = cv::Rect(sb.x * ds, sb.y * ds, sb.width * ds, sb.height * ds) &
            cv::Rect(0, 0, frame_size_.width, frame_size_.height);
    c.area_px = area;
    c.touches_edge = edge[static_cast<size_t>(i)] != 0;
    c.centroid = cv::Point2d((centroids_.at<double>(i, 0) + 0.5) * ds - 0.5,
                             (centroids_.at<double>(i, 1) + 0.5) * ds - 0.5);
    const cv::Mat blob = labels_(sb) == i;
    cv::resize(blob, c.mask, c.box.size(), 0, 0, cv::INTER_NEAREST);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(blob, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    std::vector<cv::Point> pts;
    for (const auto& k : contours) pts.insert(pts.end(), k.begin(), k.end());
    cv::RotatedRect r = cv::minAreaRect(pts);
    r.center =
        cv::Point2f((r.center.x + sb.x + 0.5f) * ds - 0.5f, (r.center.y + sb.y + 0.5f) * ds - 0.5f);
    r.size = cv::Size2f((r.size.width + 1) * ds, (r.size.height + 1) * ds);
    c.footprint = r;
    out.push_back(std::move(c));
  }
  // Background update: pixels of the table that are not foreground (with a margin) and not in
  // an occupied box.
  cv::dilate(fg_, learn_, ellipse(5));
  cv::bitwise_not(learn_, learn_);
  cv::bitwise_and(learn_, table_, learn_);
  for (const auto& r : occupied) {
    const cv::Rect s(r.x / ds - 2, r.y / ds - 2, r.width / ds + 5, r.height / ds + 5);
    learn_(s & cv::Rect(0, 0, learn_.cols, learn_.rows)).setTo(0);
  }
  if (o_.background_rate > 0)
    cv::accumulateWeighted(small_, background_, o_.background_rate, learn_);
  return out;
}

}  // namespace dreamsense::objects
