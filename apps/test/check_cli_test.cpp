// `dreamsense check SESSION [--repair OUT]` through the executable, on damaged copies of the
// 4-second demo (seed 3) of the cli_demo fixture, and the outside check of issue 18: a copy with
// a torn skeleton tail, a torn audio tail and 1 % of one camera's frames corrupted analyses, counts
// exactly that damage and answers every other primitive as the undamaged analysis.

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "cli_support.hpp"

namespace {
namespace fs = std::filesystem;
using dreamsense::cli_support::read_jsonl;
using dreamsense::cli_support::run;
using dreamsense::cli_support::RunResult;
using dreamsense::cli_support::slurp;
using nlohmann::json;

void spit(const fs::path& p, const std::string& s) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << s;
}

struct IndexLine {
  unsigned long long sequence = 0, stamp = 0, offset = 0, size = 0;
};

std::vector<IndexLine> read_index(const fs::path& p) {
  std::vector<IndexLine> out;
  std::ifstream in(p);
  for (std::string l; std::getline(in, l);) {
    if (l.empty() || l[0] == '#') continue;
    IndexLine e;
    EXPECT_EQ(
        std::sscanf(l.c_str(), "%llu,%llu,%llu,%llu", &e.sequence, &e.stamp, &e.offset, &e.size),
        4);
    out.push_back(e);
  }
  return out;
}

void write_index(const fs::path& p, const std::vector<IndexLine>& lines) {
  std::string s = "# dreamsense mjpeg index v1\n";
  for (const auto& e : lines)
    s += std::to_string(e.sequence) + "," + std::to_string(e.stamp) + "," +
         std::to_string(e.offset) + "," + std::to_string(e.size) + "\n";
  spit(p, s);
}

// 200 bytes of noise in the middle of frame k of `data` (the JPEG markers stay).
void corrupt_frame(const fs::path& data, const IndexLine& e) {
  std::fstream f(data, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(e.offset + e.size / 2));
  std::string noise(200, '\0');
  for (size_t i = 0; i < noise.size(); ++i) noise[i] = static_cast<char>((i * 7919) % 251);
  f.write(noise.data(), static_cast<std::streamsize>(noise.size()));
}

// Records of primitives.jsonl keyed by (primitive, stamp).
std::map<std::pair<std::string, int64_t>, json> read_primitives(const fs::path& p) {
  std::map<std::pair<std::string, int64_t>, json> out;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    json r = json::parse(line);
    out[{r.at("primitive").get<std::string>(), r.at("stamp_ns").get<int64_t>()}] = r;
  }
  return out;
}

// The primitives of each group of streams (the `source` of their records in the demo).
constexpr int64_t kTickNs = 40'000'000;  // the pipeline's 25 Hz

const std::set<std::string> kBodyPrimitives = {"getArmAngle", "getBody",   "getBodyPose",
                                               "getHands",    "trackHand", "identifyTrajectory"};
const std::set<std::string> kAudioPrimitives = {"getSoundDirection", "identifyVoice",
                                                "recognizeSpeech"};
const std::set<std::string> kObjectPrimitives = {"getGripLocation",     "getObjects",
                                                 "getObjects (circle)", "getObjectTableDistance",
                                                 "identifyObject",      "trackObject"};

