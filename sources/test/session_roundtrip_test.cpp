// Session format: write -> read back, merged order, manifest round trip, crash safety.

#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <cstdio>
#include <map>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "session_test_util.hpp"

namespace dreamsense::sources {
namespace {

using namespace test_util;

struct ReadBack {
  std::vector<FramePtr> all;
  std::map<SensorId, std::vector<FramePtr>> by_stream;
};

ReadBack read_all(SessionReader& reader) {
  ReadBack out;
  for (;;) {
    auto f = reader.next();
    if (!f) {
      EXPECT_TRUE(is_end_of_stream(f.error())) << f.error().message;
      break;
    }
    out.all.push_back(*f);
    out.by_stream[(*f)->sensor].push_back(*f);
  }
  return out;
}

// Checks every frame of every stream against the generator, up to the frames present.
void expect_content(const ReadBack& rb) {
  const auto& cams = rb.by_stream.at("cam");
  for (size_t k = 0; k < cams.size(); ++k) {
    const auto* c = cams[k]->as<ColorImage>();
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(cams[k]->stamp.ns(), static_cast<int64_t>(k) * kFramePeriodNs);
    EXPECT_EQ(cams[k]->sequence, k);
    ASSERT_EQ(c->image.type(), CV_8UC3);
    ASSERT_EQ(c->image.size(), cv::Size(kWidth, kHeight));
    cv::Mat diff;
    cv::absdiff(c->image, color_frame(static_cast<int>(k)), diff);
    double max_diff = 0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
    EXPECT_LT(cv::mean(diff.reshape(1))[0], 3.0) << "frame " << k;
    EXPECT_LT(max_diff, 40.0) << "frame " << k;
  }
  const auto& depths = rb.by_stream.at("depth");
  for (size_t k = 0; k < depths.size(); ++k) {
    const auto* d = depths[k]->as<DepthImage>();
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(depths[k]->stamp.ns(), static_cast<int64_t>(k) * kFramePeriodNs);
    ASSERT_EQ(d->depth_mm.type(), CV_16UC1);
    EXPECT_EQ(cv::norm(d->depth_mm, depth_frame(static_cast<int>(k)), cv::NORM_INF), 0.0);
  }
  const auto& skels = rb.by_stream.at("skel");
  for (size_t k = 0; k < skels.size(); ++k) {
    const auto* s = skels[k]->as<Skeleton>();
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(skels[k]->stamp.ns(), static_cast<int64_t>(k) * kFramePeriodNs);
    EXPECT_EQ(skels[k]->sequence, k);
    const Skeleton expected = skeleton_frame(static_cast<int>(k));
    ASSERT_EQ(s->bodies.size(), expected.bodies.size());
    EXPECT_EQ(s->bodies[0].body_id, expected.bodies[0].body_id);
    for (int j = 0; j < kJointCount; ++j) {
      const auto& a = s->bodies[0].joints[j];
      const auto& e = expected.bodies[0].joints[j];
      EXPECT_FLOAT_EQ(a.confidence, e.confidence) << "joint " << j;
      if (!e.valid()) continue;
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(a.position_m[i], e.position_m[i], 1e-6);
    }
  }
  const auto& mics = rb.by_stream.at("mic");
  int64_t sample = 0;
  for (const auto& f : mics) {
    const auto* a = f->as<AudioChunk>();
    ASSERT_NE(a, nullptr);
    ASSERT_EQ(a->sample_rate, kSampleRate);
    ASSERT_EQ(a->channels, kChannels);
    EXPECT_EQ(f->stamp.ns(), sample * 1'000'000'000LL / kSampleRate);
    for (int64_t i = 0; i < a->frames(); ++i)
      for (int c = 0; c < kChannels; ++c)
        ASSERT_NEAR(a->samples[i * kChannels + c], audio_sample(sample + i, c), 1.0 / 32768)
            << "sample " << sample + i;
    sample += a->frames();
  }
}

TEST(SessionRoundTrip, EveryStreamKind) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  constexpr int kFrames = 30;
  write_session(dir, kFrames);

  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_TRUE((*reader)->manifest().complete);
  const ReadBack rb = read_all(**reader);
  ASSERT_EQ(rb.by_stream.size(), 4u);
  EXPECT_EQ(rb.by_stream.at("cam").size(), size_t{kFrames});
  EXPECT_EQ(rb.by_stream.at("depth").size(), size_t{kFrames});
  EXPECT_EQ(rb.by_stream.at("skel").size(), size_t{kFrames});
  EXPECT_EQ(rb.by_stream.at("mic").size(), size_t{kFrames});  // 40 ms chunks
  expect_content(rb);
  // After the end, still end of stream.
  auto again = (*reader)->next();
  ASSERT_FALSE(again);
  EXPECT_EQ(again.error().code, ErrorCode::kEndOfStream);
}

TEST(SessionRoundTrip, MergedOrderIsByStampThenManifestOrder) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_session(dir, 10);
  auto reader = SessionReader::open(dir, {.audio_chunk = Duration::from_ms(20)});
  ASSERT_TRUE(reader) << reader.error().message;
  const ReadBack rb = read_all(**reader);
  ASSERT_EQ(rb.all.size(), 10u * 3 + 20);
  const std::map<SensorId, int> order = {{"cam", 0}, {"depth", 1}, {"skel", 2}, {"mic", 3}};
  for (size_t i = 1; i < rb.all.size(); ++i) {
    const auto& a = rb.all[i - 1];
    const auto& b = rb.all[i];
    ASSERT_LE(a->stamp, b->stamp) << i;
    if (a->stamp == b->stamp) {
      EXPECT_LT(order.at(a->sensor), order.at(b->sensor)) << i;
    }
  }
  // At stamp 0: cam, depth, skel, mic; then the mic chunk at 20 ms.
  EXPECT_EQ(rb.all[0]->sensor, "cam");
  EXPECT_EQ(rb.all[3]->sensor, "mic");
  EXPECT_EQ(rb.all[4]->sensor, "mic");
  EXPECT_EQ(rb.all[4]->stamp.ns(), 20'000'000);
}

TEST(SessionRoundTrip, AudioChunkingAndLastShortChunk) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_session(dir, 5);  // 3200 audio frames
  auto reader = SessionReader::open(dir, {.audio_chunk = Duration::from_ms(30), .only = {"mic"}});
  ASSERT_TRUE(reader) << reader.error().message;
  const ReadBack rb = read_all(**reader);
  const auto& mics = rb.by_stream.at("mic");
  ASSERT_EQ(mics.size(), 7u);  // 6 x 480 + 320
  EXPECT_EQ(mics.back()->as<AudioChunk>()->frames(), 320);
  EXPECT_EQ(mics[1]->stamp.ns(), 30'000'000);
  EXPECT_EQ(mics[6]->stamp.ns(), 180'000'000);
  EXPECT_EQ(rb.by_stream.size(), 1u);
  expect_content(ReadBack{rb.all, {{"mic", mics}, {"cam", {}}, {"depth", {}}, {"skel", {}}}});
}

