// Session format: every kind of bad input gives a one-line error naming the file and the problem.

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <sndfile.h>

#include <algorithm>
#include <fstream>
#include <vector>

#include "session_test_util.hpp"

namespace dreamsense::sources {
namespace {

using namespace test_util;

// A valid closed session of 10 ticks in <tmp>/s.
class SessionBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = tmp_.path() / "s";
    write_session(dir_, 10);
  }
  // Opens the session and returns its error (fails the test if it opens).
  Error open_error(SessionReaderOptions options = {}) {
    auto r = SessionReader::open(dir_, options);
    if (r) {
      ADD_FAILURE() << "session opened";
      return Error{};
    }
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << "message is not one line";
    return r.error();
  }
  TempDir tmp_;
  std::filesystem::path dir_;
};

#define EXPECT_TEXT_HAS(str, text) EXPECT_NE((str).find(text), std::string::npos) << (str)
#define EXPECT_MESSAGE_HAS(error, text) \
  EXPECT_NE((error).message.find(text), std::string::npos) << (error).message

TEST_F(SessionBadInput, MissingStreamFile) {
  std::filesystem::remove(dir_ / "cam.mjpg");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kNotFound);
  EXPECT_MESSAGE_HAS(e, "cam.mjpg: missing (declared in session.yaml)");
}

TEST_F(SessionBadInput, MissingIndexFile) {
  std::filesystem::remove(dir_ / "depth.idx");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kNotFound);
  EXPECT_MESSAGE_HAS(e, "depth.idx: missing");
}

TEST_F(SessionBadInput, MissingCalibrationFile) {
  replace_in_file(dir_ / kManifestName, "frame: cam",
                  "frame: cam\n    calibration: calib/cam.yaml");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kNotFound);
  EXPECT_MESSAGE_HAS(e, "calib/cam.yaml: missing");
}

TEST_F(SessionBadInput, MissingManifest) {
  std::filesystem::remove(dir_ / kManifestName);
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kNotFound);
  EXPECT_MESSAGE_HAS(e, "session.yaml");
}

TEST_F(SessionBadInput, UnknownFormatVersion) {
  replace_in_file(dir_ / kManifestName, "format_version: 1", "format_version: 7");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kUnsupported);
  EXPECT_MESSAGE_HAS(e, "session.yaml: unknown format_version 7 (this build reads 1)");
}

TEST_F(SessionBadInput, NotASessionManifest) {
  replace_in_file(dir_ / kManifestName, "format: dreamsense-session", "format: something-else");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kUnsupported);
  EXPECT_MESSAGE_HAS(e, "session.yaml");
}

TEST_F(SessionBadInput, InvalidYaml) {
  write_file(dir_ / kManifestName, "format: dreamsense-session\nstreams: [\n  {id: x\n");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "session.yaml: line");
}

TEST_F(SessionBadInput, TextThatIsNotUtf8) {
  // A Latin-1 name (0xE9): JSON outputs need UTF-8, so it is refused before any analysis.
  replace_in_file(dir_ / kManifestName, "name: ", "name: Z\xE9 ");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "session.yaml: line");
  EXPECT_MESSAGE_HAS(e, "not valid UTF-8");
}

TEST_F(SessionBadInput, MissingRequiredKey) {
  replace_in_file(dir_ / kManifestName, "    encoding: raw16\n", "");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "session.yaml: missing required key 'streams[1] (depth).encoding'");
}

TEST_F(SessionBadInput, WrongTypeOfValue) {
  replace_in_file(dir_ / kManifestName, "width: 64", "width: wide");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "session.yaml: key 'streams[0] (cam).width': expected an integer");
}

// Fuzz finding 6: a list used as a key made as<std::string>() throw YAML::BadConversion out of
// the reader (the program ended).
TEST_F(SessionBadInput, ListAsMetadataKey) {
  replace_in_file(dir_ / kManifestName, "generator:", "? [a, b]\n  : x\n  generator:");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "session.yaml: key 'metadata': a key must be a name");
}

TEST_F(SessionBadInput, DuplicateStreamId) {
  replace_in_file(dir_ / kManifestName, "id: depth", "id: cam");
  const Error e = open_error();
  EXPECT_MESSAGE_HAS(e, "session.yaml: duplicate stream id 'cam'");
}

