// OTB and MIL sequence readers (see the header for the layouts).

#include "dreamsense/eval/tracking_datasets.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace dreamsense::eval {
namespace fs = std::filesystem;
namespace {

std::string shorten(std::string_view s) {
  std::string out(s.substr(0, 60));
  if (s.size() > 60) out += "...";
  return out;
}

bool is_image(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e == ".jpg" || e == ".jpeg" || e == ".png" || e == ".bmp" || e == ".pgm";
}

// The frame number in an image name (the last run of digits: "0001.jpg", "img00012.png").
std::optional<long> frame_number(const fs::path& p) {
  const std::string stem = p.stem().string();
  size_t end = stem.size();
  while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
  size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  if (begin == end) return std::nullopt;
  return std::stol(stem.substr(begin, end - begin));
}

// Numbered images of a folder, by frame number.
Result<std::map<long, fs::path>> numbered_images(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: image folder not found", dir.string());
  std::map<long, fs::path> out;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (!e.is_regular_file() || !is_image(e.path())) continue;
    if (auto n = frame_number(e.path())) out[*n] = e.path();
  }
  if (ec) return make_error(ErrorCode::kIoError, "{}: cannot list: {}", dir.string(), ec.message());
  if (out.empty())
    return make_error(ErrorCode::kNotFound, "{}: no numbered images (.jpg/.png)", dir.string());
  return out;
}

// Sequences of OTB known to start after the first image (OTB configSeqs startFrame).
int known_otb_start(const std::string& name) {
  static const std::map<std::string, int> starts = {
      {"David", 300}, {"Tiger1", 6}, {"BlurCar1", 247}, {"BlurCar3", 3}, {"BlurCar4", 18}};
  const auto it = starts.find(name);
  return it == starts.end() ? 0 : it->second;
}

bool is_otb_dir(const fs::path& d) {
  std::error_code ec;
  return fs::is_directory(d / "img", ec) && (fs::exists(d / "groundtruth_rect.txt", ec) ||
                                             fs::exists(d / "groundtruth_rect.1.txt", ec));
}

std::optional<fs::path> mil_gt_file(const fs::path& d, std::string* error = nullptr) {
  std::error_code ec;
  if (!fs::is_directory(d / "imgs", ec)) return std::nullopt;
  std::vector<fs::path> found;
  for (const auto& e : fs::directory_iterator(d, ec)) {
    const std::string n = e.path().filename().string();
    if (n.size() > 7 && n.ends_with("_gt.txt")) found.push_back(e.path());
  }
  if (found.size() > 1 && error) *error = "several *_gt.txt files";
  if (found.size() != 1) return std::nullopt;
  return found[0];
}

}  // namespace

size_t TrackingSequence::labelled() const {
  return static_cast<size_t>(
      std::count_if(truth.begin(), truth.end(), [](const auto& b) { return b.has_value(); }));
}

Result<std::optional<cv::Rect2d>> parse_box_line(std::string_view line, const std::string& file,
                                                 int line_number, double origin) {
  double v[4];
  int n = 0;
  size_t i = 0;
  auto separator = [](char c) { return c == ',' || c == ' ' || c == '\t' || c == '\r'; };
  while (i < line.size()) {
    while (i < line.size() && separator(line[i])) ++i;
    if (i >= line.size()) break;
    size_t j = i;
    while (j < line.size() && !separator(line[j])) ++j;
    const std::string token(line.substr(i, j - i));
    if (n == 4)
      return make_error(ErrorCode::kCorruptData,
                        "{}:{}: expected 4 numbers x,y,w,h (separated by commas, tabs or spaces), "
                        "got more: '{}'",
                        file, line_number, shorten(line));
    char* end = nullptr;
    const double x = std::strtod(token.c_str(), &end);
    if (end != token.c_str() + token.size() || !std::isfinite(x))
      return make_error(ErrorCode::kCorruptData, "{}:{}: '{}' is not a number (line '{}')", file,
                        line_number, shorten(token), shorten(line));
    v[n++] = x;
    i = j;
  }
  if (n != 4)
    return make_error(ErrorCode::kCorruptData,
                      "{}:{}: expected 4 numbers x,y,w,h (separated by commas, tabs or spaces), "
                      "got {}: '{}'",
                      file, line_number, n, shorten(line));
  if (v[2] < 0 || v[3] < 0)
    return make_error(ErrorCode::kCorruptData, "{}:{}: negative box size {} x {}", file,
                      line_number, v[2], v[3]);
  if (v[2] == 0 || v[3] == 0) return std::optional<cv::Rect2d>{};
  return std::optional<cv::Rect2d>(cv::Rect2d(v[0] - origin, v[1] - origin, v[2], v[3]));
}

