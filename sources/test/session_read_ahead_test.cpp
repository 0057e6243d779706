// SessionReader read-ahead decoding (options.decode_threads): the same frames, order, content and
// errors for every thread count and window; clean early destruction; option checks.

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "session_test_util.hpp"

namespace dreamsense::sources {
namespace {

using namespace test_util;

// Everything observable about a frame, pixel and sample bytes included.
std::string fingerprint(const SensorFrame& f) {
  std::string s = fmt::format("{} {} {} ", f.sensor, f.stamp.ns(), f.sequence);
  const auto bytes = [&](const cv::Mat& m) {
    s += fmt::format("{}x{} type {} ", m.cols, m.rows, m.type());
    const cv::Mat c = m.isContinuous() ? m : m.clone();
    s.append(reinterpret_cast<const char*>(c.data), c.total() * c.elemSize());
  };
  if (const auto* c = f.as<ColorImage>()) bytes(c->image);
  if (const auto* d = f.as<DepthImage>()) bytes(d->depth_mm);
  if (const auto* k = f.as<Skeleton>())
    for (const auto& b : k->bodies) {
      s += fmt::format("body {}:", b.body_id);
      for (const auto& j : b.joints)
        s += fmt::format(" {} {} {} {}", j.position_m[0], j.position_m[1], j.position_m[2],
                         j.confidence);
    }
  if (const auto* a = f.as<AudioChunk>()) {
    s += fmt::format("audio {} {} ", a->sample_rate, a->channels);
    s.append(reinterpret_cast<const char*>(a->samples.data()), a->samples.size() * sizeof(float));
  }
  return s;
}

// Every result of next() up to the end: a fingerprint or "error <code>: <message>".
std::vector<std::string> replay(const std::filesystem::path& dir, int threads, int window) {
  SessionReaderOptions o;
  o.decode_threads = threads;
  o.read_ahead_frames = window;
  auto reader = SessionReader::open(dir, o);
  EXPECT_TRUE(reader) << reader.error().message;
  std::vector<std::string> out;
  if (!reader) return out;
  for (int guard = 0; guard < 100000; ++guard) {
    auto f = (*reader)->next();
    if (!f && is_end_of_stream(f.error())) break;
    out.push_back(
        f ? fingerprint(**f)
          : fmt::format("error {}: {}", static_cast<int>(f.error().code), f.error().message));
  }
  // Frames the damage policy skipped, after the frames (they are not returned by next()).
  for (const auto& d : (*reader)->damage())
    for (const auto& r : d.first)
      out.push_back(fmt::format("damage {} {} {}: {}", d.stream, r.record,
                                r.stamp_ns ? *r.stamp_ns : -1, r.what));
  return out;
}

StreamEntry stream(const std::string& id, SensorKind kind, const std::string& encoding,
                   double rate_hz) {
  StreamEntry s;
  s.id = id;
  s.kind = kind;
  s.encoding = encoding;
  s.rate_hz = rate_hz;
  s.width = kWidth;
  s.height = kHeight;
  return s;
}

// Every kind the writer produces, at two rates so that the streams interleave and tie:
// cam (mjpeg BGR, 25 Hz), grey (mjpeg grey, 30 Hz), depth (png16, 25 Hz), raw (raw16, 30 Hz),
// skel (jsonl, 25 Hz), mic (wav, 40 ms chunks).
void write_mixed_session(const std::filesystem::path& dir, int ticks) {
  SessionManifest m = make_manifest("png16");  // cam, depth, skel, mic
  m.streams.insert(m.streams.begin() + 1, stream("grey", SensorKind::kColor, "mjpeg", 30));
  m.streams.insert(m.streams.begin() + 3, stream("raw", SensorKind::kDepth, "raw16", 30));
  auto w = SessionWriter::create(dir, m);
  ASSERT_TRUE(w) << w.error().message;
  ASSERT_TRUE(write_ticks(**w, 0, ticks));
  const int64_t period30 = 1'000'000'000LL / 30;
  for (int k = 0; k * period30 < ticks * kFramePeriodNs; ++k) {
    const Timestamp t = Timestamp::from_ns(k * period30);
    cv::Mat grey;
    cv::extractChannel(color_frame(k), grey, 1);
    ASSERT_TRUE((*w)->write(*make_frame("grey", t, k, ColorImage{grey})));
    ASSERT_TRUE((*w)->write(*make_frame("raw", t, k, DepthImage{depth_frame(k + 3), false})));
  }
  ASSERT_TRUE((*w)->close());
}

// Index entry k of an indexed stream: {offset, size}.
std::pair<size_t, size_t> index_entry(const std::filesystem::path& idx, int k) {
  std::ifstream in(idx);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (n++ != k) continue;
    unsigned long long seq = 0, stamp = 0, offset = 0, size = 0;
    EXPECT_EQ(std::sscanf(line.c_str(), "%llu,%llu,%llu,%llu", &seq, &stamp, &offset, &size), 4);
    return {offset, size};
  }
  ADD_FAILURE() << "no frame " << k << " in " << idx;
  return {0, 0};
}

// Zeros the bytes of a frame between its first `keep_head` and last `keep_tail` bytes: the cheap
// checks at open() pass, decoding fails.
void spoil_frame(const std::filesystem::path& dir, const std::string& id, const std::string& data,
                 int k, size_t keep_head, size_t keep_tail) {
  const auto [offset, size] = index_entry(dir / (id + ".idx"), k);
  ASSERT_GT(size, keep_head + keep_tail);
  std::fstream f(dir / data, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset + keep_head));
  const std::string zeros(size - keep_head - keep_tail, '\0');
  f.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
}

