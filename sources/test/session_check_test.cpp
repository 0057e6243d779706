// check_session / repair_session (`dreamsense check`): each kind of damage is found in the right
// stream with the right count, and the repaired copy is sound, complete and holds every record
// the reader accepts, byte for byte.

#include "dreamsense/sources/session_check.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <vector>

#include "session_test_util.hpp"

namespace dreamsense::sources {
namespace {

using namespace test_util;
namespace fs = std::filesystem;

constexpr int kTicks = 20;

class SessionCheckTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = tmp_.path() / "s";
    write_session(dir_, kTicks);
  }
  SessionCheck check(const fs::path& dir) {
    auto c = check_session(dir);
    EXPECT_TRUE(c) << c.error().message;
    return c ? *c : SessionCheck{};
  }
  static const StreamCheck& stream(const SessionCheck& c, const std::string& id) {
    for (const auto& s : c.streams)
      if (s.stream == id) return s;
    throw std::runtime_error("no stream " + id);
  }
  // Repairs into <tmp>/fixed and checks the copy.
  SessionRepair repair() {
    auto r = repair_session(dir_, fixed());
    EXPECT_TRUE(r) << r.error().message;
    return r ? *r : SessionRepair{};
  }
  fs::path fixed() const { return tmp_.path() / "fixed"; }
  // The index lines (without comments) of `index`.
  std::vector<std::string> index_lines(const fs::path& index) {
    std::vector<std::string> out;
    std::ifstream in(index);
    for (std::string l; std::getline(in, l);)
      if (!l.empty() && l[0] != '#') out.push_back(l);
    return out;
  }
  static std::vector<unsigned long long> fields(const std::string& line) {
    unsigned long long a = 0, b = 0, c = 0, d = 0;
    EXPECT_EQ(std::sscanf(line.c_str(), "%llu,%llu,%llu,%llu", &a, &b, &c, &d), 4) << line;
    return {a, b, c, d};
  }
  // Overwrites bytes in the middle of cam.mjpg's frame k (its markers stay).
  void corrupt_frame(int k) {
    const auto f = fields(index_lines(dir_ / "cam.idx").at(static_cast<size_t>(k)));
    std::fstream data(dir_ / "cam.mjpg", std::ios::in | std::ios::out | std::ios::binary);
    data.seekp(static_cast<std::streamoff>(f[2] + f[3] / 2));
    std::string noise(std::min<unsigned long long>(200, f[3] / 3), '\0');
    for (size_t i = 0; i < noise.size(); ++i) noise[i] = static_cast<char>((i * 7919) % 251);
    data.write(noise.data(), static_cast<std::streamsize>(noise.size()));
  }
  TempDir tmp_;
  fs::path dir_;
};

TEST_F(SessionCheckTest, UndamagedSessionIsSound) {
  const SessionCheck c = check(dir_);
  EXPECT_TRUE(c.sound()) << c.table();
  ASSERT_EQ(c.streams.size(), 4u);
  for (const auto& s : c.streams) {
    EXPECT_TRUE(s.sound()) << s.stream;
    EXPECT_EQ(s.damage.damaged + s.damage.torn_tail, 0u) << s.stream;
    EXPECT_EQ(s.gap_count, 0u) << s.stream;
  }
  EXPECT_EQ(stream(c, "cam").damage.records, static_cast<uint64_t>(kTicks));
  EXPECT_EQ(stream(c, "skel").delivered, static_cast<uint64_t>(kTicks));
  EXPECT_NEAR(*stream(c, "mic").audio_seconds, kTicks * 0.04, 1e-9);
  EXPECT_EQ(c.to_json().at("sound"), true);
  EXPECT_NE(c.table().find("session is sound"), std::string::npos);
}