TEST(SessionRoundTrip, InfoDescribesStreams) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  SessionManifest m = make_manifest();
  m.streams[0].calibration = "calib/cam.yaml";
  m.streams[0].frame = "camera_optical";
  std::filesystem::create_directories(dir / "calib");
  write_file(dir / "calib/cam.yaml", "%YAML:1.0\n");
  write_session(dir, 4, m);
  auto reader = SessionReader::open(dir, {.only = {"cam", "mic"}});
  ASSERT_TRUE(reader) << reader.error().message;
  const SourceInfo info = (*reader)->info();
  ASSERT_EQ(info.sensors.size(), 2u);
  EXPECT_EQ(info.sensors[0].id, "cam");
  EXPECT_EQ(info.sensors[0].kind, SensorKind::kColor);
  EXPECT_EQ(info.sensors[0].width, kWidth);
  EXPECT_EQ(info.sensors[0].height, kHeight);
  EXPECT_DOUBLE_EQ(info.sensors[0].rate_hz, 25.0);
  EXPECT_EQ(info.sensors[0].frame, "camera_optical");
  EXPECT_TRUE(std::filesystem::path(info.sensors[0].calibration).is_absolute());
  EXPECT_TRUE(std::filesystem::exists(info.sensors[0].calibration));
  EXPECT_EQ(info.sensors[1].id, "mic");
  EXPECT_EQ(info.sensors[1].sample_rate, kSampleRate);
  EXPECT_EQ(info.sensors[1].channels, kChannels);
  EXPECT_EQ(info.sensors[1].frame, "mic");
  EXPECT_FALSE(info.live);
  EXPECT_EQ(info.start.ns(), 0);
  EXPECT_EQ(info.end.ns(), 3 * kFramePeriodNs);
  EXPECT_FALSE(info.find("depth"));
}