Result<std::vector<std::optional<cv::Rect2d>>> read_box_file(const fs::path& file, double origin) {
  std::ifstream in(file);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open", file.string());
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  auto blank = [](const std::string& s) {
    return std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c); });
  };
  while (!lines.empty() && blank(lines.back())) lines.pop_back();
  std::vector<std::optional<cv::Rect2d>> boxes;
  for (size_t i = 0; i < lines.size(); ++i) {
    auto b = parse_box_line(lines[i], file.string(), static_cast<int>(i + 1), origin);
    if (!b) return tl::unexpected(b.error());
    boxes.push_back(*b);
  }
  if (boxes.empty()) return make_error(ErrorCode::kCorruptData, "{}: no boxes", file.string());
  return boxes;
}

Result<TrackingSequence> read_otb_sequence(const fs::path& dir, int start_frame) {
  TrackingSequence seq;
  seq.dir = dir;
  seq.name = fs::absolute(dir).lexically_normal().filename().string();
  if (seq.name.empty())
    seq.name = fs::absolute(dir).lexically_normal().parent_path().filename().string();
  fs::path gt = dir / "groundtruth_rect.txt";
  std::error_code ec;
  if (!fs::exists(gt, ec)) {
    gt = dir / "groundtruth_rect.1.txt";
    if (!fs::exists(gt, ec))
      return make_error(ErrorCode::kNotFound,
                        "{}: no groundtruth_rect.txt (OTB layout: img/ + "
                        "groundtruth_rect.txt)",
                        dir.string());
    seq.warnings.push_back(seq.name + ": several targets; using groundtruth_rect.1.txt");
  }
  auto images = numbered_images(dir / "img");
  if (!images) return tl::unexpected(images.error());
  auto boxes = read_box_file(gt, 1.0);
  if (!boxes) return tl::unexpected(boxes.error());
  const long first_image = images->begin()->first;
  long start = start_frame > 0 ? start_frame : first_image;
  if (start_frame <= 0 && boxes->size() < images->size()) {
    if (const int k = known_otb_start(seq.name); k > 0) start = k;
  }
  for (size_t i = 0; i < boxes->size(); ++i) {
    const auto it = images->find(start + static_cast<long>(i));
    if (it == images->end()) {
      seq.warnings.push_back(
          fmt::format("{}: {} boxes but no image for frame {}; the rest of "
                      "the ground truth is ignored",
                      gt.filename().string(), boxes->size(), start + static_cast<long>(i)));
      break;
    }
    seq.frames.push_back(it->second);
    seq.truth.push_back((*boxes)[i]);
  }
  if (seq.frames.size() < images->size() && seq.warnings.empty())
    seq.warnings.push_back(fmt::format("{}: {} boxes for {} images; frames {}..{} evaluated",
                                       gt.filename().string(), boxes->size(), images->size(), start,
                                       start + static_cast<long>(seq.frames.size()) - 1));
  if (seq.frames.empty())
    return make_error(ErrorCode::kCorruptData, "{}: no image matches the first box (frame {})",
                      gt.string(), start);
  return seq;
}