TEST_F(SessionCheckTest, TornSkeletonTail) {
  std::string text = read_file(dir_ / "skel.jsonl");
  text.resize(text.size() - 30);
  write_file(dir_ / "skel.jsonl", text);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  EXPECT_EQ(stream(c, "skel").damage.torn_tail, 1u);
  EXPECT_EQ(stream(c, "skel").damage.damaged, 0u);
  EXPECT_TRUE(stream(c, "cam").sound());
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete);
  EXPECT_TRUE(r.after.sound()) << r.after.table();
  EXPECT_EQ(stream(r.after, "skel").delivered, static_cast<uint64_t>(kTicks - 1));
  // Undamaged streams are copied byte for byte.
  EXPECT_EQ(read_file(fixed() / "cam.mjpg"), read_file(dir_ / "cam.mjpg"));
  EXPECT_EQ(read_file(fixed() / "mic.wav"), read_file(dir_ / "mic.wav"));
  auto m = read_manifest(fixed());
  ASSERT_TRUE(m);
  EXPECT_TRUE(m->complete);
}

TEST_F(SessionCheckTest, BadSkeletonLineInTheMiddle) {
  std::string text = read_file(dir_ / "skel.jsonl");
  size_t pos = 0;
  for (int i = 0; i < 7; ++i) pos = text.find('\n', pos) + 1;  // line 8
  text.insert(pos + 5, "}}garbage");
  write_file(dir_ / "skel.jsonl", text);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  const StreamCheck& s = stream(c, "skel");
  EXPECT_EQ(s.damage.damaged, 1u);
  ASSERT_EQ(s.damage.first.size(), 1u);
  EXPECT_EQ(s.damage.first[0].record, 8u);  // the line
  EXPECT_EQ(s.gap_count, 1u);               // the record it cost
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_EQ(r.streams.at(2).dropped, 1u);
  EXPECT_EQ(stream(r.after, "skel").delivered, static_cast<uint64_t>(kTicks - 1));
}

// A stream with no records (a body tracker that never saw anyone) is empty, not damaged.
TEST_F(SessionCheckTest, EmptyStreamIsANoteNotDamage) {
  write_file(dir_ / "skel.jsonl", "");
  const SessionCheck c = check(dir_);
  EXPECT_TRUE(c.sound()) << c.table();
  const StreamCheck& s = stream(c, "skel");
  EXPECT_EQ(s.damage.records, 0u);
  EXPECT_TRUE(s.problems.empty());
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_NE(s.notes[0].find("no records"), std::string::npos) << s.notes[0];
  const std::string table = c.table();
  EXPECT_NE(table.find("empty"), std::string::npos) << table;
  EXPECT_NE(table.find("skel: note: skel.jsonl: no records"), std::string::npos) << table;
  EXPECT_NE(table.find("session is sound"), std::string::npos) << table;
  EXPECT_EQ(c.to_json()["streams"][2]["notes"].size(), 1u);
  EXPECT_TRUE(stream(c, "cam").notes.empty());
  // One line of garbage is a damaged record, not an empty stream.
  write_file(dir_ / "skel.jsonl", "garbage\n");
  const SessionCheck d = check(dir_);
  EXPECT_FALSE(d.sound());
  EXPECT_TRUE(stream(d, "skel").notes.empty());
}

TEST_F(SessionCheckTest, TornAudioTail) {
  fs::resize_file(dir_ / "mic.wav", fs::file_size(dir_ / "mic.wav") - 1000);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  EXPECT_GE(stream(c, "mic").damage.torn_tail, 1u);
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_EQ(stream(r.after, "mic").damage.torn_tail, 0u);
  // The samples that were there are kept: 1000 bytes = 250 stereo samples fewer.
  EXPECT_NEAR(*stream(r.after, "mic").audio_seconds, kTicks * 0.04 - 250.0 / kSampleRate, 1e-9);
}

TEST_F(SessionCheckTest, CorruptedMjpegFrames) {
  corrupt_frame(5);
  corrupt_frame(12);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  const StreamCheck& s = stream(c, "cam");
  EXPECT_EQ(s.damage.damaged, 2u);
  ASSERT_EQ(s.damage.first.size(), 2u);
  EXPECT_EQ(s.damage.first[0].record, 5u);
  EXPECT_EQ(s.damage.first[0].stamp_ns, 5 * kFramePeriodNs);
  EXPECT_EQ(s.damage.first[1].record, 12u);
  EXPECT_EQ(s.damage.first[1].stamp_ns, 12 * kFramePeriodNs);
  EXPECT_TRUE(stream(c, "depth").sound());
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_EQ(r.streams.at(0).dropped, 2u);
  EXPECT_EQ(stream(r.after, "cam").delivered, static_cast<uint64_t>(kTicks - 2));
}

