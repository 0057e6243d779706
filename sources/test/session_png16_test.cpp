// Session format: depth encoding "png16" (lossless 16-bit PNG frames + index), its round trip,
// its errors, and (disabled by default) a size/speed measurement against raw16.

#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <vector>

#include "session_test_util.hpp"

namespace dreamsense::sources {
namespace {

using namespace test_util;

#define EXPECT_TEXT_HAS(str, text) EXPECT_NE((str).find(text), std::string::npos) << (str)
#define EXPECT_MESSAGE_HAS(error, text) \
  EXPECT_NE((error).message.find(text), std::string::npos) << (error).message

constexpr unsigned char kPngSignature[8] = {0x89, 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A};

struct IndexLine {
  unsigned long long sequence = 0, stamp = 0, offset = 0, size = 0;
};

// The index lines of a mjpeg/raw16/png16 index file (comments skipped).
std::vector<IndexLine> read_index(const std::filesystem::path& path) {
  std::vector<IndexLine> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    IndexLine l;
    EXPECT_EQ(
        std::sscanf(line.c_str(), "%llu,%llu,%llu,%llu", &l.sequence, &l.stamp, &l.offset, &l.size),
        4)
        << line;
    out.push_back(l);
  }
  return out;
}

// A depth-only session of `frames` frames of `size`, depth stream "depth".
SessionManifest depth_manifest(const std::string& encoding, cv::Size size) {
  SessionManifest m;
  StreamEntry depth;
  depth.id = "depth";
  depth.kind = SensorKind::kDepth;
  depth.encoding = encoding;
  depth.rate_hz = 30;
  depth.width = size.width;
  depth.height = size.height;
  m.streams = {depth};
  return m;
}

// A 640x480 Kinect-like depth scene (mm): back wall, floor plane, a table top and two blobs,
// shifted with k; `noisy` adds depth-dependent noise, disparity-like quantisation and holes (0).
cv::Mat scene_depth(int k, bool noisy, cv::Size size = {640, 480}) {
  cv::Mat m(size, CV_16UC1);
  std::mt19937 rng(static_cast<unsigned>(1234 + k));
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double fy = 525.0, cy = size.height / 2.0, cx = size.width / 2.0, fx = 525.0;
  for (int y = 0; y < m.rows; ++y) {
    auto* row = m.ptr<uint16_t>(y);
    for (int x = 0; x < m.cols; ++x) {
      double z = 3000.0 - 0.3 * (x - cx);  // slightly oblique back wall, 2900-3100 mm
      // Floor (camera 0.8 m above it, looking horizontally): z = h * fy / (y - cy).
      if (y > cy + 5) z = std::min(z, 800.0 * fy / (y - cy));
      // Table top, 1.2-1.6 m, in the lower left.
      if (x > 60 && x < 300 && y > 280 && y < 360) z = std::min(z, 1200.0 + 1.2 * (360 - y));
      // Two blobs (a child's head/torso, a robot) moving with k.
      const double bx[2] = {380.0 + 2.0 * k, 200.0 - 1.5 * k}, by[2] = {220.0, 200.0};
      const double br[2] = {90.0, 60.0}, bz[2] = {1500.0, 2200.0};
      for (int b = 0; b < 2; ++b) {
        const double dx = (x - bx[b]) / br[b], dy = (y - by[b]) / (1.6 * br[b]);
        const double r2 = dx * dx + dy * dy;
        if (r2 < 1.0) z = std::min(z, bz[b] - 0.5 * br[b] * std::sqrt(1.0 - r2) * 1000.0 / fx);
      }
      z = std::clamp(z, 500.0, 3000.0);
      if (noisy) {
        // Kinect v1: sigma ~ 1.4e-6 * z^2 mm, depth quantised in disparity steps of ~2.85e-6*z^2.
        z += gauss(rng) * 1.4e-6 * z * z;
        const double step = std::max(1.0, 2.85e-6 * z * z);
        z = std::round(z / step) * step;
        if (uni(rng) < 0.01) z = 0;  // speckle holes
        if (x < 8) z = 0;            // the invalid band at the left edge
      }
      row[x] = static_cast<uint16_t>(std::clamp(std::lround(z), 0L, 65535L));
    }
  }
  if (noisy) {
    // Shadow of the nearer blob on the wall (no measurement).
    const int sx = 380 + 2 * k + 92;
    m(cv::Rect(sx, 80, 14, 280) & cv::Rect({}, size)).setTo(0);
  }
  return m;
}

double max_abs_diff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

TEST(Png16, RoundTripIsBitExactWithEveryStream) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  constexpr int kFrames = 12;
  write_session(dir, kFrames, make_manifest("png16"));
  // Default file names, the png16 index header, every frame a PNG.
  const std::string idx = read_file(dir / "depth.idx");
  EXPECT_EQ(idx.rfind("# dreamsense png16 index v1\n", 0), 0u) << idx;
  const std::string data = read_file(dir / "depth.depth");
  const auto lines = read_index(dir / "depth.idx");
  ASSERT_EQ(lines.size(), size_t{kFrames});
  uint64_t next_offset = 0;
  for (const auto& l : lines) {
    EXPECT_EQ(l.offset, next_offset);
    next_offset = l.offset + l.size;
    ASSERT_LE(l.offset + 8, data.size());
    EXPECT_EQ(data.compare(l.offset, 8, reinterpret_cast<const char*>(kPngSignature), 8), 0);
  }
  EXPECT_EQ(next_offset, data.size());

  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_EQ((*reader)->manifest().streams[1].encoding, "png16");
  EXPECT_EQ((*reader)->manifest().streams[1].file, "depth.depth");
  EXPECT_EQ((*reader)->manifest().streams[1].index, "depth.idx");
  std::map<SensorId, int> counts;
  for (auto f = (*reader)->next(); f; f = (*reader)->next()) {
    ++counts[(*f)->sensor];
    if ((*f)->sensor != "depth") continue;
    const int k = static_cast<int>((*f)->sequence);
    const auto* d = (*f)->as<DepthImage>();
    ASSERT_NE(d, nullptr);
    EXPECT_EQ((*f)->stamp.ns(), k * kFramePeriodNs);
    ASSERT_EQ(d->depth_mm.type(), CV_16UC1);
    ASSERT_EQ(d->depth_mm.size(), cv::Size(kWidth, kHeight));
    EXPECT_EQ(max_abs_diff(d->depth_mm, depth_frame(k)), 0.0) << "frame " << k;
    EXPECT_EQ(d->depth_mm.at<uint16_t>(0, 0), 0);
    EXPECT_EQ(d->depth_mm.at<uint16_t>(0, 1), 65535);
  }
  EXPECT_EQ(counts["depth"], kFrames);
  EXPECT_EQ(counts["cam"], kFrames);
  EXPECT_EQ(counts["skel"], kFrames);
  EXPECT_EQ(counts["mic"], kFrames);
}