TEST_F(SessionBadInput, UnknownKind) {
  replace_in_file(dir_ / kManifestName, "kind: skeleton", "kind: thermal");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "session.yaml");
  EXPECT_MESSAGE_HAS(e, "unknown kind 'thermal'");
}

TEST_F(SessionBadInput, UnknownEncoding) {
  replace_in_file(dir_ / kManifestName, "encoding: jsonl", "encoding: csv");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kUnsupported);
  EXPECT_MESSAGE_HAS(e, "session.yaml");
  EXPECT_MESSAGE_HAS(e, "unknown encoding 'csv'");
}

TEST_F(SessionBadInput, UnknownStreamInOnly) {
  const Error e = open_error({.only = {"camera_left"}});
  EXPECT_EQ(e.code, ErrorCode::kNotFound);
  EXPECT_MESSAGE_HAS(e, "no stream 'camera_left'");
}

// ---- Damage policy (docs/session_format.md "Damaged recordings"): a torn tail is dropped, a
// damaged record in the middle is skipped and counted, too much damage is an error.

// Opens the session (failing the test if it does not) and reads every frame of `stream`.
struct StreamReadBack {
  std::vector<int64_t> stamps;
  StreamDamage damage;
};
StreamReadBack read_stream(const std::filesystem::path& dir, const SensorId& stream,
                           SessionReaderOptions options = {}) {
  options.only = {stream};
  StreamReadBack out;
  auto reader = SessionReader::open(dir, options);
  if (!reader) {
    ADD_FAILURE() << reader.error().message;
    return out;
  }
  for (auto f = (*reader)->next(); f; f = (*reader)->next()) out.stamps.push_back((*f)->stamp.ns());
  out.damage = (*reader)->damage().at(0);
  return out;
}

TEST_F(SessionBadInput, TruncatedMjpegDataIsATornTail) {
  const auto path = dir_ / "cam.mjpg";
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
  // Half the frames of a session marked complete: lost data beyond the 20 % threshold.
  EXPECT_MESSAGE_HAS(open_error(), "cam.mjpg: ");
  EXPECT_MESSAGE_HAS(open_error(), "torn at the end; --allow-damaged");
  // Marked incomplete (a crash), the torn tail is what a crash leaves: read what is there.
  replace_in_file(dir_ / kManifestName, "complete: true", "complete: false");
  const StreamReadBack r = read_stream(dir_, "cam");
  EXPECT_GT(r.damage.torn_tail, 0u);
  EXPECT_EQ(r.damage.damaged, 0u);
  EXPECT_EQ(r.stamps.size() + r.damage.torn_tail, 10u);  // nothing else lost
}

TEST_F(SessionBadInput, TruncatedDepthDataIsATornTail) {
  std::filesystem::resize_file(dir_ / "depth.depth", 3 * kWidth * kHeight * 2);
  const StreamReadBack r = read_stream(dir_, "depth", {.allow_damaged = true});
  EXPECT_EQ(r.stamps.size(), 3u);
  EXPECT_EQ(r.damage.torn_tail, 7u);
}

TEST_F(SessionBadInput, CorruptJpegBytesCostThatFrame) {
  // Frame 3 keeps its SOI/EOI markers but everything between is zeros: fails to decode.
  const std::string idx = read_file(dir_ / "cam.idx");
  size_t line_start = 0;
  for (int skip = 0; skip < 4; ++skip) line_start = idx.find('\n', line_start) + 1;  // header+3
  unsigned long long seq = 0, stamp = 0, offset = 0, size = 0;
  ASSERT_EQ(
      std::sscanf(idx.c_str() + line_start, "%llu,%llu,%llu,%llu", &seq, &stamp, &offset, &size),
      4);
  ASSERT_EQ(seq, 3u);
  {
    std::fstream f(dir_ / "cam.mjpg", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(offset + 2));
    const std::string zeros(size - 4, '\0');
    f.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
  }
  const StreamReadBack r = read_stream(dir_, "cam");
  ASSERT_EQ(r.stamps.size(), 9u);
  EXPECT_EQ(std::count(r.stamps.begin(), r.stamps.end(), static_cast<int64_t>(stamp)), 0);
  EXPECT_EQ(r.damage.damaged, 1u);
  ASSERT_EQ(r.damage.first.size(), 1u);
  EXPECT_EQ(r.damage.first[0].record, 3u);
  EXPECT_EQ(r.damage.first[0].stamp_ns, static_cast<int64_t>(stamp));
  EXPECT_TEXT_HAS(r.damage.first[0].what, "cam.mjpg: corrupt: frame 3");
}

