// 300-W .pts reader, folder listing and the landmark metrics.

#include "dreamsense/eval/landmarks/landmarks_eval.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace dreamsense::eval::landmarks {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// A whole token as a finite double (from_chars: no locale, no partial parse).
std::optional<double> parse_number(const std::string& token) {
  double v = 0;
  const char* end = token.data() + token.size();
  auto [p, ec] = std::from_chars(token.data(), end, v);
  if (ec != std::errc() || p != end || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

}  // namespace

Result<std::vector<cv::Point2d>> read_pts(const std::filesystem::path& file, int expected_points) {
  const std::string f = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    return make_error(ErrorCode::kNotFound, fmt::format("{}: no such annotation file", f));
  std::ifstream in(file);
  if (!in) return make_error(ErrorCode::kIoError, fmt::format("{}: cannot open", f));
  std::vector<cv::Point2d> points;
  int declared = -1;
  bool in_braces = false, had_braces = false, closed = false;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    const std::string t = trim(line);
    if (t.empty()) continue;
    auto bad = [&](const std::string& what) {
      return make_error(ErrorCode::kCorruptData, fmt::format("{}:{}: {}", f, line_no, what));
    };
    if (closed) return bad("text after the closing '}'");
    if (t == "{") {
      if (had_braces || !points.empty()) return bad("unexpected '{'");
      in_braces = had_braces = true;
      continue;
    }
    if (t == "}") {
      if (!in_braces) return bad("'}' without '{'");
      in_braces = false;
      closed = true;
      continue;
    }
    if (const auto colon = t.find(':'); colon != std::string::npos) {
      if (had_braces || !points.empty())
        return bad(fmt::format("header line '{}' among the points", t));
      const std::string key = lower(trim(t.substr(0, colon)));
      const std::string value = trim(t.substr(colon + 1));
      const auto v = parse_number(value);
      if (key == "version") {
        if (!v || *v != 1) return bad(fmt::format("unsupported version '{}' (expected 1)", value));
      } else if (key == "n_points") {
        if (!v || *v < 1 || *v != std::floor(*v))
          return bad(fmt::format("n_points '{}' is not a positive integer", value));
        declared = static_cast<int>(*v);
      } else {
        return bad(fmt::format("unknown header key '{}'", key));
      }
      continue;
    }
    std::istringstream ss(t);
    std::string xs, ys, extra;
    if (!(ss >> xs >> ys) || (ss >> extra))
      return bad(fmt::format("'{}' is not a point (two numbers 'x y')", t));
    const auto x = parse_number(xs), y = parse_number(ys);
    if (!x || !y) return bad(fmt::format("'{}' is not a point (two numbers 'x y')", t));
    points.emplace_back(*x, *y);
  }
  if (in.bad()) return make_error(ErrorCode::kIoError, fmt::format("{}: read error", f));
  if (in_braces)
    return make_error(ErrorCode::kCorruptData, fmt::format("{}: missing the closing '}}'", f));
  if (declared >= 0 && static_cast<int>(points.size()) != declared)
    return make_error(ErrorCode::kCorruptData, fmt::format("{}: {} points but n_points says {}", f,
                                                           points.size(), declared));
  if (expected_points > 0 && static_cast<int>(points.size()) != expected_points)
    return make_error(ErrorCode::kCorruptData, fmt::format("{}: {} points (expected {})", f,
                                                           points.size(), expected_points));
  return points;
}

Result<std::vector<LandmarkItem>> list_300w(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, fmt::format("{}: no such folder", dir.string()));
  std::map<std::string, LandmarkItem> by_name;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (!e.is_regular_file()) continue;
    const std::string ext = lower(e.path().extension().string());
    const std::string stem = e.path().stem().string();
    if (ext == ".pts") {
      by_name[stem].pts = e.path();
    } else if (ext == ".jpg" || ext == ".jpeg" || ext == ".png") {
      LandmarkItem& it = by_name[stem];
      if (!it.image.empty())
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("{}: two images named {} ({} and {})", dir.string(), stem,
                                      it.image.filename().string(), e.path().filename().string()));
      it.image = e.path();
    }
  }
  if (ec) return make_error(ErrorCode::kIoError, fmt::format("{}: {}", dir.string(), ec.message()));
  std::vector<LandmarkItem> items;
  for (auto& [name, it] : by_name) {
    if (it.pts.empty())
      return make_error(ErrorCode::kNotFound,
                        fmt::format("{}: no annotation {}.pts beside it", it.image.string(), name));
    if (it.image.empty())
      return make_error(ErrorCode::kNotFound,
                        fmt::format("{}: no image {}.jpg/.png beside it", it.pts.string(), name));
    it.name = name;
    items.push_back(std::move(it));
  }
  if (items.empty())
    return make_error(ErrorCode::kNotFound,
                      fmt::format("{}: no NAME.jpg + NAME.pts pairs (300-W layout)", dir.string()));
  return items;
}

double outer_corner_distance(const std::vector<cv::Point2d>& truth) {
  if (truth.size() != 68) return 0;
  return cv::norm(truth[36] - truth[45]);
}

double nme_outer_corners(const std::vector<cv::Point2d>& predicted,
                         const std::vector<cv::Point2d>& truth) {
  const double d = outer_corner_distance(truth);
  if (predicted.size() != truth.size() || !(d > 0)) return std::nan("");
  double sum = 0;
  for (size_t i = 0; i < truth.size(); ++i) sum += cv::norm(predicted[i] - truth[i]);
  return sum / static_cast<double>(truth.size()) / d;
}

double eye_center_error(const std::vector<cv::Point2d>& predicted,
                        const std::vector<cv::Point2d>& truth) {
  const double d = outer_corner_distance(truth);
  if (predicted.size() != 68 || !(d > 0)) return std::nan("");
  auto centroid = [](const std::vector<cv::Point2d>& p, size_t first) {
    cv::Point2d c(0, 0);
    for (size_t i = first; i < first + 6; ++i) c += p[i];
    return c * (1.0 / 6.0);
  };
  const double right = cv::norm(centroid(predicted, 36) - centroid(truth, 36));
  const double left = cv::norm(centroid(predicted, 42) - centroid(truth, 42));
  return 0.5 * (right + left) / d;
}

int match_detection(const std::vector<cv::Rect2d>& boxes, const cv::Rect2d& truth_box,
                    double min_iou) {
  int best = -1;
  double best_iou = 0;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const double inter = (boxes[i] & truth_box).area();
    const double uni = boxes[i].area() + truth_box.area() - inter;
    const double iou = uni > 0 ? inter / uni : 0.0;
    if (iou >= min_iou && iou > best_iou) best = static_cast<int>(i), best_iou = iou;
  }
  return best;
}

}  // namespace dreamsense::eval::landmarks
