#include "dreamsense/eval/action_datasets.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>

namespace dreamsense::eval::actions {
namespace fs = std::filesystem;
using dreamsense::actions::SkeletonFrame;
using dreamsense::actions::SkeletonSequence;

namespace {

// Kinect SDK v1 / NITE order (UTKinect) -> core JointId.
constexpr std::array<JointId, kJointCount> kKinectSdkOrder = {
    JointId::kHipCenter,     JointId::kSpine,      JointId::kShoulderCenter, JointId::kHead,
    JointId::kShoulderLeft,  JointId::kElbowLeft,  JointId::kWristLeft,      JointId::kHandLeft,
    JointId::kShoulderRight, JointId::kElbowRight, JointId::kWristRight,     JointId::kHandRight,
    JointId::kHipLeft,       JointId::kKneeLeft,   JointId::kAnkleLeft,      JointId::kFootLeft,
    JointId::kHipRight,      JointId::kKneeRight,  JointId::kAnkleRight,     JointId::kFootRight};

// MSR Action3D "Real3D" order -> core JointId.
constexpr std::array<JointId, kJointCount> kMsrOrder = {
    JointId::kShoulderLeft, JointId::kShoulderRight, JointId::kShoulderCenter, JointId::kSpine,
    JointId::kHipLeft,      JointId::kHipRight,      JointId::kHipCenter,      JointId::kElbowLeft,
    JointId::kElbowRight,   JointId::kWristLeft,     JointId::kWristRight,     JointId::kHandLeft,
    JointId::kHandRight,    JointId::kKneeLeft,      JointId::kKneeRight,      JointId::kAnkleLeft,
    JointId::kAnkleRight,   JointId::kFootLeft,      JointId::kFootRight,      JointId::kHead};

const std::array<const char*, 20> kMsrLabels = {
    "high_arm_wave", "horizontal_arm_wave", "hammer",        "hand_catch",
    "forward_punch", "high_throw",          "draw_x",        "draw_tick",
    "draw_circle",   "hand_clap",           "two_hand_wave", "side_boxing",
    "bend",          "forward_kick",        "side_kick",     "jogging",
    "tennis_swing",  "tennis_serve",        "golf_swing",    "pick_up_throw"};

// Kinect camera axes (x to the sensor's left, y up, z forward) -> optical (x right, y down).
cv::Vec3d to_optical(double x, double y, double z) { return {-x, -y, z}; }

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    size_t j = i;
    while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

bool parse_double(std::string_view s, double& v) {
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (b != e && *b == '+') ++b;
  auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e;
}

bool parse_int(std::string_view s, int& v) {
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

Error line_error(const fs::path& file, int line, const std::string& what) {
  return Error{ErrorCode::kCorruptData, fmt::format("{}:{}: {}", file.string(), line, what)};
}

struct LabelSegment {
  std::string label;
  bool missing = false;  // "NaN NaN"
  int first = 0, last = 0;
};

// actionLabel.txt: "sSS_eEE" lines, each followed by "label: first last" lines.
Result<std::map<std::string, std::vector<LabelSegment>>> read_label_file(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open the label file", file.string());
  std::map<std::string, std::vector<LabelSegment>> out;
  static const std::regex kSeq(R"(s\d+_e\d+)");
  std::string line, current;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto tok = split(line);
    if (tok.empty()) continue;
    if (tok.size() == 1 && std::regex_match(std::string(tok[0]), kSeq)) {
      current = std::string(tok[0]);
      if (out.count(current))
        return tl::unexpected(line_error(file, n, "sequence " + current + " listed twice"));
      out[current];
      continue;
    }
    const size_t colon = line.find(':');
    if (colon == std::string::npos)
      return tl::unexpected(line_error(
          file, n, fmt::format("expected 'sSS_eEE' or 'label: first last', got '{}'", line)));
    if (current.empty())
      return tl::unexpected(line_error(file, n, "segment before any 'sSS_eEE' line"));
    LabelSegment s;
    const auto name = split(std::string_view(line).substr(0, colon));
    const auto nums = split(std::string_view(line).substr(colon + 1));
    if (name.size() != 1 || nums.size() != 2)
      return tl::unexpected(
          line_error(file, n, fmt::format("expected 'label: first last', got '{}'", line)));
    s.label = std::string(name[0]);
    if (nums[0] == "NaN" && nums[1] == "NaN") {
      s.missing = true;
    } else if (!parse_int(nums[0], s.first) || !parse_int(nums[1], s.last) || s.last < s.first) {
      return tl::unexpected(
          line_error(file, n, fmt::format("bad frame range '{} {}'", nums[0], nums[1])));
    }
    out[current].push_back(s);
  }
  if (out.empty())
    return make_error(ErrorCode::kCorruptData, "{}: no 'sSS_eEE' block found", file.string());
  return out;
}

}  // namespace

Result<std::vector<std::pair<int, SkeletonFrame>>> read_utkinect_joints(const fs::path& file,
                                                                        double rate) {
  std::ifstream in(file);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open", file.string());
  std::vector<std::pair<int, SkeletonFrame>> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const auto tok = split(line);
    if (tok.empty()) continue;
    if (tok.size() != 1 + 3 * kJointCount)
      return tl::unexpected(line_error(
          file, n,
          fmt::format("expected a frame id and {} coordinates (20 Kinect joints), got {} numbers",
                      3 * kJointCount, tok.size())));
    int id = 0;
    double idd = 0;
    if (!parse_int(tok[0], id)) {
      // Some copies write the id as a float ("190.000000").
      if (!parse_double(tok[0], idd) || idd != std::floor(idd) || idd < 0 || idd > 1e9)
        return tl::unexpected(line_error(file, n, fmt::format("bad frame id '{}'", tok[0])));
      id = static_cast<int>(idd);
    }
    SkeletonFrame f;
    f.stamp_ns = static_cast<int64_t>(std::llround(id * 1e9 / rate));
    for (int j = 0; j < kJointCount; ++j) {
      double v[3];
      for (int k = 0; k < 3; ++k)
        if (!parse_double(tok[static_cast<size_t>(1 + 3 * j + k)], v[k]))
          return tl::unexpected(line_error(
              file, n, fmt::format("joint {}: '{}' is not a number", j + 1, tok[1 + 3 * j + k])));
      JointObservation& o = f.joint(kKinectSdkOrder[static_cast<size_t>(j)]);
      o.position_m = to_optical(v[0], v[1], v[2]);
      const bool finite = std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
      o.confidence = finite ? 1.f : 0.f;
    }
    if (!out.empty() && id < out.back().first)
      return tl::unexpected(line_error(
          file, n,
          fmt::format("frame id {} after {} (ids must not decrease)", id, out.back().first)));
    if (!out.empty() && id == out.back().first) continue;  // repeated id: keep the first
    out.emplace_back(id, f);
  }
  if (out.empty()) return make_error(ErrorCode::kCorruptData, "{}: no frames", file.string());
  return out;
}