TEST(SessionReadAhead, SameFramesInSameOrderForEveryThreadCount) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_mixed_session(dir, 30);
  const std::vector<std::string> expected = replay(dir, 0, 1);
  // 30 ticks (1.2 s) of cam, depth, skel, mic + 37 frames (0 to 1.2 s at 30 Hz) of grey and raw.
  ASSERT_EQ(expected.size(), 30u * 4 + 37u * 2);
  for (int threads : {1, 2, 3})
    for (int window : {1, 2, 8, 100}) {
      const std::vector<std::string> got = replay(dir, threads, window);
      ASSERT_EQ(got.size(), expected.size()) << threads << " threads, window " << window;
      for (size_t i = 0; i < got.size(); ++i)
        ASSERT_TRUE(got[i] == expected[i])
            << threads << " threads, window " << window << ": result " << i << " differs";
    }
}

// Source::stream_ended (issue 18): true exactly once the stream's last frame has been returned, so
// settled replay stops waiting for a stream that ends before the others.
TEST(SessionReadAhead, StreamEndedExactlyAfterEachStreamsLastFrame) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_mixed_session(dir, 12);
  std::vector<SensorId> order;
  {
    auto reader = SessionReader::open(dir);
    ASSERT_TRUE(reader) << reader.error().message;
    for (auto f = (*reader)->next(); f; f = (*reader)->next()) order.push_back((*f)->sensor);
  }
  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  const SourceInfo info = (*reader)->info();
  ASSERT_GE(info.sensors.size(), 4u);
  for (size_t i = 0; i <= order.size(); ++i) {
    for (const auto& s : info.sensors) {
      const bool more = std::find(order.begin() + static_cast<std::ptrdiff_t>(i), order.end(),
                                  s.id) != order.end();
      ASSERT_EQ((*reader)->stream_ended(s.id), !more) << s.id << " after " << i << " frames";
    }
    if (i < order.size()) ASSERT_TRUE((*reader)->next());
  }
  EXPECT_TRUE((*reader)->stream_ended("no_such_stream"));
}