TEST(SessionRoundTrip, ManifestKeepsEveryField) {
  TempDir tmp;
  SessionManifest m = make_manifest();
  m.complete = true;
  m.truth = "truth.jsonl";
  for (auto& s : m.streams) fill_stream_defaults(s);
  m.streams[3].start_ns = 123456789;
  m.streams[0].rate_hz = 29.97;
  ASSERT_TRUE(write_manifest(tmp.path(), m));
  auto r = read_manifest(tmp.path());
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->name, "unit");
  EXPECT_EQ(r->clock_origin_unix_ns, m.clock_origin_unix_ns);
  EXPECT_EQ(r->participant.id, 7);
  EXPECT_EQ(r->participant.gender, "female");
  EXPECT_EQ(r->participant.age_months, 49.5);
  EXPECT_EQ(r->condition, "RET");
  EXPECT_EQ(r->task, "JA");
  EXPECT_TRUE(r->complete);
  EXPECT_EQ(r->truth, "truth.jsonl");
  EXPECT_EQ(r->metadata, m.metadata);
  ASSERT_EQ(r->streams.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    const auto& a = r->streams[i];
    const auto& e = m.streams[i];
    EXPECT_EQ(a.id, e.id);
    EXPECT_EQ(a.kind, e.kind);
    EXPECT_EQ(a.encoding, e.encoding);
    EXPECT_EQ(a.file, e.file);
    EXPECT_EQ(a.index, e.index);
    EXPECT_EQ(a.rate_hz, e.rate_hz);
    EXPECT_EQ(a.width, e.width);
    EXPECT_EQ(a.height, e.height);
    EXPECT_EQ(a.sample_rate, e.sample_rate);
    EXPECT_EQ(a.channels, e.channels);
    EXPECT_EQ(a.start_ns, e.start_ns);
    EXPECT_EQ(a.frame, e.frame);
  }
  EXPECT_EQ(r->streams[0].file, "cam.mjpg");
  EXPECT_EQ(r->streams[0].index, "cam.idx");
  EXPECT_EQ(r->streams[1].file, "depth.depth");
  EXPECT_EQ(r->streams[2].file, "skel.jsonl");
  EXPECT_EQ(r->streams[3].file, "mic.wav");
  // No temporary file left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(tmp.path())) ++files;
  EXPECT_EQ(files, 1);
}

TEST(SessionRoundTrip, GreyImagesAndAudioStartStamp) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  SessionManifest m = make_manifest();
  m.streams = {m.streams[0], m.streams[3]};
  auto w = SessionWriter::create(dir, m);
  ASSERT_TRUE(w) << w.error().message;
  const int64_t t0 = 5'000'000'000;
  for (int k = 0; k < 3; ++k) {
    cv::Mat grey(kHeight, kWidth, CV_8UC1, cv::Scalar(40 * k + 20));
    const Timestamp t = Timestamp::from_ns(t0 + k * kFramePeriodNs);
    ASSERT_TRUE((*w)->write(*make_frame("cam", t, k, ColorImage{grey})));
    ASSERT_TRUE((*w)->write(*make_frame("mic", t, k, audio_chunk(k))));
  }
  // The manifest records the audio start as soon as the first chunk arrives.
  auto during = read_manifest(dir);
  ASSERT_TRUE(during);
  EXPECT_FALSE(during->complete);
  EXPECT_EQ(during->streams[1].start_ns, t0);
  ASSERT_TRUE((*w)->close());
  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  const ReadBack rb = read_all(**reader);
  ASSERT_EQ(rb.by_stream.at("cam").size(), 3u);
  const auto* c = rb.by_stream.at("cam")[2]->as<ColorImage>();
  ASSERT_EQ(c->image.type(), CV_8UC1);
  EXPECT_NEAR(cv::mean(c->image)[0], 100.0, 1.0);
  EXPECT_EQ(rb.by_stream.at("mic")[0]->stamp.ns(), t0);
  EXPECT_EQ(rb.by_stream.at("mic")[1]->stamp.ns(), t0 + kFramePeriodNs);
}