Result<ActionDataset> read_utkinect(const fs::path& dir, const UtkinectOptions& o) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound,
                      "{}: not a folder (utkinect: joints_sSS_eEE.txt + "
                      "actionLabel.txt)",
                      dir.string());
  fs::path labels = o.label_file;
  if (labels.empty())
    labels = fs::exists(dir / "actionLabel_modified.txt") ? dir / "actionLabel_modified.txt"
                                                          : dir / "actionLabel.txt";
  if (!fs::exists(labels))
    return make_error(ErrorCode::kNotFound,
                      "{}: label file missing (utkinect needs "
                      "actionLabel.txt)",
                      labels.string());
  auto blocks = read_label_file(labels);
  if (!blocks) return tl::unexpected(blocks.error());
  ActionDataset d;
  d.name = "utkinect";
  static const std::regex kFile(R"(joints_(s\d+)_(e\d+)\.txt)");
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (std::regex_match(name, kFile)) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<std::string> unlabelled;
  for (const auto& file : files) {
    std::smatch m;
    const std::string name = file.filename().string();
    std::regex_match(name, m, kFile);
    const std::string seq = m[1].str() + "_" + m[2].str();
    auto it = blocks->find(seq);
    if (it == blocks->end()) {
      unlabelled.push_back(name);
      continue;
    }
    auto frames = read_utkinect_joints(file, o.frame_rate_hz);
    if (!frames) return tl::unexpected(frames.error());
    for (const auto& s : it->second) {
      if (std::find(d.labels.begin(), d.labels.end(), s.label) == d.labels.end())
        d.labels.push_back(s.label);
      if (s.missing) {
        ++d.skipped;
        continue;
      }
      LabelledSequence item;
      item.label = s.label;
      item.subject = m[1].str();
      item.source = fmt::format("{} frames {}-{}", name, s.first, s.last);
      for (const auto& [id, f] : *frames)
        if (id >= s.first && id <= s.last) item.frames.push_back(f);
      if (item.frames.size() < 2) {
        ++d.skipped;
        continue;
      }
      d.items.push_back(std::move(item));
    }
  }
  if (d.items.empty())
    return make_error(ErrorCode::kNotFound,
                      "{}: no labelled joints_sSS_eEE.txt sequence (label file {})", dir.string(),
                      labels.filename().string());
  d.note = fmt::format("{} sequences, labels from {}, {} segments skipped (NaN or no frames)",
                       files.size() - unlabelled.size(), labels.filename().string(), d.skipped);
  if (!unlabelled.empty())
    d.note += fmt::format(", {} joint files without labels ignored", unlabelled.size());
  return d;
}