TEST(SessionReadAhead, OnlyStreamsAndDefaultOptions) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_mixed_session(dir, 12);
  for (const std::vector<SensorId>& only :
       {std::vector<SensorId>{"raw", "cam"}, std::vector<SensorId>{"skel"}}) {
    std::vector<std::string> results[2];
    for (int threads : {0, 1}) {
      SessionReaderOptions o;
      o.only = only;
      o.decode_threads = threads;
      auto reader = SessionReader::open(dir, o);
      ASSERT_TRUE(reader) << reader.error().message;
      for (auto f = (*reader)->next(); f; f = (*reader)->next())
        results[threads].push_back(fingerprint(**f));
    }
    EXPECT_FALSE(results[0].empty());
    EXPECT_TRUE(results[0] == results[1]) << only.size() << " streams";
  }
  EXPECT_EQ(SessionReaderOptions{}.decode_threads, 1);
  EXPECT_EQ(SessionReaderOptions{}.read_ahead_frames, 8);
}

TEST(SessionReadAhead, CorruptFramesAreSkippedIdentically) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_mixed_session(dir, 20);
  spoil_frame(dir, "cam", "cam.mjpg", 3, 2, 2);       // keeps SOI/EOI
  spoil_frame(dir, "depth", "depth.depth", 5, 8, 0);  // keeps the PNG signature
  spoil_frame(dir, "grey", "grey.mjpg", 19, 2, 2);    // of 24
  const std::vector<std::string> expected = replay(dir, 0, 1);
  std::vector<size_t> damaged;
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NE(expected[i].rfind("error", 0), 0u) << expected[i];  // skipped, not returned
    if (expected[i].rfind("damage", 0) == 0) damaged.push_back(i);
  }
  ASSERT_EQ(damaged.size(), 3u);
  std::string all;  // damage is listed per stream, in manifest order
  for (size_t i : damaged) all += expected[i] + "\n";
  EXPECT_NE(all.find("cam.mjpg: corrupt: frame 3"), std::string::npos) << all;
  EXPECT_NE(all.find("depth.depth: corrupt: frame 5"), std::string::npos) << all;
  EXPECT_NE(all.find("grey.mjpg: corrupt: frame 19"), std::string::npos) << all;
  for (int threads : {1, 2})
    for (int window : {1, 4, 50}) {
      const std::vector<std::string> got = replay(dir, threads, window);
      ASSERT_EQ(got.size(), expected.size()) << threads << " threads, window " << window;
      for (size_t i = 0; i < got.size(); ++i)
        ASSERT_TRUE(got[i] == expected[i])
            << threads << " threads, window " << window << ": result " << i << " differs"
            << (got[i].rfind("error", 0) == 0 ? ": " + got[i] : std::string());
    }
}

// Large noisy frames (slow to decode), so that workers are busy when the reader goes away.
TEST(SessionReadAhead, EarlyDestructionIsPromptAndClean) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  {
    SessionManifest m;
    m.name = "big";
    StreamEntry a = stream("a", SensorKind::kColor, "mjpeg", 25);
    a.width = 1280;
    a.height = 960;
    StreamEntry b = a;
    b.id = "b";
    m.streams = {a, b};
    auto w = SessionWriter::create(dir, m);
    ASSERT_TRUE(w) << w.error().message;
    cv::Mat noise(960, 1280, CV_8UC3);
    cv::RNG rng(7);
    for (int k = 0; k < 12; ++k) {
      rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
      const Timestamp t = Timestamp::from_ns(k * kFramePeriodNs);
      ASSERT_TRUE((*w)->write(*make_frame("a", t, k, ColorImage{noise.clone()})));
      ASSERT_TRUE((*w)->write(*make_frame("b", t, k, ColorImage{noise.clone()})));
    }
    ASSERT_TRUE((*w)->close());
  }
  using Clock = std::chrono::steady_clock;
  for (int threads : {1, 2})
    for (int reads : {0, 1, 5, 24, 25}) {  // 24 frames: 24 = everything, 25 = past the end
      SessionReaderOptions o;
      o.decode_threads = threads;
      o.read_ahead_frames = 16;
      auto reader = SessionReader::open(dir, o);
      ASSERT_TRUE(reader) << reader.error().message;
      for (int i = 0; i < reads; ++i) {
        auto f = (*reader)->next();
        ASSERT_EQ(static_cast<bool>(f), i < 24) << i;
      }
      const auto t0 = Clock::now();
      reader->reset();
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      // At most the frame each worker is decoding (~tens of ms) is finished first.
      EXPECT_LT(ms, 2000.0) << threads << " threads, after " << reads << " frames";
    }
}