// decode_record (used by the self-calibration to decode only the frames it searches): the frame
// next() returns for that record, without moving the replay; errors for what has no index.
TEST(SessionRoundTrip, DecodeRecordGivesTheFrameNextGives) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_session(dir, 6);
  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  const auto records = (*reader)->records("cam");
  ASSERT_EQ(records.size(), 6u);
  auto third = (*reader)->decode_record("cam", 3);
  ASSERT_TRUE(third) << third.error().message;
  auto depth = (*reader)->decode_record("depth", 2);
  ASSERT_TRUE(depth) << depth.error().message;
  const ReadBack rb = read_all(**reader);  // the replay starts at the beginning all the same
  ASSERT_EQ(rb.by_stream.at("cam").size(), 6u);
  const FramePtr& expected = rb.by_stream.at("cam")[3];
  EXPECT_EQ((*third)->stamp, expected->stamp);
  EXPECT_EQ((*third)->sequence, expected->sequence);
  EXPECT_EQ((*third)->stamp.ns(), records[3].stamp_ns);
  EXPECT_EQ(
      cv::norm((*third)->as<ColorImage>()->image, expected->as<ColorImage>()->image, cv::NORM_INF),
      0);
  EXPECT_EQ(cv::norm((*depth)->as<DepthImage>()->depth_mm,
                     rb.by_stream.at("depth")[2]->as<DepthImage>()->depth_mm, cv::NORM_INF),
            0);
  auto beyond = (*reader)->decode_record("cam", 6);
  ASSERT_FALSE(beyond);
  EXPECT_EQ(beyond.error().code, ErrorCode::kInvalidArgument);
  auto unknown = (*reader)->decode_record("nope", 0);
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().code, ErrorCode::kNotFound);
  auto audio = (*reader)->decode_record("mic", 0);
  ASSERT_FALSE(audio) << "audio has no records";
}

TEST(SessionRoundTrip, MjpegFramesDecodeExactlyAsImdecode) {
  // The reader decodes mjpeg with libjpeg-turbo straight into BGR / grey; the pixels must be those
  // of cv::imdecode(IMREAD_UNCHANGED) on the same bytes (channel order, chroma upsampling).
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  SessionManifest m = make_manifest();
  StreamEntry grey = m.streams[0];
  grey.id = "grey";
  m.streams = {m.streams[0], grey};
  {
    auto w = SessionWriter::create(dir, m);
    ASSERT_TRUE(w) << w.error().message;
    cv::RNG rng(5);
    for (int k = 0; k < 4; ++k) {
      cv::Mat colour(kHeight, kWidth, CV_8UC3), g(kHeight, kWidth, CV_8UC1);
      rng.fill(colour, cv::RNG::UNIFORM, 0, 256);  // noise: every chroma sample differs
      rng.fill(g, cv::RNG::UNIFORM, 0, 256);
      colour(cv::Rect(0, 0, kWidth / 2, kHeight / 2)).setTo(cv::Scalar(255, 0, 0));  // pure blue
      const Timestamp t = Timestamp::from_ns(k * kFramePeriodNs);
      ASSERT_TRUE((*w)->write(*make_frame("cam", t, k, ColorImage{colour})));
      ASSERT_TRUE((*w)->write(*make_frame("grey", t, k, ColorImage{g})));
    }
    ASSERT_TRUE((*w)->close());
  }
  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  const ReadBack rb = read_all(**reader);
  for (const std::string id : {"cam", "grey"}) {
    const std::string data = read_file(dir / (id + ".mjpg"));
    std::istringstream idx(read_file(dir / (id + ".idx")));
    std::string line;
    std::getline(idx, line);  // header
    size_t k = 0;
    while (std::getline(idx, line)) {
      unsigned long long seq = 0, stamp = 0, offset = 0, size = 0;
      ASSERT_EQ(std::sscanf(line.c_str(), "%llu,%llu,%llu,%llu", &seq, &stamp, &offset, &size), 4);
      const std::vector<uchar> bytes(data.begin() + static_cast<std::ptrdiff_t>(offset),
                                     data.begin() + static_cast<std::ptrdiff_t>(offset + size));
      const cv::Mat expected = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
      ASSERT_LT(k, rb.by_stream.at(id).size());
      const cv::Mat& got = rb.by_stream.at(id)[k]->as<ColorImage>()->image;
      ASSERT_EQ(got.type(), expected.type()) << id << " frame " << k;
      ASSERT_EQ(got.size(), expected.size()) << id << " frame " << k;
      EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0) << id << " frame " << k;
      ++k;
    }
    EXPECT_EQ(k, 4u) << id;
  }
  // Blue stays blue: BGR order, as OpenCV.
  const cv::Mat& first = rb.by_stream.at("cam")[0]->as<ColorImage>()->image;
  const cv::Vec3b corner = first.at<cv::Vec3b>(4, 4);
  EXPECT_GT(corner[0], 200);
  EXPECT_LT(corner[2], 60);
}