class CheckCli : public ::testing::Test {
 protected:
  static fs::path root() {
    static const fs::path r =
        fs::temp_directory_path() / ("ds_check_cli_" + std::to_string(::getpid()));
    return r;
  }
  static const fs::path& demo() {
    static const fs::path d = dreamsense::cli_support::fixture_demo(root());
    return d;
  }
  // A copy of the demo session: hard links, except real copies of the files in `damaged` and of
  // session.yaml; without the demo's analysis outputs.
  static fs::path copy_of_demo(const std::string& name, const std::vector<std::string>& damaged) {
    const fs::path dst = root() / name;
    fs::remove_all(dst);
    fs::copy(demo(), dst, fs::copy_options::recursive | fs::copy_options::create_hard_links);
    for (const char* f :
         {"primitives.jsonl", "summary.json", "report.html", "events.log", "dream.json"})
      fs::remove(dst / f);
    std::vector<std::string> real = damaged;
    real.push_back("session.yaml");
    for (const auto& f : real) {
      fs::remove(dst / f);
      fs::copy_file(demo() / f, dst / f);
    }
    return dst;
  }
  static json by_stream(const json& check) {
    json out = json::object();
    for (const auto& s : check.at("streams")) out[s.at("stream").get<std::string>()] = s;
    return out;
  }
  void SetUp() override { demo(); }
  static void TearDownTestSuite() { fs::remove_all(root()); }
};