// Full-size frames with noise, holes, the extremes and a non-continuous (ROI) input, at the
// lowest, default and highest compression levels: bit-exact and smaller than raw16.
TEST(Png16, RealisticFramesAreBitExactAtEveryLevel) {
  const cv::Size size(640, 480);
  for (int level : {0, 1, 9}) {
    SCOPED_TRACE("png_compression " + std::to_string(level));
    TempDir tmp;
    const auto dir = tmp.path() / "s";
    std::vector<cv::Mat> frames;
    for (int k = 0; k < 3; ++k) frames.push_back(scene_depth(k, /*noisy=*/k != 0, size));
    frames[1].at<uint16_t>(10, 10) = 65535;
    frames[1].at<uint16_t>(479, 639) = 65535;
    // A view into a larger image (not continuous).
    cv::Mat big(size.height + 4, size.width + 6, CV_16UC1, cv::Scalar(65535));
    frames.push_back(big(cv::Rect(3, 2, size.width, size.height)));
    scene_depth(7, true, size).copyTo(frames.back());
    ASSERT_FALSE(frames.back().isContinuous());
    cv::Mat all_values(size, CV_16UC1);  // every uint16 value at least once
    for (int i = 0; i < size.area(); ++i)
      all_values.at<uint16_t>(i / size.width, i % size.width) = static_cast<uint16_t>(i * 7);
    frames.push_back(all_values);
    {
      auto w =
          SessionWriter::create(dir, depth_manifest("png16", size), {.png_compression = level});
      ASSERT_TRUE(w) << w.error().message;
      for (size_t k = 0; k < frames.size(); ++k)
        ASSERT_TRUE((*w)->write(*make_frame("depth", Timestamp::from_ns(k * 33'333'333), k,
                                            DepthImage{frames[k], false})));
      ASSERT_TRUE((*w)->close());
    }
    const auto data_size = std::filesystem::file_size(dir / "depth.depth");
    if (level > 0) {
      EXPECT_LT(data_size, frames.size() * size.area() * 2);
    }
    auto reader = SessionReader::open(dir);
    ASSERT_TRUE(reader) << reader.error().message;
    for (size_t k = 0; k < frames.size(); ++k) {
      auto f = (*reader)->next();
      ASSERT_TRUE(f) << f.error().message;
      const cv::Mat& d = (*f)->as<DepthImage>()->depth_mm;
      ASSERT_EQ(d.type(), CV_16UC1);
      EXPECT_EQ(max_abs_diff(d, frames[k]), 0.0) << "frame " << k;
    }
    EXPECT_FALSE((*reader)->next());
  }
}