// "video" (read-only): an OpenCV-readable container + a stamps file.
class VideoSession : public ::testing::Test {
 protected:
  void SetUp() override {
    SessionManifest m;
    StreamEntry cam;
    cam.id = "cam";
    cam.kind = SensorKind::kColor;
    cam.encoding = "video";
    cam.file = "cam.avi";
    cam.index = "cam.stamps";
    cam.rate_hz = 25;
    cam.width = kWidth;
    cam.height = kHeight;
    m.streams = {cam};
    m.complete = true;
    ASSERT_TRUE(write_manifest(tmp_.path(), m));
    cv::VideoWriter video((tmp_.path() / "cam.avi").string(), cv::CAP_OPENCV_MJPEG,
                          cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                          cv::Size(kWidth, kHeight));
    ASSERT_TRUE(video.isOpened());
    for (int k = 0; k < 10; ++k) video.write(color_frame(k));
    video.release();
  }
  void write_stamps(int n) {
    std::string text = "# stamp_ns\n";
    for (int k = 0; k < n; ++k) text += std::to_string(1000 + k * kFramePeriodNs) + "\n";
    write_file(tmp_.path() / "cam.stamps", text);
  }
  TempDir tmp_;
};

TEST_F(VideoSession, ReadsFramesWithTheirStamps) {
  write_stamps(10);
  auto reader = SessionReader::open(tmp_.path());
  ASSERT_TRUE(reader) << reader.error().message;
  const ReadBack rb = read_all(**reader);
  const auto& cams = rb.by_stream.at("cam");
  ASSERT_EQ(cams.size(), 10u);
  for (size_t k = 0; k < cams.size(); ++k) {
    EXPECT_EQ(cams[k]->stamp.ns(), 1000 + static_cast<int64_t>(k) * kFramePeriodNs);
    cv::Mat diff;
    cv::absdiff(cams[k]->as<ColorImage>()->image, color_frame(static_cast<int>(k)), diff);
    EXPECT_LT(cv::mean(diff.reshape(1))[0], 4.0);
  }
}

TEST_F(VideoSession, FrameCountMustMatchStamps) {
  write_stamps(12);
  auto reader = SessionReader::open(tmp_.path());
  ASSERT_FALSE(reader);
  EXPECT_EQ(reader.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(reader.error().message.find("cam.avi: truncated: video has 10 frames but cam.stamps "
                                        "has 12 stamps"),
            std::string::npos)
      << reader.error().message;
}

TEST(SessionWriter, RejectsBadFrames) {
  TempDir tmp;
  auto w = SessionWriter::create(tmp.path() / "s", make_manifest());
  ASSERT_TRUE(w) << w.error().message;
  SessionWriter& writer = **w;
  // Wrong size.
  auto st = writer.write(*make_frame("cam", Timestamp::from_ns(0), 0,
                                     ColorImage{cv::Mat(10, 10, CV_8UC3, cv::Scalar(0))}));
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(st.error().message.find("cam"), std::string::npos);
  // Wrong payload kind, unknown stream.
  EXPECT_FALSE(writer.write(*make_frame("cam", Timestamp::from_ns(0), 0, skeleton_frame(0))));
  auto unknown = writer.write(*make_frame("nope", Timestamp::from_ns(0), 0, skeleton_frame(0)));
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().code, ErrorCode::kNotFound);
  // Stamps must strictly increase.
  ASSERT_TRUE(writer.write(*make_frame("skel", Timestamp::from_ns(100), 0, skeleton_frame(0))));
  auto same = writer.write(*make_frame("skel", Timestamp::from_ns(100), 1, skeleton_frame(1)));
  ASSERT_FALSE(same);
  EXPECT_NE(same.error().message.find("skel"), std::string::npos);
  EXPECT_NE(same.error().message.find("not after previous"), std::string::npos);
  // Audio stays on the session clock: a jump of a minute is refused (another clock).
  ASSERT_TRUE(writer.write(*make_frame("mic", Timestamp::from_ns(0), 0, audio_chunk(0))));
  auto jump = writer.write(*make_frame("mic", Timestamp::from_seconds(120), 1, audio_chunk(1)));
  ASSERT_FALSE(jump);
  EXPECT_NE(jump.error().message.find("not the same clock"), std::string::npos);
  ASSERT_TRUE(writer.write(*make_frame("mic", Timestamp::from_ns(40'000'000), 1, audio_chunk(1))));
  ASSERT_TRUE(writer.close());
  // After close, writes are refused; the folder cannot be reused for a new session.
  EXPECT_FALSE(writer.write(*make_frame("skel", Timestamp::from_ns(200), 2, skeleton_frame(2))));
  auto again = SessionWriter::create(tmp.path() / "s", make_manifest());
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("already contains"), std::string::npos);
}