TEST_F(SessionBadInput, HugeSizeInAJpegHeaderCostsThatFrameBeforeDecoding) {
  // Frame 0's start-of-frame marker (FF C0..C2: length, precision, height, width) declares
  // 30000x30000: refused from the header; decoding would first allocate 2.7 GB.
  std::string data = read_file(dir_ / "cam.mjpg");
  size_t sof = std::string::npos;
  for (char kind : {'\xC0', '\xC1', '\xC2'})
    sof = std::min(sof, data.find(std::string{'\xFF', kind}));
  ASSERT_NE(sof, std::string::npos);
  data.replace(sof + 5, 4, std::string("\x75\x30\x75\x30", 4));
  write_file(dir_ / "cam.mjpg", data);
  const StreamReadBack r = read_stream(dir_, "cam");
  EXPECT_EQ(r.stamps.size(), 9u);
  ASSERT_EQ(r.damage.damaged, 1u);
  EXPECT_TEXT_HAS(r.damage.first[0].what,
                  "cam.mjpg: frame 0 is 30000x30000, session.yaml declares 64x48");
}

TEST_F(SessionBadInput, CorruptJpegMarkerCostsThatFrame) {
  // Overwrite the first bytes of frame 0: no SOI marker, found at open.
  {
    std::fstream f(dir_ / "cam.mjpg", std::ios::in | std::ios::out | std::ios::binary);
    f.write("\0\0\0\0", 4);
  }
  const StreamReadBack r = read_stream(dir_, "cam");
  EXPECT_EQ(r.stamps.size(), 9u);
  EXPECT_EQ(r.damage.damaged, 1u);
  ASSERT_FALSE(r.damage.first.empty());
  EXPECT_TEXT_HAS(r.damage.first[0].what, "not a complete JPEG");
}

TEST_F(SessionBadInput, TooMuchDamageIsAnErrorUnlessAllowed) {
  // Three of ten frames without markers: more than 20 %.
  const std::string idx = read_file(dir_ / "cam.idx");
  std::vector<unsigned long long> offsets;
  size_t pos = idx.find('\n') + 1;
  for (int k = 0; k < 10; ++k, pos = idx.find('\n', pos) + 1) {
    unsigned long long seq = 0, stamp = 0, offset = 0, size = 0;
    ASSERT_EQ(std::sscanf(idx.c_str() + pos, "%llu,%llu,%llu,%llu", &seq, &stamp, &offset, &size),
              4);
    offsets.push_back(offset);
  }
  {
    std::fstream f(dir_ / "cam.mjpg", std::ios::in | std::ios::out | std::ios::binary);
    for (int k : {2, 4, 6}) {
      f.seekp(static_cast<std::streamoff>(offsets[static_cast<size_t>(k)]));
      f.write("\0\0", 2);
    }
  }
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "cam.mjpg: 3 of 10 records damaged");
  EXPECT_MESSAGE_HAS(e, "--allow-damaged");
  const StreamReadBack r = read_stream(dir_, "cam", {.allow_damaged = true});
  EXPECT_EQ(r.stamps.size(), 7u);
  EXPECT_EQ(r.damage.damaged, 3u);
}

TEST_F(SessionBadInput, UnreadableWav) {
  write_file(dir_ / "mic.wav", std::string(4096, 'x'));
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "mic.wav: unreadable: ");
}

TEST_F(SessionBadInput, TruncatedWavIsATornTail) {
  const auto path = dir_ / "mic.wav";
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 1000);
  auto reader = SessionReader::open(dir_, {.only = {"mic"}});
  ASSERT_TRUE(reader) << reader.error().message;
  int64_t samples = 0;
  for (auto f = (*reader)->next(); f; f = (*reader)->next())
    samples += (*f)->as<AudioChunk>()->frames();
  EXPECT_EQ(samples, 6400 - 250);
  EXPECT_GE((*reader)->damage().at(0).torn_tail, 1u);
}