TEST(Png16, WriterRejectsNonDepthImages) {
  TempDir tmp;
  auto w = SessionWriter::create(tmp.path() / "s", depth_manifest("png16", {kWidth, kHeight}));
  ASSERT_TRUE(w) << w.error().message;
  auto st = (*w)->write(*make_frame("depth", Timestamp::from_ns(0), 0,
                                    DepthImage{cv::Mat(kHeight, kWidth, CV_8UC1), false}));
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, ErrorCode::kInvalidArgument);
  auto bad_size = (*w)->write(
      *make_frame("depth", Timestamp::from_ns(0), 0, DepthImage{cv::Mat(10, 10, CV_16UC1), false}));
  ASSERT_FALSE(bad_size);
  EXPECT_EQ(bad_size.error().code, ErrorCode::kInvalidArgument);
}

TEST(Png16, ManifestDefaultsAndEncodingCheck) {
  StreamEntry s;
  s.id = "front";
  s.kind = SensorKind::kDepth;
  s.encoding = "png16";
  fill_stream_defaults(s);
  EXPECT_EQ(s.encoding, "png16");
  EXPECT_EQ(s.file, "front.depth");
  EXPECT_EQ(s.index, "front.idx");
  SessionManifest m = make_manifest();
  m.streams[1].encoding = "zstd16";
  for (auto& e : m.streams) fill_stream_defaults(e);
  auto st = check_manifest(m);
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, ErrorCode::kUnsupported);
  EXPECT_MESSAGE_HAS(st.error(),
                     "unknown encoding 'zstd16' for kind depth (expected raw16 or png16)");
}

// A closed session of 10 ticks with a png16 depth stream, in <tmp>/s.
class Png16BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = tmp_.path() / "s";
    write_session(dir_, 10, make_manifest("png16"));
    index_ = read_index(dir_ / "depth.idx");
    ASSERT_EQ(index_.size(), 10u);
  }
  Error open_error(SessionReaderOptions options = {}) {
    auto r = SessionReader::open(dir_, options);
    if (r) {
      ADD_FAILURE() << "session opened";
      return Error{};
    }
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << "message is not one line";
    return r.error();
  }
  void overwrite(uint64_t offset, const std::string& bytes) {
    std::fstream f(dir_ / "depth.depth", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(offset));
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  TempDir tmp_;
  std::filesystem::path dir_;
  std::vector<IndexLine> index_;
};

// Reads the depth stream: the frames' indices (by content) and what the damage policy skipped.
struct DepthReadBack {
  std::vector<int> frames;  // k of depth_frame(k) for every frame returned
  StreamDamage damage;
};
DepthReadBack read_depth(const std::filesystem::path& dir, SessionReaderOptions o = {}) {
  o.only = {"depth"};
  DepthReadBack out;
  auto reader = SessionReader::open(dir, o);
  if (!reader) {
    ADD_FAILURE() << reader.error().message;
    return out;
  }
  for (auto f = (*reader)->next(); f; f = (*reader)->next()) {
    int match = -1;
    for (int k = 0; k < 10 && match < 0; ++k)
      if (max_abs_diff((*f)->as<DepthImage>()->depth_mm, depth_frame(k)) == 0.0) match = k;
    out.frames.push_back(match);
  }
  out.damage = (*reader)->damage().at(0);
  return out;
}