// A device that skips or repeats a little (ALSA xruns): the WAV stays on the clock, gaps are
// silence and overlaps are cut, and the session reads back.
TEST(SessionWriter, AudioGapsAreFilledAndOverlapsCut) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  auto w = SessionWriter::create(dir, make_manifest());
  ASSERT_TRUE(w) << w.error().message;
  const int64_t chunk_ns = audio_chunk(0).duration().ns();
  ASSERT_TRUE((*w)->write(*make_frame("mic", Timestamp::from_ns(0), 0, audio_chunk(0))));
  // 10 ms late: 10 ms of silence before it.
  ASSERT_TRUE((*w)->write(
      *make_frame("mic", Timestamp::from_ns(chunk_ns + 10'000'000), 1, audio_chunk(1))));
  // Then 5 ms early: its first 5 ms are cut.
  ASSERT_TRUE((*w)->write(*make_frame(
      "mic", Timestamp::from_ns(2 * chunk_ns + 10'000'000 - 5'000'000), 2, audio_chunk(2))));
  ASSERT_TRUE((*w)->close());
  auto reader = SessionReader::open(dir, {.only = {"mic"}});
  ASSERT_TRUE(reader) << reader.error().message;
  int64_t samples = 0;
  for (auto f = (*reader)->next(); f; f = (*reader)->next())
    samples += (*f)->as<AudioChunk>()->frames();
  // 3 chunks + 10 ms of silence - 5 ms cut.
  EXPECT_EQ(samples, 3 * audio_chunk(0).frames() + kSampleRate / 100 - kSampleRate / 200);
}

TEST(SessionWriter, OptionsCheck) {
  EXPECT_TRUE(SessionWriterOptions{}.check());
  EXPECT_FALSE((SessionWriterOptions{.jpeg_quality = 0}.check()));
  EXPECT_TRUE((SessionWriterOptions{.png_compression = 0}.check()));
  EXPECT_TRUE((SessionWriterOptions{.png_compression = 9}.check()));
  EXPECT_FALSE((SessionWriterOptions{.png_compression = -1}.check()));
  auto bad_png = SessionWriterOptions{.png_compression = 10}.check();
  ASSERT_FALSE(bad_png);
  EXPECT_NE(bad_png.error().message.find("png_compression must be in [0, 9], got 10"),
            std::string::npos)
      << bad_png.error().message;
  EXPECT_FALSE((SessionWriterOptions{.flush_interval = Duration::from_ns(0)}.check()));
  EXPECT_TRUE(SessionReaderOptions{}.check());
  EXPECT_FALSE((SessionReaderOptions{.audio_chunk = Duration::from_ns(0)}.check()));
}

TEST(SessionWriter, DestructorClosesTheSession) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  {
    auto w = SessionWriter::create(dir, make_manifest());
    ASSERT_TRUE(w);
    ASSERT_TRUE(write_ticks(**w, 0, 3));
  }
  auto m = read_manifest(dir);
  ASSERT_TRUE(m);
  EXPECT_TRUE(m->complete);
}

// Crash safety, for each depth encoding (param): a child records ~3 s with flush_interval 1 s and
// is SIGKILLed; everything up to the last flush (at session time 2 s) reads back, and nothing else
// (no garbage).
class SessionCrashSafety : public ::testing::TestWithParam<std::string> {};