TEST_F(SessionCheckTest, IndexCutShortIsRebuilt) {
  const std::string original_index = read_file(dir_ / "cam.idx");
  auto lines = index_lines(dir_ / "cam.idx");
  std::string cut = "# dreamsense mjpeg index v1\n";
  for (size_t i = 0; i + 4 < lines.size(); ++i) cut += lines[i] + "\n";
  write_file(dir_ / "cam.idx", cut);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  EXPECT_NEAR(static_cast<double>(stream(c, "cam").damage.damaged), 4.0, 1.0);
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_EQ(r.streams.at(0).recovered, 4u);
  EXPECT_EQ(r.streams.at(0).dropped, 0u);
  // The frames are regular, so the rebuilt index is the original one.
  EXPECT_EQ(read_file(fixed() / "cam.idx"), original_index);
  EXPECT_EQ(read_file(fixed() / "cam.mjpg"), read_file(dir_ / "cam.mjpg"));
}

// The frames after a short index are found by walking the data: PNG chunks (png16) and frame
// sizes (raw16) as well as JPEG markers.
TEST(SessionCheckDepth, ShortDepthIndexIsRebuilt) {
  for (const char* encoding : {"png16", "raw16"}) {
    TempDir tmp;
    const fs::path dir = tmp.path() / "s";
    write_session(dir, kTicks, make_manifest(encoding));
    const std::string original_index = read_file(dir / "depth.idx");
    std::string cut = original_index;
    for (int i = 0; i < 3; ++i) cut.resize(cut.rfind('\n', cut.size() - 2) + 1);
    write_file(dir / "depth.idx", cut);
    auto c = check_session(dir);
    ASSERT_TRUE(c);
    EXPECT_FALSE(c->sound()) << encoding;
    auto r = repair_session(dir, tmp.path() / "fixed");
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_TRUE(r->complete) << encoding << "\n" << r->after.table();
    EXPECT_EQ(r->streams.at(1).recovered, 3u) << encoding;
    EXPECT_EQ(read_file(tmp.path() / "fixed" / "depth.idx"), original_index) << encoding;
  }
}

// Frames after a short index that do not decode are found by the second check of the copy and
// dropped: the copy is sound.
TEST_F(SessionCheckTest, RecoveredFrameThatDoesNotDecodeIsDropped) {
  corrupt_frame(kTicks - 2);
  auto lines = index_lines(dir_ / "cam.idx");
  std::string cut = "# dreamsense mjpeg index v1\n";
  for (size_t i = 0; i + 4 < lines.size(); ++i) cut += lines[i] + "\n";
  write_file(dir_ / "cam.idx", cut);
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_TRUE(r.after.sound()) << r.after.table();
  EXPECT_EQ(r.streams.at(0).recovered, 3u);
  EXPECT_EQ(r.streams.at(0).dropped, 1u);
  EXPECT_EQ(stream(r.after, "cam").delivered, static_cast<uint64_t>(kTicks - 1));
}

TEST_F(SessionCheckTest, IndexPointingPastTheData) {
  const auto last = fields(index_lines(dir_ / "cam.idx").back());
  fs::resize_file(dir_ / "cam.mjpg", last[2] + last[3] / 2);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  EXPECT_EQ(stream(c, "cam").damage.torn_tail, 1u);
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_EQ(r.streams.at(0).recovered, 0u) << "half a frame is not a frame";
  EXPECT_EQ(stream(r.after, "cam").delivered, static_cast<uint64_t>(kTicks - 1));
}

TEST_F(SessionCheckTest, NonMonotonicStamps) {
  auto lines = index_lines(dir_ / "depth.idx");
  const auto f = fields(lines[9]);
  lines[9] = fmt::format("{},{},{},{}", f[0], 3 * kFramePeriodNs, f[2], f[3]);
  std::string text = "# dreamsense raw16 index v1\n";
  for (const auto& l : lines) text += l + "\n";
  write_file(dir_ / "depth.idx", text);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  const StreamCheck& s = stream(c, "depth");
  EXPECT_EQ(s.damage.damaged, 1u);
  ASSERT_EQ(s.damage.first.size(), 1u);
  EXPECT_NE(s.damage.first[0].what.find("not after previous"), std::string::npos);
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_EQ(stream(r.after, "depth").delivered, static_cast<uint64_t>(kTicks - 1));
}