TEST_F(Png16BadInput, TruncatedDataIsATornTail) {
  // Cut inside frame 6: frames 0-5 read bit-exact, 4 torn.
  std::filesystem::resize_file(dir_ / "depth.depth", index_[6].offset + index_[6].size / 2);
  EXPECT_MESSAGE_HAS(open_error(), "depth.depth: 4 of 10 records damaged");  // marked complete
  DepthReadBack r = read_depth(dir_, {.allow_damaged = true});
  EXPECT_EQ(r.frames, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(r.damage.torn_tail, 4u);
  EXPECT_EQ(r.damage.damaged, 0u);
  // Cut exactly at the end of frame 3, in an incomplete session: the same rule.
  std::filesystem::resize_file(dir_ / "depth.depth", index_[3].offset + index_[3].size);
  replace_in_file(dir_ / kManifestName, "complete: true", "complete: false");
  EXPECT_MESSAGE_HAS(open_error({.allow_incomplete = false}), "session.yaml: incomplete session");
  r = read_depth(dir_);
  EXPECT_EQ(r.frames, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(r.damage.torn_tail, 6u);
}

TEST_F(Png16BadInput, EmptyDataFileIsAllTorn) {
  std::filesystem::resize_file(dir_ / "depth.depth", 0);
  const DepthReadBack r = read_depth(dir_, {.allow_damaged = true});
  EXPECT_TRUE(r.frames.empty());
  EXPECT_EQ(r.damage.torn_tail, 10u);
}

TEST_F(Png16BadInput, CorruptFrameBytesCostThatFrame) {
  // Frame 3 keeps its signature but the rest is zeros: found when decoding, not at open.
  overwrite(index_[3].offset + 8, std::string(index_[3].size - 8, '\0'));
  const DepthReadBack r = read_depth(dir_);
  EXPECT_EQ(r.frames, (std::vector<int>{0, 1, 2, 4, 5, 6, 7, 8, 9}));
  ASSERT_EQ(r.damage.damaged, 1u);
  EXPECT_TEXT_HAS(r.damage.first[0].what, "depth.depth: corrupt: frame 3 (offset " +
                                              std::to_string(index_[3].offset) +
                                              ") does not decode");
}

TEST_F(Png16BadInput, FlippedBitInPixelDataCostsThatFrame) {
  // One flipped bit in the middle of frame 5's compressed data: the chunk CRC catches it.
  std::string data = read_file(dir_ / "depth.depth");
  const uint64_t pos = index_[5].offset + index_[5].size / 2;
  overwrite(pos, std::string(1, static_cast<char>(data[pos] ^ 0x10)));
  const DepthReadBack r = read_depth(dir_);
  EXPECT_EQ(r.frames, (std::vector<int>{0, 1, 2, 3, 4, 6, 7, 8, 9}));
  ASSERT_EQ(r.damage.damaged, 1u);
  EXPECT_TEXT_HAS(r.damage.first[0].what, "depth.depth: corrupt: frame 5");
}

TEST_F(Png16BadInput, MissingSignatureCostsThatFrame) {
  overwrite(index_[2].offset, std::string(4, '\0'));
  const DepthReadBack r = read_depth(dir_);
  EXPECT_EQ(r.frames, (std::vector<int>{0, 1, 3, 4, 5, 6, 7, 8, 9}));
  ASSERT_EQ(r.damage.damaged, 1u);
  EXPECT_TEXT_HAS(r.damage.first[0].what,
                  "depth.depth: frame 2 (offset " + std::to_string(index_[2].offset) + ", " +
                      std::to_string(index_[2].size) + " bytes) is not a PNG");
}

TEST_F(Png16BadInput, HugeSizeInTheHeaderCostsThatFrameBeforeDecoding) {
  // Frame 4's IHDR declares 30000x30000 (big-endian at bytes 16-23): refused from the header, as
  // the stream's 64x48 is not what it declares; decoding would first allocate 1.8 GB (the
  // out-of-memory of fuzz.session_stream, 2026-12-01).
  overwrite(index_[4].offset + 16, std::string("\x00\x00\x75\x30\x00\x00\x75\x30", 8));
  const DepthReadBack r = read_depth(dir_, {.allow_damaged = true});
  EXPECT_EQ(r.frames, (std::vector<int>{0, 1, 2, 3, 5, 6, 7, 8, 9}));
  ASSERT_EQ(r.damage.damaged, 1u);
  EXPECT_TEXT_HAS(r.damage.first[0].what,
                  "depth.depth: frame 4 is 30000x30000, session.yaml declares 64x48");
}

TEST_F(Png16BadInput, IndexOffsetNotAtAFrameCostsThatFrame) {
  // An index line that points into the middle of a frame: no signature there.
  replace_in_file(dir_ / "depth.idx", "," + std::to_string(index_[7].offset) + ",",
                  "," + std::to_string(index_[7].offset + 1) + ",");
  const DepthReadBack r = read_depth(dir_);
  EXPECT_EQ(r.damage.damaged, 1u);
  EXPECT_EQ(r.frames.size(), 9u);
}

// Valid PNGs that are not what the manifest declares: 8-bit, or the wrong size.
TEST(Png16WrongImage, WrongTypeOrSizeIsCorruptData) {
  TempDir tmp;
  SessionManifest m = depth_manifest("png16", {kWidth, kHeight});
  for (auto& s : m.streams) fill_stream_defaults(s);
  m.complete = true;
  ASSERT_TRUE(write_manifest(tmp.path(), m));
  std::vector<uchar> grey8, small16, good;
  ASSERT_TRUE(cv::imencode(".png", cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(7)), grey8));
  ASSERT_TRUE(cv::imencode(".png", cv::Mat(8, 8, CV_16UC1, cv::Scalar(700)), small16));
  ASSERT_TRUE(cv::imencode(".png", depth_frame(2), good));
  std::string data, idx = "# dreamsense png16 index v1\n";
  int k = 0;
  for (const auto* png : {&grey8, &small16, &good}) {
    idx += fmt::format("{},{},{},{}\n", k, k * kFramePeriodNs, data.size(), png->size());
    data.append(png->begin(), png->end());
    ++k;
  }
  write_file(tmp.path() / "depth.depth", data);
  write_file(tmp.path() / "depth.idx", idx);
  auto reader = SessionReader::open(tmp.path(), {.allow_damaged = true});
  ASSERT_TRUE(reader) << reader.error().message;
  // Frames 0 and 1 do not decode to what the manifest declares: skipped and reported.
  auto f = (*reader)->next();
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ(max_abs_diff((*f)->as<DepthImage>()->depth_mm, depth_frame(2)), 0.0);
  EXPECT_FALSE((*reader)->next());
  const StreamDamage d = (*reader)->damage().at(0);
  ASSERT_EQ(d.damaged, 2u);
  EXPECT_TEXT_HAS(d.first[0].what,
                  "depth.depth: corrupt: frame 0 (offset 0) is not a 16-bit grey PNG");
  EXPECT_TEXT_HAS(d.first[1].what, "depth.depth: frame 1 is 8x8, session.yaml declares 64x48");
}

// The numbers in docs/session_format.md. Run with
//   sources_test --gtest_also_run_disabled_tests --gtest_filter='*Png16Measure*'
TEST(Png16Measure, DISABLED_SizeAndSpeedOf640x480Frames) {
  using Clock = std::chrono::steady_clock;
  constexpr int kFrames = 30;
  for (bool noisy : {false, true}) {
    std::vector<cv::Mat> frames;
    for (int k = 0; k < kFrames; ++k) frames.push_back(scene_depth(k, noisy));
    const double raw = static_cast<double>(frames[0].total() * 2);
    for (int level : {1, 3, 6, 9}) {
      std::vector<double> enc_ms, dec_ms;
      double bytes = 0;
      std::vector<uchar> buf;
      for (int k = 0; k < kFrames; ++k) {
        const auto t0 = Clock::now();
        ASSERT_TRUE(cv::imencode(".png", frames[k], buf, {cv::IMWRITE_PNG_COMPRESSION, level}));
        const auto t1 = Clock::now();
        const cv::Mat back = cv::imdecode(buf, cv::IMREAD_UNCHANGED);
        const auto t2 = Clock::now();
        ASSERT_EQ(max_abs_diff(back, frames[k]), 0.0);
        bytes += static_cast<double>(buf.size());
        enc_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        dec_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
      }
      std::sort(enc_ms.begin(), enc_ms.end());
      std::sort(dec_ms.begin(), dec_ms.end());
      const double mean_bytes = bytes / kFrames;
      std::printf(
          "%s scene, level %d: %.0f bytes/frame (raw16 %.0f), ratio %.2fx (%.1f%% of raw16), "
          "encode %.2f ms, decode %.2f ms (medians of %d frames)\n",
          noisy ? "noisy" : "smooth", level, mean_bytes, raw, raw / mean_bytes,
          100.0 * mean_bytes / raw, enc_ms[kFrames / 2], dec_ms[kFrames / 2], kFrames);
    }
  }
}

}  // namespace
}  // namespace dreamsense::sources