TEST(SessionReadAhead, OptionsCheck) {
  SessionReaderOptions o;
  EXPECT_TRUE(o.check());
  o.decode_threads = 0;
  o.read_ahead_frames = 1;
  EXPECT_TRUE(o.check());
  o.decode_threads = 16;
  EXPECT_TRUE(o.check());
  o.decode_threads = -1;
  o.read_ahead_frames = 0;
  auto st = o.check();
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(st.error().message.find("decode_threads must be in [0, 16], got -1"), std::string::npos)
      << st.error().message;
  EXPECT_NE(st.error().message.find("read_ahead_frames must be >= 1, got 0"), std::string::npos)
      << st.error().message;
  o = {};
  o.decode_threads = 17;
  EXPECT_FALSE(o.check());
  TempDir tmp;
  auto reader = SessionReader::open(tmp.path(), o);  // options are checked before anything else
  ASSERT_FALSE(reader);
  EXPECT_EQ(reader.error().code, ErrorCode::kInvalidArgument);
}

// The numbers in docs/session_format.md: next() over a demo session, alone and with a simulated
// analysis load on the caller's thread (a busy loop of `load_ms` per frame of 1280 pixels or
// wider, about what face detection costs on the demo's three 1280x960 cameras).
// Generate the session with `dreamsense demo --out /tmp/prefetch-demo --seed 1 --no-analyze`, then
// run with DREAMSENSE_DEMO_SESSION=/tmp/prefetch-demo and the flags
// --gtest_also_run_disabled_tests --gtest_filter='*ReadAheadMeasure*'.
TEST(ReadAheadMeasure, DISABLED_NextFramesPerSecondOnDemoSession) {
  const char* dir = std::getenv("DREAMSENSE_DEMO_SESSION");
  if (dir == nullptr) GTEST_SKIP() << "DREAMSENSE_DEMO_SESSION not set";
  using Clock = std::chrono::steady_clock;
  for (double load_ms : {0.0, 12.0})
    for (int threads : {0, 1, 2}) {
      SessionReaderOptions o;
      o.decode_threads = threads;
      auto reader = SessionReader::open(dir, o);
      ASSERT_TRUE(reader) << reader.error().message;
      const auto t0 = Clock::now();
      int frames = 0;
      for (auto f = (*reader)->next(); f; f = (*reader)->next()) {
        ++frames;
        const auto* c = (*f)->as<ColorImage>();
        if (load_ms > 0 && c != nullptr && c->image.cols >= 1280) {
          const auto until = Clock::now() + std::chrono::duration<double, std::milli>(load_ms);
          while (Clock::now() < until) {
          }
        }
      }
      const double s = std::chrono::duration<double>(Clock::now() - t0).count();
      const double session_s = ((*reader)->info().end - (*reader)->info().start).seconds();
      std::printf(
          "load %.0f ms/large frame, decode_threads %d: %d frames in %.2f s: %.0f frames/s, "
          "%.2fx real time\n",
          load_ms, threads, frames, s, frames / s, session_s / s);
      std::fflush(stdout);
    }
}

}  // namespace
}  // namespace dreamsense::sources
