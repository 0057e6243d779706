#pragma once
// Test support shared by face_landmarks and head_pose tests: a 3 s demo session (seed 3)
// generated once per test binary (testing/demo_cache.hpp), its face truth (docs/truth_format.md),
// and the face pipeline face_detection -> face_landmarks run once over it, cached per tick.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/face_detection/face_detection_analyzer.hpp"
#include "dreamsense/face_landmarks/face_landmarks_analyzer.hpp"
#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/sim/demo_session.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/testing/demo_cache.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <unistd.h>
#include <vector>

namespace dreamsense::face_testing {

inline const std::vector<SensorId> kCameras{"camera_left", "camera_middle", "camera_right"};

struct CameraTruth {
  bool visible = false;
  cv::Rect2d box;
  double yaw_deg = 0;
  cv::Point2d left_eye_px, right_eye_px;  // the child's own left / right eye
};
struct FaceTruth {
  cv::Vec3d head_position_m;
  double yaw_deg = 0, pitch_deg = 0, roll_deg = 0;
  cv::Vec3d head_gaze_dir;
  std::map<SensorId, CameraTruth> cameras;
};

inline std::map<int64_t, FaceTruth> read_face_truth(const std::filesystem::path& dir) {
  std::map<int64_t, FaceTruth> out;
  std::ifstream in(dir / "truth.jsonl");
  std::string line;
  auto vec3 = [](const nlohmann::json& j) {
    return cv::Vec3d(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
  };
  auto pt = [](const nlohmann::json& j) {
    return cv::Point2d(j[0].get<double>(), j[1].get<double>());
  };
  while (std::getline(in, line)) {
    const auto j = nlohmann::json::parse(line);
    if (j.at("type") != "face") continue;
    FaceTruth t;
    t.head_position_m = vec3(j.at("head_position_m"));
    t.yaw_deg = j.at("yaw_deg").get<double>();
    t.pitch_deg = j.at("pitch_deg").get<double>();
    t.roll_deg = j.at("roll_deg").get<double>();
    t.head_gaze_dir = vec3(j.at("head_gaze_dir"));
    for (const auto& [id, c] : j.at("cameras").items()) {
      CameraTruth ct;
      ct.visible = c.at("visible").get<bool>();
      const auto& b = c.at("box");
      ct.box = cv::Rect2d(b[0].get<double>(), b[1].get<double>(), b[2].get<double>(),
                          b[3].get<double>());
      ct.yaw_deg = c.at("yaw_deg").get<double>();
      if (c.contains("eyes_px") && !c.at("eyes_px").is_null()) {
        ct.left_eye_px = pt(c.at("eyes_px").at("left"));
        ct.right_eye_px = pt(c.at("eyes_px").at("right"));
      }
      t.cameras[id] = ct;
    }
    out[j.at("stamp_ns").get<int64_t>()] = std::move(t);
  }
  return out;
}

// Calls fn(tick) for each tick (the camera frames sharing one stamp), streaming.
template <typename Fn>
Status for_each_tick(const std::filesystem::path& dir, Fn&& fn) {
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
      mf.tick = n++;
      fn(mf);
      mf = MultiFrame{};
    }
    if (end) return ok_status();
    mf.stamp = (*f)->stamp;
    mf.frames[(*f)->sensor] = *f;
  }
}

// One tick of the face pipeline, as the blackboard held it.
struct TickResult {
  Timestamp stamp;
  std::optional<SelectedCamera> selected;
  std::optional<FaceLandmarks> landmarks;
  double landmark_ms = 0;  // wall time of the landmarks analyser in this tick
  const FaceTruth* truth = nullptr;
};

struct DemoRun {
  std::filesystem::path dir;
  std::map<int64_t, FaceTruth> truth;
  std::map<SensorId, CameraModel> cameras;
  std::vector<TickResult> ticks;
};

// Generates the demo (once per process) and runs detection + landmarks over it (once).
inline const DemoRun& demo_run(std::shared_ptr<const face_landmarks::Landmarker> landmarker) {
  static DemoRun run = [&] {
    DemoRun r;
    sim::DemoOptions o;
    o.seed = 3;
    o.duration_s = 3;
    auto dir = testing::cached_demo_session("s3_3s", o);
    if (!dir) throw std::runtime_error(dir.error().to_string());
    r.dir = *dir;
    r.truth = read_face_truth(r.dir);
    for (const SensorId& c : kCameras) {
      auto m = read_camera_model(r.dir / "calib" / (c + ".yaml"));
      if (!m) throw std::runtime_error(m.error().to_string());
      r.cameras[c] = *m;
    }
    auto det = face_detection::make_face_detection_analyzer();
    if (!det) throw std::runtime_error(det.error().to_string());
    auto lm = face_landmarks::make_face_landmarks_analyzer({}, landmarker);
    if (!lm) throw std::runtime_error(lm.error().to_string());
    Blackboard bb;
    auto s = for_each_tick(r.dir, [&](const MultiFrame& mf) {
      BlackboardWriter w1("face_detection");
      if (!(*det)->process(mf, bb.snapshot(), w1)) throw std::runtime_error("face_detection");
      bb.commit(w1, mf.stamp);
      BlackboardWriter w2("face_landmarks");
      const auto t0 = std::chrono::steady_clock::now();
      if (!(*lm)->process(mf, bb.snapshot(), w2)) throw std::runtime_error("face_landmarks");
      const auto t1 = std::chrono::steady_clock::now();
      bb.commit(w2, mf.stamp);
      const BlackboardView v = bb.snapshot();
      TickResult t;
      t.stamp = mf.stamp;
      if (auto e = v.get(keys::kSelectedCamera); e && e->stamp == mf.stamp && e->present())
        t.selected = *e->value;
      if (auto e = v.get(keys::kFaceLandmarks); e && e->stamp == mf.stamp && e->present())
        t.landmarks = *e->value;
      t.landmark_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
      auto it = r.truth.find(mf.stamp.ns());
      if (it != r.truth.end()) t.truth = &it->second;
      r.ticks.push_back(std::move(t));
    });
    if (!s) throw std::runtime_error(s.error().to_string());
    return r;
  }();
  return run;
}

inline double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace dreamsense::face_testing