TEST_P(SessionCrashSafety, KillAfterThreeSecondsReadsBackFlushedData) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    auto w = SessionWriter::create(dir, make_manifest(GetParam()),
                                   {.flush_interval = Duration::from_seconds(1.0)});
    if (!w) ::_exit(2);
    if (!write_ticks(**w, 0, 75)) ::_exit(3);  // stamps 0 .. 2.96 s
    ::raise(SIGKILL);
    ::_exit(4);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "child exit code " << WEXITSTATUS(status);
  ASSERT_EQ(WTERMSIG(status), SIGKILL);

  auto strict = SessionReader::open(dir, {.allow_incomplete = false});
  ASSERT_FALSE(strict);
  EXPECT_NE(strict.error().message.find("session.yaml"), std::string::npos);

  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_FALSE((*reader)->manifest().complete);
  EXPECT_EQ((*reader)->manifest().streams[1].encoding, GetParam());
  const ReadBack rb = read_all(**reader);
  for (const char* id : {"cam", "depth", "skel", "mic"}) {
    ASSERT_TRUE(rb.by_stream.count(id)) << id;
    const auto& frames = rb.by_stream.at(id);
    // The flush at 2.0 s made at least everything stamped before 2.0 s durable.
    EXPECT_GE(frames.back()->stamp.ns(), 2'000'000'000LL - kFramePeriodNs) << id;
    EXPECT_LE(frames.back()->stamp.ns(), 74 * kFramePeriodNs) << id;
  }
  expect_content(rb);
}

TEST_P(SessionCrashSafety, TornTailOfIndexAndDataIsIgnored) {
  TempDir tmp;
  const auto dir = tmp.path() / "s";
  write_session(dir, 10, make_manifest(GetParam()));
  // Pretend the recorder died: complete false, a partial index line, half a frame of data, a
  // partial skeleton line.
  replace_in_file(dir / kManifestName, "complete: true", "complete: false");
  {
    std::ofstream idx(dir / "cam.idx", std::ios::app);
    idx << "10,400000000,99999";
    std::ofstream data(dir / "cam.mjpg", std::ios::app | std::ios::binary);
    data << "\xFF\xD8garbage";
    std::ofstream skel(dir / "skel.jsonl", std::ios::app);
    skel << "{\"stamp_ns\":400000000,\"bod";
    std::ofstream didx(dir / "depth.idx", std::ios::app);
    didx << "10,400000000,";
    std::ofstream ddata(dir / "depth.depth", std::ios::app | std::ios::binary);
    ddata << "\x89PNG\r\n\x1A\ngarbage";
  }
  auto reader = SessionReader::open(dir);
  ASSERT_TRUE(reader) << reader.error().message;
  const ReadBack rb = read_all(**reader);
  EXPECT_EQ(rb.by_stream.at("cam").size(), 10u);
  EXPECT_EQ(rb.by_stream.at("depth").size(), 10u);
  EXPECT_EQ(rb.by_stream.at("skel").size(), 10u);
  expect_content(rb);
  // The same torn files in a session that claims to be complete: the same rule (dropped,
  // reported as a torn tail), never the whole session lost.
  replace_in_file(dir / kManifestName, "complete: false", "complete: true");
  auto complete = SessionReader::open(dir);
  ASSERT_TRUE(complete) << complete.error().message;
  const ReadBack again = read_all(**complete);
  EXPECT_EQ(again.by_stream.at("cam").size(), 10u);
  EXPECT_EQ(again.by_stream.at("skel").size(), 10u);
  for (const auto& d : (*complete)->damage()) {
    if (d.stream == "mic") continue;
    EXPECT_EQ(d.torn_tail, 1u) << d.stream;
    EXPECT_EQ(d.damaged, 0u) << d.stream;
  }
}

INSTANTIATE_TEST_SUITE_P(DepthEncodings, SessionCrashSafety, ::testing::Values("raw16", "png16"),
                         [](const auto& info) { return info.param; });

TEST(Truth, ReadsRecordsAndNamesBadLines) {
  TempDir tmp;
  const auto path = tmp.path() / "truth.jsonl";
  write_file(path,
             "{\"type\":\"meta\",\"truth_version\":1}\n\n{\"type\":\"face\",\"stamp_ns\":0}\n");
  auto r = read_truth(path);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->size(), 2u);
  EXPECT_EQ((*r)[1]["type"], "face");
  write_file(path, "{\"type\":\"meta\"}\n{\"type\":\"face\",\"stamp_ns\":\n");
  auto bad = read_truth(path);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(bad.error().message.find("truth.jsonl: line 2"), std::string::npos)
      << bad.error().message;
  auto missing = read_truth(tmp.path() / "nope.jsonl");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
}

}  // namespace
}  // namespace dreamsense::sources
