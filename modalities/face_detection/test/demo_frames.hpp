#pragma once
// Test/bench support: camera frames and face truth of a demo session (docs/truth_format.md), and
// the three face metrics that `eval session` reports (README.md "Metrics").

#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/sim/demo_session.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::face_detection::testing {

inline const std::vector<SensorId> kCameras{"camera_left", "camera_middle", "camera_right"};

struct CameraTruth {
  bool visible = false;
  cv::Rect2d box;
  double yaw_deg = 0;
};
struct FaceTruth {
  int64_t stamp_ns = 0;
  std::optional<SensorId> best_camera;
  std::map<SensorId, CameraTruth> cameras;
};

struct DemoFrames {
  std::vector<MultiFrame> ticks;       // one per camera frame index (25 Hz)
  std::map<int64_t, FaceTruth> truth;  // by stamp_ns
};

// The face analysers' own scene: the original gestures (the hands never near the face). The
// default demo's drive_car changes camera selection on this 3 s clip (0.92); over whole sessions
// it is measured by `eval session` (modalities/actions/README.md "Demo").
inline sim::DemoOptions face_demo_options(double duration_s, uint64_t seed) {
  sim::DemoOptions o;
  o.seed = seed;
  o.duration_s = duration_s;
  o.script.gestures = sim::DemoScriptOptions::GestureSet::kClassic;
  return o;
}

// Generates a demo session into `dir` unless it already holds one.
inline Status ensure_demo(const std::filesystem::path& dir, double duration_s, uint64_t seed) {
  if (std::filesystem::exists(dir / "session.yaml")) return ok_status();
  sim::DemoOptions o = face_demo_options(duration_s, seed);
  o.out_dir = dir;
  o.overwrite = true;
  auto r = sim::generate_demo_session(o);
  if (!r) return tl::unexpected(r.error());
  return ok_status();
}

inline std::map<int64_t, FaceTruth> read_face_truth(const std::filesystem::path& dir) {
  std::map<int64_t, FaceTruth> out;
  std::ifstream in(dir / "truth.jsonl");
  std::string line;
  while (std::getline(in, line)) {
    const auto j = nlohmann::json::parse(line);
    if (j.at("type") != "face") continue;
    FaceTruth t;
    t.stamp_ns = j.at("stamp_ns").get<int64_t>();
    if (!j.at("best_camera").is_null()) t.best_camera = j.at("best_camera").get<std::string>();
    for (const auto& [id, c] : j.at("cameras").items()) {
      CameraTruth ct;
      ct.visible = c.at("visible").get<bool>();
      const auto& b = c.at("box");
      ct.box = cv::Rect2d(b[0].get<double>(), b[1].get<double>(), b[2].get<double>(),
                          b[3].get<double>());
      ct.yaw_deg = c.at("yaw_deg").get<double>();
      t.cameras[id] = ct;
    }
    out[t.stamp_ns] = std::move(t);
  }
  return out;
}

// Calls `fn(tick)` for each tick (the three camera frames with one stamp), streaming, so a long
// session never sits in memory. Stops after `max_ticks`.
template <typename Fn>
Status for_each_tick(const std::filesystem::path& dir, Fn&& fn, size_t max_ticks = SIZE_MAX) {
  sources::SessionReaderOptions ro;
  ro.only = kCameras;
  auto reader = sources::SessionReader::open(dir, ro);
  if (!reader) return tl::unexpected(reader.error());
  MultiFrame mf;
  size_t n = 0;
  for (;;) {
    auto f = (*reader)->next();
    if (!f && f.error().code != ErrorCode::kEndOfStream) return tl::unexpected(f.error());
    const bool end = !f;
    if (!mf.frames.empty() && (end || (*f)->stamp != mf.stamp)) {
      mf.tick = n;
      fn(mf);
      if (++n >= max_ticks) return ok_status();
      mf = MultiFrame{};
    }
    if (end) return ok_status();
    mf.stamp = (*f)->stamp;
    mf.frames[(*f)->sensor] = *f;
  }
}

// Decodes the first `max_ticks` ticks of the demo session in `dir` (a 20 s session is 1500
// 1280x960 images, 5.5 GB: stream it instead).
inline Result<DemoFrames> load_demo(const std::filesystem::path& dir, size_t max_ticks = SIZE_MAX) {
  DemoFrames out;
  auto s = for_each_tick(
      dir, [&](const MultiFrame& mf) { out.ticks.push_back(mf); }, max_ticks);
  if (!s) return tl::unexpected(s.error());
  out.truth = read_face_truth(dir);
  return out;
}

// A detection matches the truth face when the truth face is visible and the detection's box
// centre lies inside the truth box.
inline bool matches(const DetectedFace& f, const CameraTruth& t) {
  const cv::Point2d c(f.box_px.x + f.box_px.width / 2, f.box_px.y + f.box_px.height / 2);
  return t.visible && t.box.contains(c);
}

struct FaceMetrics {
  int positives = 0, hits = 0;           // camera frames with a visible face, |yaw| <= max_yaw
  int camera_frames = 0, fp_frames = 0;  // all searched camera frames; those with a false face
  int selection_ticks = 0, selection_exact = 0, selection_ok = 0;
  double recall() const { return positives ? double(hits) / positives : 1.0; }
  double false_positive_rate() const {
    return camera_frames ? double(fp_frames) / camera_frames : 0;
  }
  double selection_exact_rate() const {
    return selection_ticks ? double(selection_exact) / selection_ticks : 1.0;
  }
  double selection_accuracy() const {
    return selection_ticks ? double(selection_ok) / selection_ticks : 1.0;
  }
};

// Accumulates one tick: `detections` / `selected` as read from the blackboard (nullopt / null
// value = absent entry), `searched` = cameras that had a frame in the tick.
inline void accumulate(FaceMetrics& m, const FaceTruth& truth,
                       const std::vector<SensorId>& searched, const FaceDetections* detections,
                       const SelectedCamera* selected, double max_yaw_deg = 45,
                       double tie_margin_deg = 10) {
  for (const SensorId& cam : searched) {
    const CameraTruth& t = truth.cameras.at(cam);
    const std::vector<DetectedFace>* faces = nullptr;
    if (detections != nullptr) {
      auto it = detections->cameras.find(cam);
      if (it != detections->cameras.end()) faces = &it->second.faces;
    }
    bool hit = false, false_face = false;
    if (faces != nullptr)
      for (const DetectedFace& f : *faces) (matches(f, t) ? hit : false_face) = true;
    ++m.camera_frames;
    m.fp_frames += false_face;
    if (t.visible && std::abs(t.yaw_deg) <= max_yaw_deg) {
      ++m.positives;
      m.hits += hit;
    }
  }
  if (truth.best_camera) {
    ++m.selection_ticks;
    if (selected != nullptr) {
      const bool exact = selected->camera == *truth.best_camera;
      const CameraTruth& st = truth.cameras.at(selected->camera);
      const double best_yaw = std::abs(truth.cameras.at(*truth.best_camera).yaw_deg);
      m.selection_exact += exact;
      m.selection_ok += exact || (st.visible && matches(selected->face, st) &&
                                  std::abs(st.yaw_deg) <= best_yaw + tie_margin_deg);
    }
  }
}

}  // namespace dreamsense::face_detection::testing