Result<SkeletonSequence> read_msr_skeleton(const fs::path& file, double rate) {
  std::ifstream in(file);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open", file.string());
  SkeletonSequence out;
  std::string line;
  int n = 0, joint = 0;
  SkeletonFrame f;
  bool any = false;
  while (std::getline(in, line)) {
    ++n;
    const auto tok = split(line);
    if (tok.empty()) continue;
    if (tok.size() != 4)
      return tl::unexpected(
          line_error(file, n, fmt::format("expected 'x y z c' (4 numbers), got {}", tok.size())));
    double v[4];
    for (int k = 0; k < 4; ++k)
      if (!parse_double(tok[static_cast<size_t>(k)], v[k]))
        return tl::unexpected(
            line_error(file, n, fmt::format("'{}' is not a number", tok[static_cast<size_t>(k)])));
    JointObservation& o = f.joint(kMsrOrder[static_cast<size_t>(joint)]);
    o.position_m = to_optical(v[0], v[1], v[2]);
    const bool finite = std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
    const bool zero = v[0] == 0 && v[1] == 0 && v[2] == 0;
    o.confidence = finite && !zero ? 1.f : 0.f;
    any = any || o.confidence > 0;
    if (++joint == kJointCount) {
      f.stamp_ns = static_cast<int64_t>(std::llround(static_cast<double>(out.size()) * 1e9 / rate));
      out.push_back(f);
      f = SkeletonFrame{};
      joint = 0;
    }
  }
  if (joint != 0)
    return make_error(ErrorCode::kCorruptData,
                      "{}:{}: truncated: the last frame has {} of 20 joint lines", file.string(), n,
                      joint);
  if (out.empty()) return make_error(ErrorCode::kCorruptData, "{}: no frames", file.string());
  if (!any) out.clear();  // all zeros: no data
  return out;
}

Result<ActionDataset> read_msr_action3d(const fs::path& dir, const MsrAction3dOptions& o) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound,
                      "{}: not a folder (msr-action3d: aXX_sYY_eZZ_skeleton3D.txt)", dir.string());
  static const std::regex kFile(R"(a(\d\d)_(s\d\d)_e(\d\d)_skeleton3D\.txt)");
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (std::regex_match(e.path().filename().string(), kFile)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ActionDataset d;
  d.name = "msr-action3d";
  d.labels.assign(kMsrLabels.begin(), kMsrLabels.end());
  for (const auto& file : files) {
    std::smatch m;
    const std::string name = file.filename().string();
    std::regex_match(name, m, kFile);
    const int a = std::stoi(m[1].str());
    if (a < 1 || a > 20)
      return make_error(ErrorCode::kCorruptData, "{}: action {} outside a01-a20", file.string(), a);
    auto seq = read_msr_skeleton(file, o.frame_rate_hz);
    if (!seq) return tl::unexpected(seq.error());
    if (seq->size() < 2) {
      ++d.skipped;
      continue;
    }
    d.items.push_back({kMsrLabels[static_cast<size_t>(a - 1)], m[2].str(), name, std::move(*seq)});
  }
  if (d.items.empty())
    return make_error(ErrorCode::kNotFound, "{}: no aXX_sYY_eZZ_skeleton3D.txt with frames",
                      dir.string());
  d.note = fmt::format("{} sequences, {} skipped (no usable frame)", files.size(), d.skipped);
  return d;
}

Result<ActionDataset> read_action_dataset(const std::string& name, const fs::path& dir) {
  if (name == "utkinect") return read_utkinect(dir);
  if (name == "msr-action3d") return read_msr_action3d(dir);
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown actions dataset '{}' (utkinect, msr-action3d)", name);
}

}  // namespace dreamsense::eval::actions