void write_wav(const std::filesystem::path& path, int rate, int channels) {
  SF_INFO info{};
  info.samplerate = rate;
  info.channels = channels;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* f = sf_open(path.c_str(), SFM_WRITE, &info);
  ASSERT_NE(f, nullptr);
  std::vector<short> zeros(static_cast<size_t>(rate / 10 * channels), 0);
  sf_writef_short(f, zeros.data(), rate / 10);
  sf_close(f);
}

TEST_F(SessionBadInput, WrongRateWav) {
  write_wav(dir_ / "mic.wav", 44100, kChannels);
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "mic.wav: sample rate 44100 Hz, session.yaml declares 16000 Hz");
}

TEST_F(SessionBadInput, WrongChannelCountWav) {
  write_wav(dir_ / "mic.wav", kSampleRate, 4);
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "mic.wav: 4 channels, session.yaml declares 2");
}

TEST_F(SessionBadInput, NonIncreasingStampInIndexCostsThatFrame) {
  // Frame 2 (line 4, after the header line) goes back in time.
  replace_in_file(dir_ / "cam.idx", "2,80000000,", "2,30000000,");
  const StreamReadBack r = read_stream(dir_, "cam");
  EXPECT_EQ(r.stamps.size(), 9u);
  EXPECT_EQ(r.damage.damaged, 1u);
  ASSERT_FALSE(r.damage.first.empty());
  EXPECT_TEXT_HAS(r.damage.first[0].what,
                  "cam.idx: line 4: stamp 30000000 not after previous 40000000");
}

TEST_F(SessionBadInput, MalformedIndexLineCostsThatFrame) {
  replace_in_file(dir_ / "depth.idx", "\n5,", "\n5;");
  const StreamReadBack r = read_stream(dir_, "depth");
  EXPECT_EQ(r.stamps.size(), 9u);
  EXPECT_EQ(r.damage.damaged, 1u);
  ASSERT_FALSE(r.damage.first.empty());
  EXPECT_EQ(r.damage.first[0].record, 7u);  // the line
  EXPECT_TEXT_HAS(r.damage.first[0].what, "depth.idx: line 7: malformed index line");
}

TEST_F(SessionBadInput, IndexCutShortInACompleteSessionIsReported) {
  // Keep the header and 4 of 10 index lines: the data of 6 frames is no longer indexed.
  const std::string idx = read_file(dir_ / "cam.idx");
  size_t pos = 0;
  for (int k = 0; k < 5; ++k) pos = idx.find('\n', pos) + 1;
  write_file(dir_ / "cam.idx", idx.substr(0, pos));
  const StreamReadBack r = read_stream(dir_, "cam", {.allow_damaged = true});
  EXPECT_EQ(r.stamps.size(), 4u);
  EXPECT_NEAR(static_cast<double>(r.damage.damaged), 6.0, 1.0);  // estimated from frame sizes
  ASSERT_FALSE(r.damage.first.empty());
  EXPECT_TEXT_HAS(r.damage.first[0].what, "not in cam.idx");
  EXPECT_MESSAGE_HAS(open_error(), "records damaged");  // > 20 %: not analysed silently
}

TEST_F(SessionBadInput, MalformedSkeletonLineCostsThatRecord) {
  replace_in_file(dir_ / "skel.jsonl", "{\"stamp_ns\":120000000", "{\"stamp_ns\":120000000,,");
  const StreamReadBack r = read_stream(dir_, "skel");
  EXPECT_EQ(r.stamps.size(), 9u);
  EXPECT_EQ(r.damage.damaged, 1u);
  ASSERT_FALSE(r.damage.first.empty());
  EXPECT_EQ(r.damage.first[0].record, 4u);
  EXPECT_TEXT_HAS(r.damage.first[0].what, "skel.jsonl: line 4: malformed JSON");
}

TEST_F(SessionBadInput, CutLastSkeletonLineIsATornTailEvenInACompleteSession) {
  std::string text = read_file(dir_ / "skel.jsonl");
  text.resize(text.size() - 10);  // the recorder died in the middle of the last line
  write_file(dir_ / "skel.jsonl", text);
  const StreamReadBack r = read_stream(dir_, "skel");
  EXPECT_EQ(r.stamps.size(), 9u);
  EXPECT_EQ(r.damage.torn_tail, 1u);
  EXPECT_EQ(r.damage.damaged, 0u);
}