TEST_F(CheckCli, UndamagedDemoIsSound) {
  const fs::path j = root() / "sound.json";
  RunResult r = run("check " + demo().string() + " --json " + j.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const json check = json::parse(slurp(j));
  EXPECT_EQ(check.at("sound"), true) << check.dump(1);
  auto manifest = dreamsense::sources::read_manifest(demo());
  ASSERT_TRUE(manifest) << manifest.error().message;
  EXPECT_EQ(check.at("streams").size(), manifest->streams.size());  // every stream checked
  EXPECT_GE(check.at("streams").size(), 8u);
  for (const auto& s : check.at("streams")) {
    EXPECT_EQ(s.at("damaged"), 0) << s.at("stream");
    EXPECT_EQ(s.at("torn_tail"), 0) << s.at("stream");
    EXPECT_EQ(s.at("gaps").at("count"), 0) << s.at("stream");
    EXPECT_GT(s.at("records").get<int>(), 0) << s.at("stream");
  }
}

// Every kind of record damage at once, each in its own stream: check finds each (stream and
// count) and exits 1; the repaired copy checks sound, analyses without --allow-damaged, and the
// primitives of the undamaged streams (the toys: top.color) are those of the original analysis.
TEST_F(CheckCli, FindsEachDamageAndTheRepairedCopyAnalyses) {
  const fs::path s =
      copy_of_demo("damaged", {"front.skeleton.jsonl", "mic_array.wav", "camera_left.mjpg",
                               "camera_middle.idx", "camera_right.idx", "camera_right.mjpg"});
  // Skeleton: a bad line in the middle (line 30) and a torn last line.
  std::string skel = slurp(s / "front.skeleton.jsonl");
  size_t pos = 0;
  for (int i = 0; i < 29; ++i) pos = skel.find('\n', pos) + 1;
  skel.insert(pos + 3, "#not json#");
  skel.resize(skel.size() - 40);
  spit(s / "front.skeleton.jsonl", skel);
  const std::string full_skel = slurp(demo() / "front.skeleton.jsonl");
  const int64_t bad_line_stamp =
      json::parse(full_skel.substr(pos, full_skel.find('\n', pos) - pos)).at("stamp_ns");
  // Audio: the WAV's last 3000 bytes gone (its header declares them).
  fs::resize_file(s / "mic_array.wav", fs::file_size(s / "mic_array.wav") - 3000);
  // camera_left: frames 20 and 60 corrupted.
  const auto left = read_index(s / "camera_left.idx");
  corrupt_frame(s / "camera_left.mjpg", left.at(20));
  corrupt_frame(s / "camera_left.mjpg", left.at(60));
  // camera_middle: the index cut short by 5 frames.
  auto middle = read_index(s / "camera_middle.idx");
  const size_t middle_frames = middle.size();
  middle.resize(middle.size() - 5);
  write_index(s / "camera_middle.idx", middle);
  // camera_right: a stamp that goes back (line 31) and an index pointing past the data.
  auto right = read_index(s / "camera_right.idx");
  right.at(30).stamp = right.at(10).stamp;
  write_index(s / "camera_right.idx", right);
  fs::resize_file(s / "camera_right.mjpg", right.back().offset + right.back().size / 2);

  const fs::path j = root() / "damaged.json";
  RunResult r = run("check " + s.string() + " --json " + j.string());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const json check = json::parse(slurp(j));
  EXPECT_EQ(check.at("sound"), false);
  const json st = by_stream(check);
  EXPECT_EQ(st.at("front.skeleton").at("damaged"), 1);
  EXPECT_EQ(st.at("front.skeleton").at("torn_tail"), 1);
  EXPECT_EQ(st.at("front.skeleton").at("damaged_records").at(0).at("record"), 30);  // the line
  EXPECT_EQ(st.at("mic_array").at("torn_tail"), 1);
  EXPECT_EQ(st.at("mic_array").at("damaged"), 0);
  EXPECT_EQ(st.at("camera_left").at("damaged"), 2);
  EXPECT_EQ(st.at("camera_left").at("damaged_records").at(0).at("record"), 20);
  EXPECT_EQ(st.at("camera_left").at("damaged_records").at(0).at("stamp_ns"), left.at(20).stamp);
  EXPECT_EQ(st.at("camera_left").at("damaged_records").at(1).at("record"), 60);
  EXPECT_NEAR(st.at("camera_middle").at("damaged").get<double>(), 5.0, 1.0);  // estimated
  EXPECT_EQ(st.at("camera_right").at("damaged"), 1);
  EXPECT_EQ(st.at("camera_right").at("torn_tail"), 1);
  for (const char* ok : {"front.color", "front.depth", "top.color"}) {
    EXPECT_EQ(st.at(ok).at("sound"), true) << ok;
    EXPECT_EQ(st.at(ok).at("damaged"), 0) << ok;
  }

  const fs::path fixed = root() / "repaired";
  fs::remove_all(fixed);
  const fs::path rj = root() / "repair.json";
  RunResult rep =
      run("check " + s.string() + " --repair " + fixed.string() + " --json " + rj.string());
  ASSERT_EQ(rep.exit_code, 0) << rep.err;
  const json repair = json::parse(slurp(rj)).at("repair");
  EXPECT_EQ(repair.at("complete"), true);
  std::map<std::string, json> rs;
  for (const auto& x : repair.at("streams")) rs[x.at("stream")] = x;
  EXPECT_EQ(rs.at("camera_middle").at("recovered"), 5) << "the index is rebuilt";
  EXPECT_EQ(rs.at("camera_middle").at("kept"), middle_frames - 5);
  EXPECT_EQ(rs.at("camera_left").at("dropped"), 2);
  EXPECT_EQ(rs.at("front.skeleton").at("dropped"), 1);
  EXPECT_EQ(rs.at("front.skeleton").at("torn_cut"), 1);
  EXPECT_EQ(slurp(fixed / "camera_middle.idx"), slurp(demo() / "camera_middle.idx"))
      << "regular frames: the rebuilt index is the original";
  EXPECT_EQ(slurp(fixed / "top.color.mjpg"), slurp(demo() / "top.color.mjpg"));
  EXPECT_TRUE(fs::exists(fixed / "calib" / "camera_left.yaml"));
  EXPECT_TRUE(fs::exists(fixed / "truth.jsonl"));

  RunResult again = run("check " + fixed.string());
  EXPECT_EQ(again.exit_code, 0) << again.err;

  const fs::path out = root() / "repaired_out";
  fs::remove_all(out);
  RunResult a = run("analyze " + fixed.string() + " --out " + out.string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const json summary = json::parse(slurp(out / "summary.json"));
  for (const auto& d : summary.at("damage"))
    EXPECT_EQ(d.at("damaged").get<int>() + d.at("torn_tail").get<int>(), 0) << d.dump();
  const auto original = read_primitives(demo() / "primitives.jsonl");
  const auto repaired = read_primitives(out / "primitives.jsonl");
  size_t compared = 0;
  for (const auto& [key, rec] : original) {
    const bool objects = kObjectPrimitives.count(key.first) != 0;
    // A tick may take a frame up to one tick period (40 ms) ahead of its stamp.
    const bool body_before_damage =
        kBodyPrimitives.count(key.first) != 0 && key.second + kTickNs < bad_line_stamp;
    if (!objects && !body_before_damage) continue;
    ASSERT_TRUE(repaired.count(key)) << key.first << " " << key.second;
    EXPECT_EQ(repaired.at(key), rec) << key.first << " at " << key.second;
    ++compared;
  }
  EXPECT_GT(compared, 600u);
}

TEST_F(CheckCli, MissingCalibrationIsReported) {
  const fs::path s = copy_of_demo("no_calib", {});
  fs::remove(s / "calib" / "front.color.yaml");  // a hard link: the demo keeps its own
  const fs::path j = root() / "no_calib.json";
  RunResult r = run("check " + s.string() + " --json " + j.string());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const json st = by_stream(json::parse(slurp(j)));
  EXPECT_NE(st.at("front.color")
                .at("calibration")
                .at("error")
                .get<std::string>()
                .find("calib/front.color.yaml: missing"),
            std::string::npos);
  EXPECT_EQ(st.at("front.color").at("damaged"), 0) << "the frames are checked all the same";
  for (const char* ok : {"camera_left", "front.depth", "mic_array"})
    EXPECT_EQ(st.at(ok).at("sound"), true) << ok;
  // Shown in the human table too (without -q).
  const std::string cmd = std::string(DREAMSENSE_EXE) + " check " + s.string() + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string text;
  char buf[4096];
  while (size_t n = std::fread(buf, 1, sizeof buf, p)) text.append(buf, n);
  EXPECT_EQ(WEXITSTATUS(::pclose(p)), 1);
  EXPECT_NE(text.find("calib/front.color.yaml: missing"), std::string::npos) << text;
  EXPECT_NE(text.find("session has damage or errors"), std::string::npos) << text;
}

TEST_F(CheckCli, RepairRefusesAFolderThatHoldsSomething) {
  const fs::path full = root() / "full";
  fs::create_directories(full);
  spit(full / "keep.txt", "mine");
  RunResult r = run("check " + demo().string() + " --repair " + full.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--force"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(slurp(full / "keep.txt"), "mine");
  RunResult usage = run("check " + demo().string() + " --force");
  EXPECT_NE(usage.exit_code, 0) << "--force needs --repair";
  EXPECT_NE(usage.exit_code, 1) << "a usage error, not a damaged session";
  RunResult missing = run("check " + (root() / "nowhere").string());
  EXPECT_EQ(missing.exit_code, 1);
}

// Issue 18, checked from outside: a torn skeleton tail, a torn audio tail and 1 % of one camera's
// frames corrupted. The analysis succeeds without --allow-damaged, summary.json counts exactly
// that damage, and every primitive answers exactly as in the undamaged analysis except where the
// damaged records fed it: the body at the torn last frame, the sound in the last 0.5 s, and the
// face primitives from the corrupted camera frame on (the face detector's tracking state of that
// camera restarts, so their values differ by up to ~2 cm for the rest of this 4-s demo; measured
// with seed 3), which must still answer with the undamaged analysis' status at every tick, but
// for rare borderline answers (confidence < 0.1) that flip between ok and no_data.
TEST_F(CheckCli, DamagedCopyAnalysesAndMatchesTheUndamagedAnalysis) {
  const fs::path s =
      copy_of_demo("outside", {"front.skeleton.jsonl", "mic_array.wav", "camera_left.mjpg"});
  std::string skel = slurp(s / "front.skeleton.jsonl");
  skel.resize(skel.size() - 40);
  spit(s / "front.skeleton.jsonl", skel);
  const size_t last_line = skel.rfind('\n') + 1;
  const std::string full_skel = slurp(demo() / "front.skeleton.jsonl");
  const int64_t torn_stamp =
      json::parse(full_skel.substr(last_line, full_skel.find('\n', last_line) - last_line))
          .at("stamp_ns");
  fs::resize_file(s / "mic_array.wav", fs::file_size(s / "mic_array.wav") - 3000);
  const auto left = read_index(s / "camera_left.idx");
  const size_t n_corrupt = std::max<size_t>(1, (left.size() + 99) / 100);  // 1 %
  std::vector<int64_t> corrupt_stamps;
  for (size_t i = 0; i < n_corrupt; ++i) {
    const size_t k = (i + 1) * left.size() / (n_corrupt + 1);
    corrupt_frame(s / "camera_left.mjpg", left.at(k));
    corrupt_stamps.push_back(static_cast<int64_t>(left.at(k).stamp));
  }

  const fs::path out = root() / "outside_out";
  fs::remove_all(out);
  RunResult r = run("analyze " + s.string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json summary = json::parse(slurp(out / "summary.json"));
  std::map<std::string, json> damage;
  for (const auto& d : summary.at("damage")) damage[d.at("stream")] = d;
  EXPECT_EQ(damage.at("front.skeleton").at("torn_tail"), 1);
  EXPECT_EQ(damage.at("mic_array").at("torn_tail"), 1);
  EXPECT_EQ(damage.at("camera_left").at("damaged"), n_corrupt);
  for (const auto& [id, d] : damage) {
    if (id == "front.skeleton" || id == "mic_array") {
      EXPECT_EQ(d.at("damaged"), 0) << id;
    } else if (id != "camera_left") {
      EXPECT_EQ(d.at("damaged").get<int>() + d.at("torn_tail").get<int>(), 0) << id;
    }
  }

  const auto original = read_primitives(demo() / "primitives.jsonl");
  const auto damaged = read_primitives(out / "primitives.jsonl");
  int64_t end = 0;
  for (const auto& [key, rec] : original) end = std::max(end, key.second);
  const int64_t first_corrupt = *std::min_element(corrupt_stamps.begin(), corrupt_stamps.end());
  size_t compared = 0, status_only = 0, skipped = 0, borderline_flips = 0;
  for (const auto& [key, rec] : original) {
    const std::string& name = key.first;
    const int64_t t = key.second;
    ASSERT_TRUE(damaged.count(key)) << name << " at " << t;
    const json& other = damaged.at(key);
    const bool face = kBodyPrimitives.count(name) == 0 && kAudioPrimitives.count(name) == 0 &&
                      kObjectPrimitives.count(name) == 0;
    if ((kBodyPrimitives.count(name) != 0 && t + kTickNs >= torn_stamp) ||
        (kAudioPrimitives.count(name) != 0 && t > end - 500'000'000)) {
      ++skipped;
      continue;
    }
    if (face && t >= first_corrupt) {
      // Same status, except a borderline answer: the landmark cascade is chaotic, so a tick
      // whose answer has a very low confidence (e.g. eyes at 0.06 on a strongly turned face) may
      // flip between ok and no_data when the camera's tracking restarts.
      const auto borderline = [](const json& x) {
        return x.at("status") == "ok" && x.at("confidence").is_number() &&
               x.at("confidence").get<double>() < 0.1;
      };
      if (other.at("status") != rec.at("status") && (borderline(other) || borderline(rec))) {
        ++borderline_flips;
      } else {
        EXPECT_EQ(other.at("status"), rec.at("status")) << name << " at " << t;
      }
      ++status_only;
      continue;
    }
    EXPECT_EQ(other, rec) << name << " at " << t << ":\n  damaged:   " << other.dump()
                          << "\n  undamaged: " << rec.dump();
    ++compared;
  }
  EXPECT_GT(compared, 2 * (status_only + skipped)) << "most records are compared exactly";
  EXPECT_LE(borderline_flips, status_only / 50) << "borderline flips are rare";
}

}  // namespace