Result<TrackingSequence> read_mil_sequence(const fs::path& dir) {
  std::string why;
  const auto gt = mil_gt_file(dir, &why);
  if (!gt)
    return make_error(ErrorCode::kNotFound,
                      "{}: not a MIL sequence (imgs/ + NAME_gt.txt + NAME_frames.txt){}",
                      dir.string(), why.empty() ? "" : ": " + why);
  TrackingSequence seq;
  seq.dir = dir;
  const std::string gt_name = gt->filename().string();
  seq.name = gt_name.substr(0, gt_name.size() - 7);
  const fs::path frames_file = dir / (seq.name + "_frames.txt");
  std::ifstream in(frames_file);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open", frames_file.string());
  std::string line;
  std::getline(in, line);
  // "first,last" (two numbers): reuse the box tokenizer's separators.
  long first = 0, last = 0;
  {
    std::string t = line;
    std::replace_if(
        t.begin(), t.end(), [](char c) { return c == ',' || c == '\t' || c == '\r'; }, ' ');
    std::istringstream ss(t);
    std::string extra;
    if (!(ss >> first >> last) || (ss >> extra) || first < 0 || last < first)
      return make_error(ErrorCode::kCorruptData,
                        "{}:1: expected 'first,last' frame numbers, got '{}'", frames_file.string(),
                        shorten(line));
  }
  auto images = numbered_images(dir / "imgs");
  if (!images) return tl::unexpected(images.error());
  auto boxes = read_box_file(*gt, 0.0);
  if (!boxes) return tl::unexpected(boxes.error());
  const size_t n = static_cast<size_t>(last - first + 1);
  if (boxes->size() != n)
    seq.warnings.push_back(fmt::format("{}: {} boxes for frames {}..{} ({} frames)", gt_name,
                                       boxes->size(), first, last, n));
  for (size_t i = 0; i < n; ++i) {
    const auto it = images->find(first + static_cast<long>(i));
    if (it == images->end())
      return make_error(ErrorCode::kNotFound, "{}: frame {} (of {}..{} in {}) has no image",
                        (dir / "imgs").string(), first + static_cast<long>(i), first, last,
                        frames_file.filename().string());
    seq.frames.push_back(it->second);
    seq.truth.push_back(i < boxes->size() ? (*boxes)[i] : std::nullopt);
  }
  if (seq.labelled() == 0)
    return make_error(ErrorCode::kCorruptData, "{}: no labelled frame", gt->string());
  return seq;
}

Result<std::vector<TrackingSequence>> read_tracking_dataset(std::string_view dataset,
                                                            const fs::path& dir, int start_frame) {
  if (dataset != "otb" && dataset != "mil")
    return make_error(ErrorCode::kInvalidArgument,
                      "tracking dataset '{}' is not supported (supported: otb, mil)", dataset);
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: no such directory", dir.string());
  auto is_seq = [&](const fs::path& d) {
    return dataset == "otb" ? is_otb_dir(d)
                            : mil_gt_file(d).has_value() || fs::is_directory(d / "imgs", ec);
  };
  auto read = [&](const fs::path& d) {
    return dataset == "otb" ? read_otb_sequence(d, start_frame) : read_mil_sequence(d);
  };
  std::vector<TrackingSequence> out;
  if (is_seq(dir)) {
    auto s = read(dir);
    if (!s) return tl::unexpected(s.error());
    out.push_back(std::move(*s));
    return out;
  }
  std::vector<fs::path> subs;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_directory() && is_seq(e.path())) subs.push_back(e.path());
  std::sort(subs.begin(), subs.end());
  for (const auto& d : subs) {
    auto s = read(d);
    if (!s) return tl::unexpected(s.error());
    out.push_back(std::move(*s));
  }
  if (out.empty())
    return make_error(
        ErrorCode::kNotFound, "{}: no {} sequence ({})", dir.string(), dataset,
        dataset == "otb" ? "img/ + groundtruth_rect.txt" : "imgs/ + NAME_gt.txt + NAME_frames.txt");
  return out;
}

}  // namespace dreamsense::eval