TEST_F(SessionBadInput, ImplausibleJointsAndEmptyLinesAreCounted) {
  replace_in_file(dir_ / "skel.jsonl", "{\"stamp_ns\":120000000", "\n{\"stamp_ns\":120000000");
  std::string text = read_file(dir_ / "skel.jsonl");
  const auto head = text.find("\"head\":[");
  ASSERT_NE(head, std::string::npos);
  const auto comma = text.find(',', head + 8);
  text.replace(head + 8, comma - (head + 8), "1e308");  // x of the head: 1e308 m
  write_file(dir_ / "skel.jsonl", text);
  const StreamReadBack r = read_stream(dir_, "skel", {.allow_damaged = true});
  EXPECT_EQ(r.damage.empty_lines, 1u);
  EXPECT_EQ(r.damage.damaged, 1u);
  EXPECT_EQ(r.stamps.size(), 9u);
}

TEST_F(SessionBadInput, UnknownSkeletonJointCostsThatRecord) {
  replace_in_file(dir_ / "skel.jsonl", "\"head\"", "\"tail\"");
  const StreamReadBack r = read_stream(dir_, "skel", {.allow_damaged = true});
  ASSERT_FALSE(r.damage.first.empty());
  EXPECT_TEXT_HAS(r.damage.first[0].what, "skel.jsonl: line 1: bodies[0]: unknown joint 'tail'");
}

TEST_F(SessionBadInput, LinksOutOfTheSessionAreRefused) {
  TempDir outside;
  std::filesystem::rename(dir_ / "skel.jsonl", outside.path() / "skel.jsonl");
  std::filesystem::create_symlink(outside.path() / "skel.jsonl", dir_ / "skel.jsonl");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kInvalidArgument);
  EXPECT_MESSAGE_HAS(e, "skel.jsonl: is a link to a file outside the session folder");
  EXPECT_TRUE(SessionReader::open(dir_, {.follow_links_outside = true}));
}

TEST_F(SessionBadInput, ClockMismatch) {
  // The microphone claims to start an hour later than the other streams.
  replace_in_file(dir_ / kManifestName, "start_ns: 0", "start_ns: 3600000000000");
  const Error e = open_error();
  EXPECT_EQ(e.code, ErrorCode::kCorruptData);
  EXPECT_MESSAGE_HAS(e, "mic.wav: clock mismatch");
}

TEST_F(SessionBadInput, IncompleteSessionWhenNotAllowed) {
  replace_in_file(dir_ / kManifestName, "complete: true", "complete: false");
  const Error e = open_error({.allow_incomplete = false});
  EXPECT_MESSAGE_HAS(e, "session.yaml: incomplete session");
  EXPECT_TRUE(SessionReader::open(dir_));
}

TEST(SessionWriterBadInput, UnwritableOutputFolder) {
  TempDir tmp;
  // Tests may run as root, so "unwritable" is a parent that is a regular file.
  write_file(tmp.path() / "file", "not a folder");
  const auto dir = tmp.path() / "file" / "session";
  auto w = SessionWriter::create(dir, make_manifest());
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error().code, ErrorCode::kIoError);
  EXPECT_MESSAGE_HAS(w.error(), dir.string() + ": cannot create session folder");
}

TEST(SessionWriterBadInput, InvalidManifest) {
  TempDir tmp;
  SessionManifest m = make_manifest();
  m.streams[1].id = "cam";
  auto dup = SessionWriter::create(tmp.path() / "a", m);
  ASSERT_FALSE(dup);
  EXPECT_MESSAGE_HAS(dup.error(), "duplicate stream id 'cam'");
  m = make_manifest();
  m.streams[0].encoding = "video";
  auto video = SessionWriter::create(tmp.path() / "b", m);
  ASSERT_FALSE(video);
  EXPECT_EQ(video.error().code, ErrorCode::kUnsupported);
  m = make_manifest();
  m.streams[0].file = "../escape.mjpg";
  auto escape = SessionWriter::create(tmp.path() / "c", m);
  ASSERT_FALSE(escape);
  EXPECT_MESSAGE_HAS(escape.error(), "not a relative path inside the session folder");
}

}  // namespace
}  // namespace dreamsense::sources