TEST_F(SessionCheckTest, MissingCalibrationFile) {
  replace_in_file(dir_ / kManifestName, "frame: cam",
                  "frame: cam\n    calibration: calib/cam.yaml");
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  const StreamCheck& s = stream(c, "cam");
  ASSERT_TRUE(s.calibration_error.has_value());
  EXPECT_NE(s.calibration_error->find("calib/cam.yaml: missing"), std::string::npos);
  EXPECT_EQ(s.delivered, static_cast<uint64_t>(kTicks)) << "the data is checked all the same";
  // The repair cannot make the calibration up: the copy says it is not complete.
  const SessionRepair r = repair();
  EXPECT_FALSE(r.complete);
  EXPECT_TRUE(r.streams.at(0).calibration_removed);
  auto m = read_manifest(fixed());
  ASSERT_TRUE(m);
  EXPECT_FALSE(m->complete);
  EXPECT_TRUE(m->streams.at(0).calibration.empty());
}

TEST_F(SessionCheckTest, MissingDataFileIsAnErrorOfThatStream) {
  fs::remove(dir_ / "skel.jsonl");
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  ASSERT_TRUE(stream(c, "skel").error.has_value());
  EXPECT_NE(stream(c, "skel").error->find("skel.jsonl: missing"), std::string::npos);
  EXPECT_TRUE(stream(c, "cam").sound()) << "the other streams are checked";
}

TEST_F(SessionCheckTest, IncompleteSessionIsReported) {
  replace_in_file(dir_ / kManifestName, "complete: true", "complete: false");
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  ASSERT_EQ(c.session_problems.size(), 1u);
  // Nothing else is wrong: the repaired copy is complete.
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_TRUE(r.after.sound());
}

// What a recorder killed between two flushes leaves: complete: false, frames written after the
// index's last flush. The repair indexes them again and closes the copy.
TEST_F(SessionCheckTest, CrashedRecordingIsClosedByTheRepair) {
  replace_in_file(dir_ / kManifestName, "complete: true", "complete: false");
  const std::string original_index = read_file(dir_ / "cam.idx");
  auto lines = index_lines(dir_ / "cam.idx");
  std::string cut = "# dreamsense mjpeg index v1\n";
  for (size_t i = 0; i + 3 < lines.size(); ++i) cut += lines[i] + "\n";
  write_file(dir_ / "cam.idx", cut);
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  EXPECT_EQ(stream(c, "cam").damage.damaged, 0u) << "an index lagging after a crash is normal";
  const SessionRepair r = repair();
  EXPECT_TRUE(r.complete) << r.after.table();
  EXPECT_EQ(r.streams.at(0).recovered, 3u);
  EXPECT_EQ(r.streams.at(0).dropped, 0u);
  EXPECT_EQ(read_file(fixed() / "cam.idx"), original_index);
  auto m = read_manifest(fixed());
  ASSERT_TRUE(m);
  EXPECT_TRUE(m->complete);
}

TEST_F(SessionCheckTest, RepairRefusesANonEmptyFolderUnlessForced) {
  fs::create_directories(fixed());
  write_file(fixed() / "old.txt", "x");
  auto r = repair_session(dir_, fixed());
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("--force"), std::string::npos);
  EXPECT_TRUE(fs::exists(fixed() / "old.txt"));
  auto forced = repair_session(dir_, fixed(), {.force = true});
  ASSERT_TRUE(forced) << forced.error().message;
  EXPECT_FALSE(fs::exists(fixed() / "old.txt"));
  EXPECT_TRUE(fs::exists(fixed() / kManifestName));
}

TEST_F(SessionCheckTest, FailedRepairLeavesNothing) {
  // Another clock: the copy cannot be made.
  replace_in_file(dir_ / kManifestName, "start_ns: 0", "start_ns: 3600000000000");
  const SessionCheck c = check(dir_);
  EXPECT_FALSE(c.sound());
  auto r = repair_session(dir_, fixed());
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("clock"), std::string::npos) << r.error().message;
  EXPECT_FALSE(fs::exists(fixed()));
}

}  // namespace
}  // namespace dreamsense::sources
