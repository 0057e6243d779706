#pragma once
// Shared helpers of the session tests: a temp folder per test and a small synthetic session.

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace dreamsense::sources::test_util {

inline constexpr int kWidth = 64;
inline constexpr int kHeight = 48;
inline constexpr int kSampleRate = 16000;
inline constexpr int kChannels = 2;
inline constexpr int64_t kFramePeriodNs = 40'000'000;  // 25 Hz
inline constexpr int64_t kChunkFrames = 640;           // 40 ms of audio

// A fresh folder under the system temp dir, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "dreamsense_sources_";
    if (info != nullptr) name += std::string(info->test_suite_name()) + "_" + info->name() + "_";
    name += std::to_string(::getpid()) + "_" + std::to_string(counter++);
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Streams cam (mjpeg), depth (`depth_encoding`: raw16 or png16), skel (jsonl), mic (wav).
inline SessionManifest make_manifest(const std::string& depth_encoding = "raw16") {
  SessionManifest m;
  m.name = "unit";
  m.clock_origin_unix_ns = 1700000000000000000LL;
  m.participant.id = 7;
  m.participant.gender = "female";
  m.participant.age_months = 49.5;
  m.condition = "RET";
  m.task = "JA";
  m.frame_rate = 25;
  m.metadata["generator"] = "session_test";
  m.metadata["seed"] = "42";
  StreamEntry cam;
  cam.id = "cam";
  cam.kind = SensorKind::kColor;
  cam.encoding = "mjpeg";
  cam.rate_hz = 25;
  cam.width = kWidth;
  cam.height = kHeight;
  StreamEntry depth;
  depth.id = "depth";
  depth.kind = SensorKind::kDepth;
  depth.encoding = depth_encoding;
  depth.rate_hz = 25;
  depth.width = kWidth;
  depth.height = kHeight;
  StreamEntry skel;
  skel.id = "skel";
  skel.kind = SensorKind::kSkeleton;
  skel.encoding = "jsonl";
  skel.rate_hz = 25;
  StreamEntry mic;
  mic.id = "mic";
  mic.kind = SensorKind::kAudio;
  mic.encoding = "wav";
  mic.sample_rate = kSampleRate;
  mic.channels = kChannels;
  m.streams = {cam, depth, skel, mic};
  return m;
}

// Smooth colour gradient (JPEG-friendly), shifted by k.
inline cv::Mat color_frame(int k) {
  cv::Mat m(kHeight, kWidth, CV_8UC3);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      m.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(x * 3 + k % 40), static_cast<uchar>(y * 4 + (2 * k) % 40),
                    static_cast<uchar>(128));
  return m;
}

// A ramp plus the extreme values: 0 (no measurement) and 65535 in a few pixels.
inline cv::Mat depth_frame(int k) {
  cv::Mat m(kHeight, kWidth, CV_16UC1);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      m.at<uint16_t>(y, x) = static_cast<uint16_t>(500 + x + y * kWidth + k * 7);
  m.at<uint16_t>(0, 0) = 0;
  m.at<uint16_t>(0, 1) = 65535;
  m.at<uint16_t>(kHeight - 1, (k * 5) % kWidth) = 0;
  m.at<uint16_t>(k % kHeight, kWidth - 1) = 65535;
  return m;
}

inline Skeleton skeleton_frame(int k) {
  Skeleton s;
  SkeletonBody b;
  b.body_id = k % 3;
  for (int j = 0; j < kJointCount; ++j) {
    if (j % 4 == 3) continue;  // untracked
    b.joints[j].position_m = {0.1234567 * j - 1.0 + k * 0.001, -0.5 + 0.01 * k, 2.0 + j * 0.0123};
    b.joints[j].confidence = (j % 2 == 0) ? 1.f : 0.5f;
  }
  s.bodies.push_back(b);
  return s;
}

// Deterministic audio sample of (frame index, channel), exactly representable in PCM16.
inline float audio_sample(int64_t i, int c) {
  const double v = 0.6 * std::sin(2 * M_PI * 440.0 * static_cast<double>(i) / kSampleRate + c);
  return static_cast<float>(std::lrint(v * 32767.0) / 32767.0);
}

inline AudioChunk audio_chunk(int k) {
  AudioChunk a;
  a.sample_rate = kSampleRate;
  a.channels = kChannels;
  a.samples.resize(kChunkFrames * kChannels);
  for (int64_t i = 0; i < kChunkFrames; ++i)
    for (int c = 0; c < kChannels; ++c)
      a.samples[i * kChannels + c] = audio_sample(k * kChunkFrames + i, c);
  return a;
}

// Writes `frames` ticks of every stream (tick k at k*40 ms; audio chunk k covers [k*40, k*40+40)
// ms), in the order cam, depth, skel, mic.
inline Status write_ticks(SessionWriter& w, int first, int frames, int64_t offset_ns = 0) {
  for (int k = first; k < first + frames; ++k) {
    const Timestamp t = Timestamp::from_ns(offset_ns + k * kFramePeriodNs);
    const uint64_t seq = static_cast<uint64_t>(k);
    if (auto st = w.write(*make_frame("cam", t, seq, ColorImage{color_frame(k)})); !st) return st;
    if (auto st = w.write(*make_frame("depth", t, seq, DepthImage{depth_frame(k), false})); !st)
      return st;
    if (auto st = w.write(*make_frame("skel", t, seq, skeleton_frame(k))); !st) return st;
    if (auto st = w.write(*make_frame("mic", t, seq, audio_chunk(k))); !st) return st;
  }
  return ok_status();
}

// A closed session of `frames` ticks in `dir`.
inline void write_session(const std::filesystem::path& dir, int frames,
                          SessionManifest manifest = make_manifest()) {
  auto w = SessionWriter::create(dir, std::move(manifest));
  ASSERT_TRUE(w) << w.error().message;
  auto st = write_ticks(**w, 0, frames);
  ASSERT_TRUE(st) << st.error().message;
  auto c = (*w)->close();
  ASSERT_TRUE(c) << c.error().message;
}

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_file(const std::filesystem::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << text;
}

inline void replace_in_file(const std::filesystem::path& p, const std::string& from,
                            const std::string& to) {
  std::string s = read_file(p);
  const auto pos = s.find(from);
  ASSERT_NE(pos, std::string::npos) << "'" << from << "' not in " << p;
  s.replace(pos, from.size(), to);
  write_file(p, s);
}

}  // namespace dreamsense::sources::test_util
