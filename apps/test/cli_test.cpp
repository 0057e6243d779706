// Whole-pipeline tests through the `dreamsense` executable, as a user runs it.
// One short demo session is generated once per test binary and copied for the bad-input cases.

#include "dreamsense/publish/dds_publisher.hpp"
#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <sys/wait.h>
#include <vector>

#include "cli_support.hpp"
#include "demo_video.hpp"

namespace {
namespace fs = std::filesystem;
using dreamsense::cli_support::read_jsonl;
using dreamsense::cli_support::run;
using dreamsense::cli_support::RunResult;
using dreamsense::cli_support::slurp;
using nlohmann::json;

class Cli : public ::testing::Test {
 protected:
  static fs::path root() {
    static const fs::path r = fs::temp_directory_path() / ("ds_cli_" + std::to_string(::getpid()));
    return r;
  }
  // A 4-second demo (seed 3), analysed: the ctest fixture `cli_demo_fixture` makes it once for
  // all tests; a test binary run by hand makes its own.
  static const fs::path& demo() {
    static const fs::path d = dreamsense::cli_support::fixture_demo(root());
    return d;
  }
  // A copy of the demo made of hard links (cheap); `damaged` is a real copy, safe to modify.
  static fs::path copy_of_demo(const std::string& name, const std::string& damaged = "") {
    const fs::path dst = root() / name;
    fs::remove_all(dst);
    fs::copy(demo(), dst, fs::copy_options::recursive | fs::copy_options::create_hard_links);
    for (const char* f : {"session.yaml", "primitives.jsonl"}) {  // edited by some tests
      fs::remove(dst / f);
      fs::copy_file(demo() / f, dst / f);
    }
    if (!damaged.empty()) {
      fs::remove(dst / damaged);
      fs::copy_file(demo() / damaged, dst / damaged);
    }
    return dst;
  }
  void SetUp() override { demo(); }  // before any test writes into root()
  static void TearDownTestSuite() { fs::remove_all(root()); }
};

TEST_F(Cli, DemoLeavesSessionTruthAndAllOutputs) {
  for (const char* f : {"session.yaml", "truth.jsonl", "primitives.jsonl", "events.log",
                        "report.html", "dream.json", "summary.json"})
    EXPECT_TRUE(fs::exists(demo() / f)) << f;
  const auto records = read_jsonl(demo() / "primitives.jsonl");
  std::set<std::string> names;
  for (const auto& r : records) {
    names.insert(r["primitive"].get<std::string>());
    for (const char* k : {"stamp_ns", "status", "confidence", "value", "legacy", "source"}) {
      ASSERT_TRUE(r.contains(k)) << k;
    }
    if (r["status"] != "ok") {
      EXPECT_TRUE(r["value"].is_null()) << "no value without data";
    }
  }
  EXPECT_EQ(names.size(), 25u);
  EXPECT_EQ(records.size() % 25, 0u);
  EXPECT_GE(records.size() / 25, 99u) << "4 s at 25 Hz";
  // The skeleton is in the demo, so the body primitives answer.
  int body_ok = 0;
  for (const auto& r : records)
    if (r["primitive"] == "getBodyPose" && r["status"] == "ok") {
      ++body_ok;
      EXPECT_EQ(r["legacy"].size(), 30u);
    }
  EXPECT_GE(body_ok, 95);
  EXPECT_NE(slurp(demo() / "events.log").find("getBodyPose:o;"), std::string::npos);
}

TEST_F(Cli, DreamJsonValidatesAgainstSchema11) {
  const fs::path schema =
      fs::path(DREAMSENSE_SOURCE_DIR) / "../shared/data/dream_dataset_format/dream.1.1.json";
  if (!fs::exists(schema)) GTEST_SKIP() << "DREAM schema not found at " << schema;
  const std::string cmd = "/usr/bin/python3 " + std::string(DREAMSENSE_SOURCE_DIR) +
                          "/tools/validate_json_schema.py " + schema.string() + " " +
                          (demo() / "dream.json").string();
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const json d = json::parse(slurp(demo() / "dream.json"));
  EXPECT_EQ(d["skeleton"]["head"]["x"].size(), d["head_gaze"]["rx"].size());
  EXPECT_FALSE(d["skeleton"]["sholder_center"]["z"][10].is_null());
}

TEST_F(Cli, EvalSessionMeasuresTheBodyAgainstTruth) {
  const fs::path out = root() / "eval.json";
  RunResult r = run("eval session " + demo().string() + " --analysis " + demo().string() +
                    " --json " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(slurp(out));
  EXPECT_EQ(j["task"], "session");
  // Joint noise in the demo is 5 mm per axis: the median 3-D error must be of that order.
  ASSERT_TRUE(j["metrics"]["body_joint_median_error_m"].is_number());
  EXPECT_LT(j["metrics"]["body_joint_median_error_m"].get<double>(), 0.02);
  EXPECT_GT(j["metrics"]["body_joint_median_error_m"].get<double>(), 0.0);
  // Faces are detected in the three cameras (4 s: the first frames of each camera are searched
  // before a track exists, so recall is a little below the 20-s sessions').
  ASSERT_TRUE(j["metrics"]["face_recall"].is_number());
  EXPECT_GE(j["metrics"]["face_recall"].get<double>(), 0.95);
  EXPECT_LE(j["metrics"]["face_false_positive_rate"].get<double>(), 0.02);
  // The demo names its child, so the shipped calibration (data/subjects/demo_child, fitted on
  // seeds 101-104) is used: issue 4's targets hold on this seed too. A failure here after a
  // change to the demo face or the face pipeline means: re-run tools/train_demo_subject.sh.
  const json& m = j["metrics"];
  for (const char* k : {"head_pose_median_deg", "gaze_median_deg", "eye_center_median_px",
                        "eye_position_median_m", "camera_selection_accuracy", "mutual_gaze_f1"})
    ASSERT_TRUE(m[k].is_number()) << k;
  // getEyes' 3-D positions are the pupils (demo seed 5: 4.2 mm; the eyeball centres that were
  // reported before were 6.9 mm off).
  EXPECT_LE(m["eye_position_median_m"].get<double>(), 0.006);
  EXPECT_LE(m["head_pose_median_deg"].get<double>(), 3.0);
  EXPECT_LE(m["gaze_median_deg"].get<double>(), 5.0);
  EXPECT_LE(m["eye_center_median_px"].get<double>(), 1.5);
  EXPECT_GE(m["camera_selection_accuracy"].get<double>(), 0.95);
  EXPECT_GE(m["mutual_gaze_f1"].get<double>(), 0.90);
  // faces (issue 12): the portrait's smile is read as happy on the face ticks, and the child is
  // identified from its gallery (data/subjects/demo_child, enrolled on seed 101) when the npm
  // face-api weights are installed (else identifyFace is disabled and not evaluated).
  ASSERT_TRUE(m["expression_ok_rate"].is_number());
  EXPECT_GE(m["expression_ok_rate"].get<double>(), 0.9);
  EXPECT_GE(m["expression_accuracy"].get<double>(), 0.9);
  if (m["face_identity_ok_rate"].is_number()) {
    EXPECT_GE(m["face_identity_ok_rate"].get<double>(), 0.9);
    EXPECT_GE(m["face_identity_accuracy"].get<double>(), 0.95);
  } else {
    EXPECT_TRUE(j["not_evaluated"].contains("face_identity_accuracy"));
  }
  // The demo child makes DREAM gestures (issue 13): identifyTrajectory per tick, 0.3 s edge
  // tolerance, and no gesture reported in rests.
  ASSERT_TRUE(m["action_accuracy"].is_number());
  EXPECT_GE(m["action_accuracy"].get<double>(), 0.95);
  EXPECT_LE(m["action_rest_false_positive_rate"].get<double>(), 0.05);
  EXPECT_TRUE(m["action_confusion"].is_object());
}

TEST_F(Cli, SameSeedGivesIdenticalTruthAndAnalysis) {
  const fs::path again = root() / "again";
  RunResult r = run("demo --out " + again.string() + " --seed 3 --duration 4");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(slurp(again / "truth.jsonl"), slurp(demo() / "truth.jsonl"));
  EXPECT_EQ(slurp(again / "primitives.jsonl"), slurp(demo() / "primitives.jsonl"));
  EXPECT_EQ(slurp(again / "camera_left.mjpg"), slurp(demo() / "camera_left.mjpg"));
  fs::remove_all(again);
}

TEST_F(Cli, TruncatedCameraVideoIsAOneLineErrorNamingTheFile) {
  const fs::path s = copy_of_demo("truncated", "camera_left.mjpg");
  const fs::path video = s / "camera_left.mjpg";
  ASSERT_TRUE(fs::exists(video));
  fs::resize_file(video, fs::file_size(video) / 2);
  const fs::path out = root() / "truncated_out";
  RunResult r = run("analyze " + s.string() + " --out " + out.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("camera_left.mjpg"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(out / "primitives.jsonl")) << "no half-written output";
}

// A torn skeleton tail, a torn audio tail and one corrupted camera frame cost those records:
// the analysis succeeds, summary.json counts exactly that damage, and the report says so.
TEST_F(Cli, DamagedRecordsCostOnlyThemselves) {
  const fs::path s = copy_of_demo("damaged", "camera_left.mjpg");
  for (const char* f : {"front.skeleton.jsonl", "mic_array.wav"}) {
    fs::remove(s / f);
    fs::copy_file(demo() / f, s / f);
  }
  std::string skel = slurp(s / "front.skeleton.jsonl");
  skel.resize(skel.size() - 40);  // the last line cut, as a crash leaves it
  std::ofstream(s / "front.skeleton.jsonl", std::ios::binary) << skel;
  fs::resize_file(s / "mic_array.wav", fs::file_size(s / "mic_array.wav") - 3000);
  {  // 200 random bytes in the middle of camera_left's frame 40
    std::ifstream idx(s / "camera_left.idx");
    std::string line;
    int k = -1;
    unsigned long long seq = 0, stamp = 0, offset = 0, size = 0;
    while (std::getline(idx, line) && k < 40) {
      if (!line.empty() && line[0] != '#' && ++k == 40) {
        ASSERT_EQ(std::sscanf(line.c_str(), "%llu,%llu,%llu,%llu", &seq, &stamp, &offset, &size),
                  4);
      }
    }
    std::fstream f(s / "camera_left.mjpg", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(offset + size / 2));
    std::string noise(200, '\0');
    for (size_t i = 0; i < noise.size(); ++i) noise[i] = static_cast<char>((i * 7919) % 251);
    f.write(noise.data(), static_cast<std::streamsize>(noise.size()));
  }
  for (const char* f : {"primitives.jsonl", "summary.json", "report.html"}) fs::remove(s / f);
  // What the recorder's capture counted (capture.json) travels with the analysis.
  std::ofstream(s / "capture.json")
      << R"j({"duration_s": 4.0, "streams": {"camera_left": {"frames_captured": 60,)j"
      << R"j( "frames_dropped": 2, "overruns": 0, "lost": "unplugged (2.4 s)"}}})j";
  const fs::path out = root() / "damaged_out";
  RunResult r = run("analyze " + s.string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(slurp(out / "summary.json"))
                .at("recording_capture")
                .at("streams")
                .at("camera_left")
                .at("lost"),
            "unplugged (2.4 s)");
  EXPECT_EQ(r.err.find("Corrupt JPEG"), std::string::npos) << "libjpeg's messages are counted";
  const json summary = json::parse(slurp(out / "summary.json"));
  std::map<std::string, json> by_stream;
  for (const auto& d : summary.at("damage")) by_stream[d.at("stream")] = d;
  EXPECT_EQ(by_stream.at("front.skeleton").at("torn_tail"), 1);
  EXPECT_EQ(by_stream.at("mic_array").at("torn_tail"), 1);
  EXPECT_EQ(by_stream.at("camera_left").at("damaged"), 1);
  EXPECT_EQ(by_stream.at("camera_left").at("first_damaged").at(0).at("record"), 40);
  for (const auto& [id, d] : by_stream) {
    if (id != "front.skeleton" && id != "mic_array" && id != "camera_left") {
      EXPECT_EQ(d.at("damaged").get<int>() + d.at("torn_tail").get<int>(), 0) << id;
    }
  }
  EXPECT_NE(slurp(out / "report.html").find("Damaged recording: camera_left.mjpg"),
            std::string::npos);
  // The undamaged tick count is kept: a damaged record does not end the session.
  EXPECT_EQ(summary.at("ticks"), json::parse(slurp(demo() / "summary.json")).at("ticks"));
}

// An output folder that holds an analysis is replaced only with --force, then completely.
TEST_F(Cli, AnExistingAnalysisIsReplacedOnlyWithForce) {
  const fs::path out = root() / "force_out";
  fs::remove_all(out);
  ASSERT_EQ(run("analyze " + demo().string() + " --out " + out.string()).exit_code, 0);
  std::ofstream(out / "overlay.mp4") << "an old overlay";
  RunResult again = run("analyze " + demo().string() + " --out " + out.string());
  EXPECT_NE(again.exit_code, 0);
  EXPECT_NE(again.err.find("--force"), std::string::npos) << again.err;
  EXPECT_TRUE(fs::exists(out / "overlay.mp4"));
  ASSERT_EQ(run("analyze " + demo().string() + " --out " + out.string() + " --force").exit_code, 0);
  EXPECT_FALSE(fs::exists(out / "overlay.mp4")) << "old and new outputs never mix";
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().find("partial"), std::string::npos) << e.path();
  // A run that fails after planning (unknown analyser option) leaves no folder behind.
  const fs::path fresh = root() / "never_made";
  RunResult bad = run("analyze " + demo().string() + " --out " + fresh.string() +
                      " --set gaze.no_such_option=1");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_FALSE(fs::exists(fresh));
}

TEST_F(Cli, MissingStreamFileIsNamed) {
  const fs::path s = copy_of_demo("missing");
  fs::remove(s / "mic_array.wav");
  RunResult r = run("analyze " + s.string() + " --out " + (root() / "missing_out").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("mic_array.wav"), std::string::npos) << r.err;
}

TEST_F(Cli, UnknownFormatVersionIsRejected) {
  const fs::path s = copy_of_demo("version");
  std::string yaml = slurp(s / "session.yaml");
  const auto pos = yaml.find("format_version: 1");
  ASSERT_NE(pos, std::string::npos);
  yaml.replace(pos, 17, "format_version: 99");
  std::ofstream(s / "session.yaml") << yaml;
  RunResult r = run("analyze " + s.string() + " --out " + (root() / "version_out").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("format_version"), std::string::npos) << r.err;
}

TEST_F(Cli, UnwritableOutputFolderIsRejected) {
  std::ofstream(root() / "a_file") << "x";
  RunResult r =
      run("analyze " + demo().string() + " --out " + (root() / "a_file" / "out").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("a_file/out"), std::string::npos) << r.err;
}

// record with a video file standing in for the camera, then analyze the recording; and a
// configuration typo is a one-line error before anything is recorded.
TEST_F(Cli, RecordWritesASessionThatAnalyzeReads) {
  const fs::path dir = root() / "record";
  fs::create_directories(dir);
  const fs::path video = dir / "cam.avi";
  {
    cv::VideoWriter w(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                      cv::Size(160, 120));
    ASSERT_TRUE(w.isOpened());
    for (int k = 0; k < 40; ++k) w.write(cv::Mat(120, 160, CV_8UC3, cv::Scalar(k, 80, 160)));
  }
  std::ofstream(dir / "rec.yaml") << "session: {name: dry, metadata: {subject: none}}\n"
                                     "cameras:\n  - {id: camera_middle, device: cam.avi}\n";
  RunResult r = run("record --config " + (dir / "rec.yaml").string() + " --out " +
                    (dir / "s").string() + " --duration 0.5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto m = dreamsense::sources::read_manifest(dir / "s");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_TRUE(m->complete);
  EXPECT_EQ(m->metadata.at("generator"), "dreamsense record");
  r = run("analyze " + (dir / "s").string() + " --out " + (dir / "a").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(read_jsonl(dir / "a" / "primitives.jsonl").empty());

  std::ofstream(dir / "typo.yaml") << "cameras:\n  - {id: camera_middle, devise: cam.avi}\n";
  r = run("record --config " + (dir / "typo.yaml").string() + " --out " + (dir / "t").string() +
          " --duration 0.5");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cameras[0].devise: unknown key"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "t" / "session.yaml"));
}

// live: the demo's middle camera played from a video file as if it were a device, with its
// calibration; the face analysers run as frames arrive and the session is recorded on the way.
TEST_F(Cli, LiveAnalysesACameraAsItDeliversAndRecordsIt) {
  const fs::path dir = root() / "live";
  fs::create_directories(dir);
  // Played three times (12 s): the models may take seconds to load on a loaded machine while
  // the "device" already plays; --duration 3 counts from when they are ready and ends the run.
  dreamsense::cli_support::write_video(demo(), "camera_middle", 3, dir / "middle.avi");
  if (HasFatalFailure()) return;
  std::ofstream(dir / "live.yaml")
      << "session: {name: live-test, metadata: {subject: demo_child}}\n"
         "cameras:\n  - {id: camera_middle, device: middle.avi, "
         "calibration: "
      << (demo() / "calib" / "camera_middle.yaml").string() << "}\n";
  // A ROS 2-style subscriber on getFaces hears the live run (DDS, this machine only).
  dreamsense::publish::DdsPublisherOptions dds;
  dds.domain_id = 100 + static_cast<int>(::getpid() % 100);
  auto faces_topic = dreamsense::publish::DdsStringSubscriber::create(dds, "getFaces");
  const bool have_dds = static_cast<bool>(faces_topic);
  RunResult r =
      run("live --config " + (dir / "live.yaml").string() + " --out " + (dir / "out").string() +
          " --record " + (dir / "rec").string() + " --duration 3 --ui 0" +
          (have_dds ? " --publish dds --dds-json --dds-domain " + std::to_string(dds.domain_id)
                    : std::string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("operator page: http://127.0.0.1:"), std::string::npos) << r.err;
  int faces_ok = 0, head_ok = 0, ticks = 0;
  for (const auto& rec : read_jsonl(dir / "out" / "primitives.jsonl")) {
    if (rec["primitive"] == "getFaces") {
      ++ticks;
      faces_ok += rec["status"] == "ok";
    }
    head_ok += rec["primitive"] == "getHead" && rec["status"] == "ok";
  }
  if (have_dds) {
    const auto heard = (*faces_topic)->wait_for(static_cast<size_t>(std::max(faces_ok, 1)), 2000);
    // Every ok record is published (only ok ones by default); how many there are depends on how
    // many frames the machine analysed live (asserted below).
    const auto expected = std::min<size_t>(5, static_cast<size_t>(faces_ok));
    ASSERT_GE(heard.size(), std::max<size_t>(1, expected))
        << faces_ok << " getFaces ok records in primitives.jsonl";
    const auto first = json::parse(heard.front());
    EXPECT_EQ(first["primitive"], "getFaces");
    EXPECT_EQ(first["status"], "ok");
  }
  EXPECT_GE(ticks, 15);     // 3 s at 25 Hz, minus what a loaded machine drops (21 seen at load 11)
  EXPECT_GE(faces_ok, 10);  // the child faces the middle camera most of the time
  EXPECT_GE(head_ok, 5);
  auto m = dreamsense::sources::read_manifest(dir / "rec");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_TRUE(m->complete);
  EXPECT_EQ(m->find("camera_middle")->calibration, "calib/camera_middle.yaml");
  EXPECT_EQ(m->metadata.at("subject"), "demo_child");
}

TEST_F(Cli, BenchPipelineReportsTheContractKeys) {
  const fs::path out = root() / "bench.json";
  RunResult r = run("bench pipeline " + demo().string() + " --no-live --json " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(slurp(out));
  EXPECT_EQ(j["task"], "pipeline");
  for (const char* k : {"fps", "realtime_factor", "latency_p95_ms", "dropped_frames"})
    EXPECT_TRUE(j["metrics"].contains(k)) << k;
  // Speed is reported, not asserted (benchmarks measure it); the run itself must be complete.
  EXPECT_GT(j["metrics"]["fps"].get<double>(), 0.0);
  EXPECT_EQ(j["metrics"]["ticks"], 100);
  EXPECT_FALSE(j["stages"].empty());
  for (const json& stage : j["stages"]) {
    // Every call takes time, so the total is at least the calls times the fastest of them.
    EXPECT_GE(stage["latency_ms_total"].get<double>(),
              0.5 * stage["calls"].get<double>() * stage["latency_ms_median"].get<double>())
        << stage["name"];
    EXPECT_GE(stage["latency_ms_total"].get<double>(), stage["latency_ms_p95"].get<double>())
        << stage["name"];
  }
  // The configuration measured can be changed (A/B of an option in one build).
  const fs::path off = root() / "bench_off.json";
  r = run("bench pipeline " + demo().string() +
          " --no-live --disable face_detection --set gaze.mutual.radius_m=0.3 --json " +
          off.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const json& stage : json::parse(slurp(off))["stages"])
    EXPECT_NE(stage["name"], "face_detection");
  // Parallel ticks: the threads used are reported.
  const fs::path three = root() / "bench_threads.json";
  r = run("bench pipeline " + demo().string() + " --no-live --threads 3 --json " + three.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(slurp(three))["timing"]["threads"], 3);
  r = run("bench pipeline " + demo().string() + " --no-live --set face_detection.no_such=1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("no_such"), std::string::npos) << r.err;
}

// Numbers within `tol`, everything else equal.
void expect_json_near(const json& a, const json& b, double tol, const std::string& where) {
  if (a.is_number() && b.is_number()) {
    EXPECT_NEAR(a.get<double>(), b.get<double>(), tol) << where;
    return;
  }
  ASSERT_EQ(a.type(), b.type()) << where;
  if (a.is_object()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (const auto& [k, v] : a.items()) {
      ASSERT_TRUE(b.contains(k)) << where << "/" << k;
      expect_json_near(v, b[k], tol, where + "/" + k);
    }
  } else if (a.is_array()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (size_t i = 0; i < a.size(); ++i)
      expect_json_near(a[i], b[i], tol, where + "/" + std::to_string(i));
  } else {
    EXPECT_EQ(a, b) << where;
  }
}

// Golden output of the whole pipeline on demo seed 3 (4 s): every record that is not
// `disabled`. Regenerate deliberately with DREAMSENSE_UPDATE_GOLDEN=1 after an intended change.
TEST_F(Cli, EnabledPrimitivesMatchGoldenOutput) {
  const fs::path golden =
      fs::path(DREAMSENSE_SOURCE_DIR) / "data/fixtures/golden/demo-seed3-4s.enabled.jsonl";
  std::vector<json> actual;
  for (auto& r : read_jsonl(demo() / "primitives.jsonl"))
    if (r["status"] != "disabled") actual.push_back(r);
  ASSERT_FALSE(actual.empty());
  if (std::getenv("DREAMSENSE_UPDATE_GOLDEN") != nullptr) {
    fs::create_directories(golden.parent_path());
    std::ofstream out(golden);
    for (const auto& r : actual) out << r.dump() << "\n";
    GTEST_SKIP() << "golden output rewritten: " << golden;
  }
  ASSERT_TRUE(fs::exists(golden)) << golden << " (run with DREAMSENSE_UPDATE_GOLDEN=1)";
  const auto expected = read_jsonl(golden);
  ASSERT_EQ(actual.size(), expected.size());
  for (size_t i = 0; i < actual.size(); ++i)
    expect_json_near(actual[i], expected[i], 1e-6, "record " + std::to_string(i));
}

TEST_F(Cli, EvalCalibrationRecoversTheDemoCamerasFromNoisyCorrespondences) {
  const fs::path out = root() / "calib.json";
  RunResult r =
      run("eval calibration --dataset demo " + demo().string() + " --json " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(slurp(out));
  EXPECT_EQ(j["task"], "calibration");
  EXPECT_LE(j["metrics"]["rot_err_deg_max"].get<double>(), 0.5);
  EXPECT_LE(j["metrics"]["trans_err_m_max"].get<double>(), 0.02);
}

TEST_F(Cli, CalibrateExtrinsicsRejectsDegeneratePointsAndWritesNothing) {
  const fs::path csv = root() / "collinear.csv";
  {
    std::ofstream f(csv);
    f << "u,v,x,y,z\n";
    for (int i = 0; i < 8; ++i)
      f << 100 + 10 * i << "," << 100 + 10 * i << "," << 0.1 * i << ",0,1\n";
  }
  const fs::path out = root() / "ext.yaml";
  RunResult r =
      run("calibrate extrinsics --intrinsics " + (demo() / "calib/camera_left.yaml").string() +
          " --points " + csv.string() + " --out " + out.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("collinear"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// Speaker models from the demo's enrolment audio (enroll/<speaker>/*.wav): train, eval, and the
// one-line errors for a missing or corrupt model.
TEST_F(Cli, TrainAndEvalVoicesOnTheDemoEnrolment) {
  const fs::path enroll = demo() / "enroll", model = root() / "voices.yaml";
  ASSERT_TRUE(fs::exists(enroll / "child")) << "the demo writes enrolment audio";
  RunResult t =
      run("train voices --dataset folders " + enroll.string() + " --out " + model.string());
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_NE(slurp(model).find("dreamsense.voice_model"), std::string::npos);
  const fs::path out = root() / "voices.json";
  RunResult e = run("eval voices --dataset folders " + enroll.string() + " --enroll 1 --json " +
                    out.string());
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const json j = json::parse(slurp(out));
  EXPECT_EQ(j["task"], "voices");
  EXPECT_EQ(j["dataset"]["name"], "folders");
  EXPECT_GE(j["metrics"]["accuracy"].get<double>(), 0.0);
  EXPECT_TRUE(j["per_class"].contains("therapist"));

  RunResult missing = run("eval voices --dataset folders " + enroll.string() + " --model " +
                          (root() / "no_such_model.yaml").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("no_such_model.yaml"), std::string::npos) << missing.err;
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  const fs::path corrupt = root() / "corrupt_voices.yaml";
  std::ofstream(corrupt) << "%YAML:1.0\n---\nformat: [dreamsense.voice_model\n";
  RunResult bad = run("analyze " + demo().string() + " --out " + (root() / "voice_out").string() +
                      " --voice-model " + corrupt.string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("corrupt_voices.yaml"), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
}

// recognizeSpeech on demo audio (issue 16): seed 613's 60 s session holds an utterance whose
// abruptly cut pre-roll PocketSphinx decoded as an extra word ("eight ten of clubs") and a
// "five five" that the phone loop rejected at weight 1. The defaults (pre-roll faded in,
// rejection weight 0.5) get every command right and accept none of the therapist's sentences;
// the old settings fail on this session, so the seed exercises what the defaults fix.
TEST_F(Cli, DemoCommandsAreRecognisedWithoutAWordFromTheCut) {
  const fs::path session = root() / "speech613";
  RunResult d =
      run("demo --seed 613 --duration 60 --audio-only --no-analyze --out " + session.string());
  ASSERT_EQ(d.exit_code, 0) << d.err;
  auto speech = [&](const std::string& name, const std::string& options) {
    const fs::path out = session / name, report = root() / (name + ".json");
    RunResult a = run("analyze " + session.string() + " --out " + out.string() + options);
    EXPECT_EQ(a.exit_code, 0) << a.err;
    RunResult e = run("eval session " + session.string() + " --analysis " + out.string() +
                      " --json " + report.string());
    EXPECT_EQ(e.exit_code, 0) << e.err;
    return json::parse(slurp(report))["metrics"];
  };
  const json now = speech("defaults", "");
  ASSERT_TRUE(now["speech_accuracy"].is_number());
  EXPECT_EQ(now["speech_accuracy"].get<double>(), 1.0);
  EXPECT_EQ(now["speech_false_accept_rate"].get<double>(), 0.0);
  EXPECT_EQ(now["robot_speech_false_reports"].get<int>(), 0);
  const json before =
      speech("before", " --set speech.fade_in_s=0 --set speech.garbage_phone_weight=1");
  EXPECT_LT(before["speech_accuracy"].get<double>(), 1.0);
}

// The child's calibration: `train face` on the demo (truth head poses) writes a face model that
// `analyze --subject` uses; a subject folder without calibration files is a clear error; a
// session naming an unknown subject falls back to the generic model.
TEST_F(Cli, TrainFaceAndSubjectFolders) {
  const fs::path subject = root() / "subject";
  fs::create_directories(subject);
  RunResult r = run("train face --session " + demo().string() + " --out " +
                    (subject / "face_model.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string model = slurp(subject / "face_model.yaml");
  EXPECT_NE(model.find("dreamsense-face-model"), std::string::npos);
  EXPECT_NE(model.find("demo-seed-3"), std::string::npos) << "provenance names the session";

  const fs::path out = root() / "with-subject";
  r = run("-v analyze " + demo().string() + " --out " + out.string() + " --subject " +
          subject.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find((subject / "face_model.yaml").string()), std::string::npos) << r.err;
  int ok_heads = 0;
  for (const auto& rec : read_jsonl(out / "primitives.jsonl"))
    if (rec["primitive"] == "getHeadGaze" && rec["status"] == "ok") ++ok_heads;
  EXPECT_GT(ok_heads, 50);

  const fs::path empty = root() / "empty-subject";
  fs::create_directories(empty);
  r = run("analyze " + demo().string() + " --out " + (root() / "x").string() + " --subject " +
          empty.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("face_model.yaml"), std::string::npos) << r.err;

  const fs::path unknown = copy_of_demo("unknown-subject");
  std::string manifest = slurp(unknown / "session.yaml");
  const auto at = manifest.find("subject: demo_child");
  ASSERT_NE(at, std::string::npos) << "the demo names its subject";
  manifest.replace(at, std::string("subject: demo_child").size(), "subject: nobody_known");
  std::ofstream(unknown / "session.yaml") << manifest;
  const fs::path subjects = root() / "saved-subjects";
  fs::remove_all(subjects);
  fs::create_directories(subjects);
  // Without the dead zone even the 4-s demo's few looks at the robot give a correction to save.
  r = run("-v analyze " + unknown.string() + " --out " + (root() / "y").string() +
          " --save-subject --subjects-dir " + subjects.string() +
          " --set gaze.fixation_yaw.dead_zone_deg=0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("no calibration for subject 'nobody_known'"), std::string::npos) << r.err;
  // Issue 15: with no subject folder the analysis self-calibrates from the session (the demo's
  // three calibrated cameras), uses the result and reports it in summary.json.
  const json summary = json::parse(slurp(root() / "y" / "summary.json"));
  ASSERT_TRUE(summary.contains("self_calibration")) << summary.dump();
  const json& sc = summary["self_calibration"];
  EXPECT_EQ(sc["status"], "converged") << sc.dump();
  EXPECT_GE(sc["ticks_used"].get<int>(), 12);
  EXPECT_LT(sc["residual_rms_mm"].get<double>(), 3.0);
  // The demo gives the robot's head (robot_head_m): the level comes from the gaze's fixations
  // on it, or the head's, when enough ticks have them in these 4 s, else from the world-level
  // pitch; either way the summary says which.
  const std::string level = sc.value("level", "");
  EXPECT_TRUE(level == "gaze_fixations" || level == "target_fixations" || level == "world_pitch")
      << sc.dump();
  EXPECT_TRUE(sc.contains("fixation_ticks")) << sc.dump();
  ASSERT_TRUE(sc.contains("gaze_level")) << sc.dump();
  EXPECT_EQ(sc["gaze_level"]["applied"].get<bool>(), level == "gaze_fixations") << sc.dump();
  EXPECT_TRUE(fs::exists(root() / "y" / "self_calibration" / "face_model.yaml"));
  EXPECT_NE(r.err.find("self_calibration/face_model.yaml"), std::string::npos) << r.err;
  // ... and in the report, with its quality.
  const std::string report = slurp(root() / "y" / "report.html");
  EXPECT_NE(report.find("<b>Child calibration.</b> self-calibrated from the session"),
            std::string::npos);
  EXPECT_NE(report.find("residual"), std::string::npos);
  // The anatomical eyeballs learn their sideways bias from fixations on the robot (gaze.yaml
  // turns it on); summary.json reports the value applied at the last gaze.
  EXPECT_NE(slurp(root() / "y" / "self_calibration" / "gaze.yaml").find("fixation_yaw: 1"),
            std::string::npos);
  ASSERT_TRUE(summary.contains("gaze_fixation_yaw_deg")) << summary.dump();
  EXPECT_TRUE(summary["gaze_fixation_yaw_deg"].is_number()) << summary.dump();
  // --save-subject: the child's folder for the next session, with the learnt correction in its
  // gaze.yaml (none learnt: no key) so that the next session applies it from its first tick.
  const fs::path saved = subjects / "nobody_known";
  EXPECT_EQ(sc.value("saved_to", ""), saved.string()) << sc.dump();
  EXPECT_TRUE(fs::exists(saved / "face_model.yaml"));
  const double learnt = summary["gaze_fixation_yaw_deg"].get<double>();
  EXPECT_NE(learnt, 0) << "no correction learnt: the save of one is not exercised";
  const std::string saved_gaze = slurp(saved / "gaze.yaml");
  EXPECT_EQ(saved_gaze.find("fixation_yaw_start_deg") != std::string::npos, learnt != 0)
      << saved_gaze;
  EXPECT_EQ(sc.contains("saved_fixation_yaw_deg"), learnt != 0) << sc.dump();
  if (learnt != 0) {
    EXPECT_EQ(sc["saved_fixation_yaw_deg"].get<double>(), learnt);
  }
  // The report says so where the gaze was corrected.
  EXPECT_EQ(report.find("gaze: a sideways correction of") != std::string::npos, learnt != 0);
  // The next session with that folder starts from the saved correction (here one written in).
  {
    std::string text = saved_gaze;
    if (const size_t at = text.find("fixation_yaw_start_deg:"); at != std::string::npos)
      text.erase(at, text.find('\n', at) + 1 - at);
    std::ofstream(saved / "gaze.yaml") << text << "fixation_yaw_start_deg: -4.5\n";
    const fs::path plan = root() / "returning-child-plan.txt";
    r = run("analyze " + unknown.string() + " --subject " + saved.string() +
            " --print-pipeline > " + plan.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string printed = slurp(plan);
    EXPECT_NE(printed.find("fixation_yaw.start_deg=-4.5"), std::string::npos) << printed;
    EXPECT_NE(printed.find("starting from -4.5 deg (an earlier session's)"), std::string::npos)
        << printed;
  }
  // The head-fixation level and the full size range at every tick (the baselines) on request;
  // an unknown self-calibration option is an error naming it.
  r = run("analyze " + unknown.string() +
          " --set self_calibration.gaze_level=false --set "
          "self_calibration.size_guided_search=false --out " +
          (root() / "y2").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json base = json::parse(slurp(root() / "y2" / "summary.json"))["self_calibration"];
  EXPECT_FALSE(base["gaze_level"]["applied"].get<bool>()) << base.dump();
  EXPECT_NE(base.value("level", ""), "gaze_fixations") << base.dump();
  // The guided face search (half the CPU) converges too.
  r = run("analyze " + unknown.string() + " --set self_calibration.guided_search=true --out " +
          (root() / "y4").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(slurp(root() / "y4" / "summary.json"))["self_calibration"]["status"],
            "converged");
  r = run("analyze " + unknown.string() + " --set self_calibration.gaze_levl=false --out " +
          (root() / "y3").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("self_calibration.gaze_levl"), std::string::npos) << r.err;
  // `--subject none` keeps the generic model and does not self-calibrate (so --save-subject
  // says that it saved nothing).
  r = run("analyze " + unknown.string() + " --subject none --save-subject --out " +
              (root() / "z").string(),
          false);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("--save-subject: nothing saved"), std::string::npos) << r.err;
  const json generic = json::parse(slurp(root() / "z" / "summary.json"));
  EXPECT_FALSE(generic.contains("self_calibration"));
  // Built-in gaze constants: nothing is learnt.
  EXPECT_TRUE(generic["gaze_fixation_yaw_deg"].is_null() ||
              generic["gaze_fixation_yaw_deg"].get<double>() == 0)
      << generic.dump();
  EXPECT_NE(slurp(root() / "z" / "report.html")
                .find("<b>Child calibration.</b> generic face model and built-in gaze constants"),
            std::string::npos);
}

// `train speech --dataset list` adapts the en-us model to a talker (the five cards utterances of
// pocketsphinx-testdata, one speaker) and `analyze --speech-model` decodes with it; bad list
// lines and unknown words are one-line errors that leave no model folder behind.
TEST_F(Cli, TrainSpeechAdaptsToATalkerAndAnalyzeUsesTheModel) {
  const fs::path cards = "/usr/share/pocketsphinx/test/data/cards";
  if (!fs::exists(cards / "005.wav") || !fs::exists("/usr/lib/sphinxtrain/bw"))
    GTEST_SKIP() << "pocketsphinx-testdata or sphinxtrain missing";
  const fs::path list = root() / "cards.list", model = root() / "child_speech";
  std::ofstream(list) << "# the cards talker\n"
                      << (cards / "001.wav").string() << " ten of clubs\n"
                      << (cards / "002.wav").string() << " four queen of clubs\n"
                      << (cards / "003.wav").string() << " seven of clubs\n"
                      << (cards / "004.wav").string() << " five five\n"
                      << (cards / "005.wav").string()
                      << " eight of spades four of clubs seven of hearts\n";
  // A wrong transcript far longer than its audio cannot be aligned: left out and reported.
  std::string wrong;
  for (int i = 0; i < 40; ++i) wrong += " ten of clubs";
  std::ofstream(list, std::ios::app) << (cards / "004.wav").string() << wrong << "\n";
  RunResult r = run("train speech --dataset list " + list.string() + " --out " + model.string() +
                    " --min-utterances 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string provenance = slurp(model / "adaptation.yaml");
  EXPECT_NE(provenance.find("utterances: 6"), std::string::npos) << provenance;
  EXPECT_NE(provenance.find("trained_utterances: 5"), std::string::npos) << provenance;
  EXPECT_NE(provenance.find("not_aligned: [line7]"), std::string::npos) << provenance;
  EXPECT_NE(provenance.find("rate_hz: 16000"), std::string::npos) << provenance;
  EXPECT_TRUE(fs::exists(model / "means"));

  const fs::path out = root() / "with-speech-model";
  r = run("-v analyze " + demo().string() + " --out " + out.string() + " --speech-model " +
          model.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("speech: acoustic model " + model.string()), std::string::npos) << r.err;

  // The model measured on recordings with the grammar: the cards talker's first take is
  // recognised, another talker's command and other speech are rejected.
  const fs::path data = cards.parent_path(), eval_list = root() / "eval.list";
  std::ofstream(eval_list) << (cards / "001.wav").string() << " ten of clubs\n"
                           << (data / "goforward.raw").string() << " -\n"
                           << (data / "numbers.raw").string() << " -\n";
  const fs::path eval_json = root() / "eval_list.json";
  r = run("eval speech --dataset list " + eval_list.string() + " --grammar " +
          (cards / "cards.gram").string() + " --model " + model.string() + " --json " +
          eval_json.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json e = json::parse(slurp(eval_json));
  EXPECT_EQ(e["dataset"]["name"], "list");
  EXPECT_EQ(e["metrics"]["in_grammar_items"], 1);
  EXPECT_EQ(e["metrics"]["out_of_grammar_items"], 2);
  EXPECT_EQ(e["metrics"]["grammar_sentence_accuracy"], 1.0) << e.dump(1);
  EXPECT_EQ(e["metrics"]["false_accept_rate"], 0.0) << e.dump(1);
  EXPECT_NE(e["protocol"].get<std::string>().find(model.string()), std::string::npos);
  r = run("eval speech --dataset list " + eval_list.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--grammar"), std::string::npos) << r.err;

  const fs::path bad_list = root() / "bad.list";
  std::ofstream(bad_list) << (cards / "001.wav").string() << " ten of clubs\n"
                          << (cards / "002.wav").string() << "\n";
  r = run("train speech --dataset list " + bad_list.string() + " --out " +
          (root() / "m2").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("bad.list:2"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  std::ofstream(bad_list) << (cards / "001.wav").string() << " ten of clubz\n"
                          << (cards / "002.wav").string() << " four queen of clubs\n";
  r = run("train speech --dataset list " + bad_list.string() + " --out " +
          (root() / "m3").string() + " --min-utterances 2");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("clubz"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(root() / "m3"));
}

TEST_F(Cli, HelpAndUsageErrors) {
  EXPECT_EQ(run("analyze --help").exit_code, 0);
  EXPECT_NE(run("analyze").exit_code, 0) << "missing SESSION";
  EXPECT_NE(run("no-such-verb").exit_code, 0);
  // An unknown actions method is named, with the known ones, before any data is read.
  const RunResult bad =
      run("eval actions --dataset utkinect " + root().string() + " --methods pyramid,bogus");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("'bogus'"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("pyramid_lda"), std::string::npos) << bad.err;
  // --threads outside [0, 64] is refused by name before any data is read.
  for (const char* threads : {"-1", "65"}) {
    const RunResult r = run("analyze no-such-session --out x --threads " + std::string(threads));
    EXPECT_NE(r.exit_code, 0) << threads;
    EXPECT_NE(r.err.find("--threads"), std::string::npos) << r.err;
  }
}

}  // namespace
