// Recording from live devices: the configuration file, and a recording whose "camera" is a
// video file (OpenCV plays it back at its frame rate, as a device would deliver it). Audio from a
// real ALSA card is only exercised where one exists (ALSA's "null" device is not paced).

#include "dreamsense/sources/recorder.hpp"

#include "dreamsense/sources/camera_source.hpp"
#include "dreamsense/sources/depth_sensor_source.hpp"
#include "dreamsense/sources/session_check.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <arpa/inet.h>
#include <atomic>
#include <chrono>
#include <fstream>
#include <map>
#include <netinet/in.h>
#include <set>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

#include "session_test_util.hpp"

namespace dreamsense::sources {
namespace {

namespace fs = std::filesystem;
using test_util::TempDir;

// A 25 fps MJPG AVI whose frame k shows k as a bright bar position (so order can be checked).
fs::path write_video(const fs::path& dir, int frames, cv::Size size = {160, 120}) {
  const fs::path file = dir / "camera.avi";
  cv::VideoWriter w(file.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, size);
  EXPECT_TRUE(w.isOpened());
  for (int k = 0; k < frames; ++k) {
    cv::Mat img(size, CV_8UC3, cv::Scalar(30, 30, 30));
    cv::rectangle(img, cv::Rect(k % size.width, 0, 4, size.height), cv::Scalar(255, 255, 255),
                  cv::FILLED);
    w.write(img);
  }
  return file;
}

void write_text(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

const char* kCalibration = R"(%YAML:1.0
---
)";

TEST(RecordConfig, ReadsRelativePathsAndSessionFields) {
  TempDir tmp;
  write_video(tmp.path(), 3);
  write_text(tmp.path() / "cam.yaml", kCalibration);
  write_text(tmp.path() / "speech.gram", "#JSGF V1.0;\ngrammar g;\npublic <a> = yes | no;\n");
  write_text(tmp.path() / "rec.yaml", R"(
session:
  name: s01
  participant: {id: 12, gender: female, age_months: 61}
  condition: RET
  task: TT
  metadata: {subject: child12}
  speech_grammar: speech.gram
cameras:
  - {id: camera_middle, device: camera.avi, width: 160, height: 120, fps: 25, calibration: cam.yaml}
audio: {id: mic_array, device: "hw:1,0", sample_rate: 16000, channels: 4}
)");
  auto c = read_record_config(tmp.path() / "rec.yaml");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->name, "s01");
  EXPECT_EQ(c->participant.id, 12);
  EXPECT_EQ(c->participant.gender.value_or(""), "female");
  EXPECT_DOUBLE_EQ(c->participant.age_months.value_or(0), 61);
  EXPECT_EQ(c->metadata.at("subject"), "child12");
  EXPECT_EQ(c->speech_grammar, tmp.path() / "speech.gram");
  ASSERT_EQ(c->cameras.size(), 1u);
  EXPECT_EQ(c->cameras[0].device, (tmp.path() / "camera.avi").string());
  EXPECT_EQ(c->cameras[0].calibration, tmp.path() / "cam.yaml");
  ASSERT_TRUE(c->audio);
  EXPECT_EQ(c->audio->device, "hw:1,0");
  EXPECT_EQ(c->audio->channels, 4);
}

// `yaml`, written to DIR/rec.yaml, is refused with a message holding `needle` and the file name.
void expect_config_error(const fs::path& dir, const std::string& yaml, const std::string& needle) {
  write_text(dir / "rec.yaml", yaml);
  auto c = read_record_config(dir / "rec.yaml");
  ASSERT_FALSE(c) << yaml;
  EXPECT_NE(c.error().message.find(needle), std::string::npos) << c.error().message;
  EXPECT_NE(c.error().message.find("rec.yaml"), std::string::npos) << c.error().message;
}

TEST(RecordConfig, BadConfigurationsNameTheProblem) {
  TempDir tmp;
  const auto expect_error = [&](const std::string& yaml, const std::string& needle) {
    expect_config_error(tmp.path(), yaml, needle);
  };
  expect_error("cameras:\n  - {id: a, device: 0, widht: 640}\n", "cameras[0].widht: unknown key");
  expect_error("camera:\n  - {id: a, device: 0}\n", "camera: unknown key");
  expect_error("session: {name: x}\n", "nothing to record");
  expect_error("cameras:\n  - {id: a, device: 0}\n  - {id: a, device: 1}\n", "used twice");
  expect_error("cameras:\n  - {id: a, device: 0, calibration: nope.yaml}\n", "not found");
  expect_error("cameras:\n  - {id: a, device: 0, width: wide}\n", "cameras[0].width: wrong type");
  expect_error("cameras: [\n", "rec.yaml:");
  auto missing = read_record_config(tmp.path() / "absent.yaml");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
}

// fuzz_configs finding: a path the system refuses (a 300-character name: ENAMETOOLONG) threw
// std::filesystem_error out of RecordConfig::check() and ended the program.
TEST(RecordConfig, PathTheSystemRefusesIsNotFoundNotACrash) {
  TempDir tmp;
  const std::string long_name(300, 'x');
  write_text(tmp.path() / "rec.yaml",
             "session:\n  voice_enroll: " + long_name + "\ncameras:\n  - {id: a, device: 0}\n");
  auto c = read_record_config(tmp.path() / "rec.yaml");
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().message.find("voice_enroll"), std::string::npos) << c.error().message;
  EXPECT_NE(c.error().message.find("is not a folder"), std::string::npos) << c.error().message;
}

// Fuzz finding 6: a list or map used as a key (`? [a, b]: 1`) made as<std::string>() throw
// YAML::BadConversion out of the reader, and the program ended.
TEST(RecordConfig, ListOrMapAsKeyIsAnErrorNotACrash) {
  TempDir tmp;
  for (const std::string yaml :
       {"? [a, b]\n: 1\ncameras:\n  - {id: a, device: 0}\n",
        "session:\n  metadata:\n    ? {room: 1}\n    : x\ncameras:\n  - {id: a, device: 0}\n",
        "cameras:\n  - ? [id]\n    : a\n"}) {
    write_text(tmp.path() / "rec.yaml", yaml);
    Result<RecordConfig> c = tl::unexpected(Error{ErrorCode::kInternal, "not read"});
    EXPECT_NO_THROW(c = read_record_config(tmp.path() / "rec.yaml")) << yaml;
    ASSERT_FALSE(c) << yaml;
    EXPECT_NE(c.error().message.find("a key must be a name"), std::string::npos)
        << c.error().message;
  }
}

TEST(CameraSource, VideoFilePlaysBackInOrderWithIncreasingStamps) {
  TempDir tmp;
  CameraSourceOptions o;
  o.sensor = "cam";
  o.device = write_video(tmp.path(), 10).string();
  o.clock_origin = std::chrono::steady_clock::now();
  auto cam = CameraSource::open(o);
  ASSERT_TRUE(cam) << cam.error().message;
  EXPECT_EQ((*cam)->size(), cv::Size(160, 120));
  EXPECT_NEAR((*cam)->fps(), 25, 0.5);
  int64_t last = -1;
  int n = 0;
  while (true) {
    auto f = (*cam)->next();
    if (!f) {
      EXPECT_TRUE(is_end_of_stream(f.error())) << f.error().message;
      break;
    }
    EXPECT_EQ((*f)->sequence, static_cast<uint64_t>(n));
    EXPECT_GT((*f)->stamp.ns(), last);
    last = (*f)->stamp.ns();
    const auto* img = std::get_if<ColorImage>(&(*f)->payload);
    ASSERT_NE(img, nullptr);
    // The bar of frame k is at column k (JPEG blurs it a little).
    cv::Mat grey;
    cv::cvtColor(img->image, grey, cv::COLOR_BGR2GRAY);
    cv::Point at;
    cv::minMaxLoc(grey.row(60), nullptr, nullptr, nullptr, &at);
    EXPECT_NEAR(at.x, n + 1.5, 2.5);
    ++n;
  }
  EXPECT_EQ(n, 10);
  // Played at 25 fps: ten frames span about 0.36 s, not the microseconds of decoding.
  EXPECT_GT(last, 300'000'000);
}

TEST(CameraSource, MissingDeviceIsAClearError) {
  CameraSourceOptions o;
  o.device = "/nonexistent/video.avi";
  auto cam = CameraSource::open(o);
  ASSERT_FALSE(cam);
  EXPECT_EQ(cam.error().code, ErrorCode::kNotFound);
  EXPECT_NE(cam.error().message.find("/nonexistent/video.avi"), std::string::npos);
  o.width = 640;  // height missing
  EXPECT_FALSE(o.check());
}

TEST(Recorder, RecordsAReadableCompleteSession) {
  TempDir tmp;
  write_text(tmp.path() / "cam.yaml", kCalibration);
  RecordConfig c;
  c.name = "dry-run";
  c.metadata["subject"] = "child01";
  RecordCameraConfig cam;
  cam.id = "camera_middle";
  cam.device = write_video(tmp.path(), 50).string();
  cam.calibration = tmp.path() / "cam.yaml";
  c.cameras.push_back(cam);
  RecordOptions o;
  o.duration_s = 0.6;
  const fs::path out = tmp.path() / "session";
  auto stats = record_session(c, out, o);
  ASSERT_TRUE(stats) << stats.error().message;
  EXPECT_GE(stats->duration_s, 0.6);
  const auto written = stats->streams.at("camera_middle").frames_written;
  EXPECT_GE(written, 8u);  // 25 fps for 0.6 s = 15 frames, allowing for a slow machine
  // Never faster than the device: 15 frames, + the frame the camera thread pushes after the stop
  // (it checks the flag after each grab), + one frame of the recorder's 20 ms stop polling.
  EXPECT_LE(written, 18u);

  auto reader = SessionReader::open(out);
  ASSERT_TRUE(reader) << reader.error().message;
  const auto& m = (*reader)->manifest();
  EXPECT_TRUE(m.complete);
  EXPECT_EQ(m.name, "dry-run");
  EXPECT_EQ(m.metadata.at("subject"), "child01");
  EXPECT_GT(m.clock_origin_unix_ns, 1'600'000'000'000'000'000LL);  // a wall-clock time
  ASSERT_NE(m.find("camera_middle"), nullptr);
  EXPECT_EQ(m.find("camera_middle")->calibration, "calib/camera_middle.yaml");
  EXPECT_TRUE(fs::exists(out / "calib/camera_middle.yaml"));
  uint64_t read = 0;
  int64_t last = -1;
  while (true) {
    auto f = (*reader)->next();
    if (!f) {
      EXPECT_TRUE(is_end_of_stream(f.error())) << f.error().message;
      break;
    }
    EXPECT_GT((*f)->stamp.ns(), last);
    EXPECT_LT((*f)->stamp.ns(), 1'000'000'000);  // stamps count from the start of the recording
    last = (*f)->stamp.ns();
    ++read;
  }
  EXPECT_EQ(read, written);

  // A second recording into the same folder must not overwrite it.
  auto again = record_session(c, out, o);
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("already holds a session"), std::string::npos);
}

TEST(Recorder, MissingCameraFailsBeforeWritingAnything) {
  TempDir tmp;
  RecordConfig c;
  RecordCameraConfig cam;
  cam.id = "camera_left";
  cam.device = (tmp.path() / "absent.avi").string();
  c.cameras.push_back(cam);
  RecordOptions o;
  o.duration_s = 0.2;
  auto stats = record_session(c, tmp.path() / "session", o);
  ASSERT_FALSE(stats);
  EXPECT_NE(stats.error().message.find("camera_left"), std::string::npos);
  EXPECT_FALSE(fs::exists(tmp.path() / "session" / kManifestName));
}

TEST(Recorder, StopFlagEndsTheRecording) {
  TempDir tmp;
  RecordConfig c;
  RecordCameraConfig cam;
  cam.id = "camera_middle";
  cam.device = write_video(tmp.path(), 250).string();
  c.cameras.push_back(cam);
  std::atomic<bool> stop{true};  // already set: the recording ends at once, cleanly
  RecordOptions o;
  o.stop = &stop;
  auto stats = record_session(c, tmp.path() / "session", o);
  ASSERT_TRUE(stats) << stats.error().message;
  EXPECT_LT(stats->duration_s, 1.0);
  auto m = read_manifest(tmp.path() / "session");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_TRUE(m->complete);
}

// A device that ends (a video file runs out) ends the stream, unless until_stopped: then the
// stream stays open, next() waiting, until stop() (live --duration, issue 21).
TEST(LiveCapture, EndsWithTheLastDeviceUnlessHeldUntilStopped) {
  TempDir tmp;
  RecordConfig c;
  RecordCameraConfig cam;
  cam.id = "camera_middle";
  cam.device = write_video(tmp.path(), 5).string();  // 0.2 s
  c.cameras.push_back(cam);
  auto drain = [](LiveCapture& capture) {
    int frames = 0;
    while (true) {
      auto f = capture.next();
      if (!f) return is_end_of_stream(f.error()) ? frames : -1;
      ++frames;
    }
  };
  {
    auto capture = LiveCapture::open(c);
    ASSERT_TRUE(capture) << capture.error().message;
    EXPECT_EQ(drain(**capture), 5) << "ends by itself";
    ASSERT_TRUE((*capture)->finish());
  }
  LiveCaptureOptions hold;
  hold.until_stopped = true;
  auto capture = LiveCapture::open(c, {}, {}, hold);
  ASSERT_TRUE(capture) << capture.error().message;
  std::atomic<bool> ended{false};
  int frames = 0;
  std::thread consumer([&] {
    frames = drain(**capture);
    ended = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(800));  // the video ended after 0.2 s
  EXPECT_FALSE(ended) << "the stream must wait for stop()";
  (*capture)->stop();
  consumer.join();
  EXPECT_TRUE(ended);
  EXPECT_EQ(frames, 5);
  ASSERT_TRUE((*capture)->finish());
}

// A body tracker's skeletons over UDP: parsed into frames stamped on arrival, a bad datagram
// skipped, and recorded into the session's skeleton stream (issue 21).
TEST(LiveCapture, SkeletonsFromAnExternalTrackerOverUdpAreAnalysedAndRecorded) {
  TempDir tmp;
  RecordConfig c;
  RecordSkeletonConfig sk;
  sk.id = "front.skeleton";
  sk.port = 0;  // any free port
  c.skeletons.push_back(sk);
  const fs::path rec = tmp.path() / "session";
  auto capture = LiveCapture::open(c, rec);
  ASSERT_TRUE(capture) << capture.error().message;
  const int port = (*capture)->skeleton_ports().at("front.skeleton");
  ASSERT_GT(port, 0);
  EXPECT_EQ((*capture)->manifest().find("front.skeleton")->kind, SensorKind::kSkeleton);

  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<uint16_t>(port));
  inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
  auto send = [&](const std::string& text) {
    ::sendto(fd, text.data(), text.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  };
  send(
      R"({"bodies": [{"id": 4, "joints": {"head": [0.1, -0.5, 1.6, 1.0], "hand_left": [0.3, 0, 1.4]}}]})");
  send(R"({"bodies": [{"joints": {"head": "not a number"}}]})");  // skipped, counted
  send(R"({"stamp_ns": 5, "bodies": []})");                       // the sender's stamp is ignored
  std::vector<FramePtr> frames;
  for (int i = 0; i < 2; ++i) {
    auto f = (*capture)->next();
    ASSERT_TRUE(f) << f.error().message;
    frames.push_back(*f);
  }
  ::close(fd);
  (*capture)->stop();
  EXPECT_FALSE((*capture)->next()) << "ends after stop()";
  ASSERT_TRUE((*capture)->finish());

  const auto* first = frames[0]->as<Skeleton>();
  ASSERT_NE(first, nullptr);
  ASSERT_EQ(first->bodies.size(), 1u);
  EXPECT_EQ(first->bodies[0].body_id, 4);
  EXPECT_DOUBLE_EQ(first->bodies[0].joint(JointId::kHead).position_m[1], -0.5);
  EXPECT_FLOAT_EQ(first->bodies[0].joint(JointId::kHandLeft).confidence, 1.f);
  EXPECT_TRUE(frames[1]->as<Skeleton>()->bodies.empty());
  EXPECT_GT(frames[1]->stamp.ns(), frames[0]->stamp.ns());
  EXPECT_GT(frames[1]->stamp.ns(), 5) << "arrival time on the capture clock";

  auto reader = SessionReader::open(rec);
  ASSERT_TRUE(reader) << reader.error().message;
  int read = 0;
  for (auto f = (*reader)->next(); f; f = (*reader)->next()) {
    EXPECT_EQ((*f)->sensor, "front.skeleton");
    ++read;
  }
  EXPECT_EQ(read, 2);
}

// A live RGB-D sensor behind the depth-sensor interface: the `fake` driver (no hardware here;
// freenect and openni2 are used the same way when a device is present).
TEST(LiveCapture, DepthSensorDeliversDepthAndColourAndIsRecorded) {
  TempDir tmp;
  RecordConfig c;
  RecordDepthSensorConfig d;
  d.id = "front";
  d.driver = "fake";
  d.fps = 30;
  c.depth_sensors.push_back(d);
  const fs::path rec = tmp.path() / "session";
  auto capture = LiveCapture::open(c, rec);
  ASSERT_TRUE(capture) << capture.error().message;
  const auto* depth_entry = (*capture)->manifest().find("front.depth");
  ASSERT_NE(depth_entry, nullptr);
  EXPECT_EQ(depth_entry->kind, SensorKind::kDepth);
  EXPECT_EQ(depth_entry->encoding, "raw16");
  ASSERT_NE((*capture)->manifest().find("front.color"), nullptr);
  int depth = 0, color = 0;
  int64_t last = -1;
  for (int i = 0; i < 12; ++i) {
    auto f = (*capture)->next();
    ASSERT_TRUE(f) << f.error().message;
    if (const auto* di = (*f)->as<DepthImage>()) {
      ++depth;
      EXPECT_EQ(di->depth_mm.type(), CV_16UC1);
      // The table plane and the ball: millimetres between 0.5 and 4 m where measured.
      double lo = 0, hi = 0;
      cv::minMaxLoc(di->depth_mm, &lo, &hi, nullptr, nullptr, di->depth_mm > 0);
      EXPECT_GT(lo, 500);
      EXPECT_LT(hi, 4001);
      EXPECT_GT((*f)->stamp.ns(), last);
      last = (*f)->stamp.ns();
    } else if ((*f)->as<ColorImage>() != nullptr) {
      ++color;
    }
  }
  EXPECT_EQ(depth, 6);
  EXPECT_EQ(color, 6);
  (*capture)->stop();
  while ((*capture)->next()) {
  }
  ASSERT_TRUE((*capture)->finish());
  auto reader = SessionReader::open(rec);
  ASSERT_TRUE(reader) << reader.error().message;
  int read_depth = 0;
  for (auto f = (*reader)->next(); f; f = (*reader)->next())
    read_depth += (*f)->as<DepthImage>() != nullptr;
  EXPECT_GE(read_depth, 6);

  RecordConfig bad;
  RecordDepthSensorConfig k;
  k.driver = "kinect2";
  bad.depth_sensors.push_back(k);
  auto st = bad.check();
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("driver must be freenect, openni2 or fake"), std::string::npos);
}

// A device that fails mid-session (the fake sensor unplugged at its 6th grab; the first, at
// open, gives the sizes) ends only its own streams: the camera goes on to its end, the
// recording is complete and readable, finish() succeeds and names the lost streams, and
// lost_devices() is the error the command exits with.
TEST(LiveCapture, UnpluggedDeviceGoesOfflineAndTheOthersGoOn) {
  TempDir tmp;
  RecordConfig c;
  RecordCameraConfig cam;
  cam.id = "camera_middle";
  cam.device = write_video(tmp.path(), 15).string();  // 0.6 s at 25 fps
  c.cameras.push_back(cam);
  RecordDepthSensorConfig d;
  d.id = "front";
  d.driver = "fake";
  d.device = "unplug_after=6";
  c.depth_sensors.push_back(d);
  const fs::path rec = tmp.path() / "session";
  auto capture = LiveCapture::open(c, rec);
  ASSERT_TRUE(capture) << capture.error().message;
  std::map<SensorId, int> frames;
  while (true) {
    auto f = (*capture)->next();
    if (!f) {
      EXPECT_TRUE(is_end_of_stream(f.error())) << f.error().message;
      break;
    }
    ++frames[(*f)->sensor];
  }
  EXPECT_EQ(frames["camera_middle"], 15) << "the camera goes on after the sensor is lost";
  EXPECT_EQ(frames["front.depth"], 5);
  EXPECT_EQ(frames["front.color"], 5);
  auto stats = (*capture)->finish();
  ASSERT_TRUE(stats) << stats.error().message;
  EXPECT_NE(stats->streams.at("front.depth").lost.find("unplugged"), std::string::npos);
  EXPECT_NE(stats->streams.at("front.color").lost.find("unplugged"), std::string::npos);
  EXPECT_TRUE(stats->streams.at("camera_middle").lost.empty());
  const Status lost = lost_devices(*stats);
  ASSERT_FALSE(lost);
  EXPECT_NE(lost.error().message.find("front.depth"), std::string::npos) << lost.error().message;
  EXPECT_EQ(lost.error().message.find("camera_middle"), std::string::npos);

  auto reader = SessionReader::open(rec);
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_TRUE((*reader)->manifest().complete);
  std::map<SensorId, int> read;
  for (auto f = (*reader)->next(); f; f = (*reader)->next()) ++read[(*f)->sensor];
  EXPECT_EQ(read["camera_middle"], 15);
  EXPECT_EQ(read["front.depth"], 5);
  // The session keeps what the capture counted, and `check` says it: the loss is a note (the
  // records on disk are intact), on the lost device's streams only.
  std::ifstream report_file(rec / kCaptureReportFile);
  const nlohmann::json report = nlohmann::json::parse(report_file, nullptr, false);
  ASSERT_TRUE(report.is_object()) << "capture.json";
  EXPECT_NE(report["streams"]["front.depth"]["lost"].get<std::string>().find("unplugged"),
            std::string::npos);
  EXPECT_TRUE(report["streams"]["camera_middle"]["lost"].is_null());
  EXPECT_EQ(report["streams"]["camera_middle"]["frames_captured"], 15);
  auto checked = check_session(rec);
  ASSERT_TRUE(checked) << checked.error().message;
  EXPECT_TRUE(checked->sound()) << checked->table();
  for (const StreamCheck& sc : checked->streams) {
    const bool lost_device = sc.stream.rfind("front.", 0) == 0;
    ASSERT_EQ(sc.notes.size(), lost_device ? 1u : 0u) << sc.stream << "\n" << checked->table();
    if (lost_device) {
      EXPECT_NE(sc.notes[0].find("lost during the recording"), std::string::npos) << sc.notes[0];
    }
  }
  // A damaged report is a session problem, as a damaged markers.jsonl is.
  std::ofstream(rec / kCaptureReportFile) << "{\"streams\": [";
  checked = check_session(rec);
  ASSERT_TRUE(checked);
  EXPECT_FALSE(checked->sound());
  ASSERT_EQ(checked->session_problems.size(), 1u);
  EXPECT_NE(checked->session_problems[0].find("capture.json"), std::string::npos);

  // record: with its only device lost it ends by itself, not at --duration (or Ctrl-C).
  RecordConfig only_depth;
  only_depth.depth_sensors.push_back(d);
  RecordOptions ro;
  ro.duration_s = 30;
  const auto started = std::chrono::steady_clock::now();
  auto recorded = record_session(only_depth, tmp.path() / "depth_only", ro);
  ASSERT_TRUE(recorded) << recorded.error().message;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 10);
  EXPECT_FALSE(recorded->streams.at("front.depth").lost.empty());

  DepthSensorOptions o;  // the fake device's setting
  for (const char* device : {"unplug_after=0", "unplug_after=", "unplug", "3"}) {
    o.device = device;
    EXPECT_FALSE(o.check()) << device;
  }
  o.device = "unplug_after=12";
  EXPECT_TRUE(o.check());
}

// The robot's voice as a second ALSA input (docs/recording.md, "The robot's voice"): read with
// its defaults, and refused where it could not serve as the microphone array's reference.
TEST(RecordConfig, RobotAudioIsReadAndNeedsTheMicrophoneArray) {
  TempDir tmp;
  write_text(tmp.path() / "a.yaml",
             "audio: {id: mic_array, device: \"hw:1,0\", channels: 4}\n"
             "robot_audio: {device: \"hw:Loopback,1,0\"}\n");
  auto c = read_record_config(tmp.path() / "a.yaml");
  ASSERT_TRUE(c) << c.error().message;
  ASSERT_TRUE(c->robot_audio);
  EXPECT_EQ(c->robot_audio->id, "robot_audio");
  EXPECT_EQ(c->robot_audio->device, "hw:Loopback,1,0");
  EXPECT_EQ(c->robot_audio->channels, 1);
  EXPECT_EQ(c->robot_audio->sample_rate, 16000);
  const auto expect_error = [&](const std::string& yaml, const std::string& needle) {
    expect_config_error(tmp.path(), yaml, needle);
  };
  expect_error("cameras:\n  - {id: a, device: 0}\nrobot_audio: {device: x}\n",
               "robot_audio without audio");
  expect_error("audio: {device: a}\nrobot_audio: {id: mic_array, device: x}\n", "used twice");
  expect_error("audio: {device: a}\nrobot_audio: {channels: 2}\n", "robot_audio has no device");
  expect_error("audio: {device: a}\nrobot_audio: {device: x, calibration: m.yaml}\n",
               "robot_audio.calibration: unknown key");
}

// Both audio inputs are captured, each stream declaring its role in the manifest (which a
// recording writes as its session.yaml), so the analysers of a live session or of its recording
// gate the robot's voice. ALSA's "null" device for both: it is not paced (seconds of audio in a
// millisecond), so nothing is recorded here; a recording's writer would refuse its stamps.
TEST(LiveCapture, RobotVoiceIsASecondAudioStreamWithItsRole) {
  RecordConfig c;
  c.audio = RecordAudioConfig{};
  c.audio->device = "null";
  c.robot_audio = RecordRobotAudioConfig{};
  c.robot_audio->device = "null";
  auto capture = LiveCapture::open(c);
  if (!capture && capture.error().message.find("null") != std::string::npos)
    GTEST_SKIP() << "ALSA 'null' device unavailable: " << capture.error().message;
  ASSERT_TRUE(capture) << capture.error().message;
  std::set<SensorId> seen;
  for (int i = 0; i < 10000 && seen.size() < 2; ++i) {
    auto f = (*capture)->next();
    ASSERT_TRUE(f) << f.error().message;
    ASSERT_NE((*f)->as<AudioChunk>(), nullptr);
    EXPECT_EQ((*f)->as<AudioChunk>()->channels, (*f)->sensor == "robot_audio" ? 1 : 4);
    seen.insert((*f)->sensor);
  }
  EXPECT_EQ(seen, (std::set<SensorId>{"mic_array", "robot_audio"}));
  const SessionManifest& m = (*capture)->manifest();
  ASSERT_NE(m.find("robot_audio"), nullptr);
  EXPECT_EQ(m.find("robot_audio")->channels, 1);
  EXPECT_EQ(m.find("mic_array")->channels, 4);
  auto roles = stream_roles(m);
  ASSERT_TRUE(roles) << roles.error().message;
  EXPECT_EQ(roles->at("robot_audio"), std::vector<std::string>{"robot_audio"});
  EXPECT_EQ(roles->at("mic_array"), std::vector<std::string>{"mic_array"});
  auto stats = (*capture)->finish();
  ASSERT_TRUE(stats) << stats.error().message;
  EXPECT_EQ(stats->streams.count("robot_audio"), 1u);
}

TEST(RecordConfig, SkeletonInputsAreRead) {
  TempDir tmp;
  write_text(tmp.path() / "a.yaml",
             "skeletons:\n  - {id: front.skeleton, udp: \"127.0.0.1:9870\", rate_hz: 30}\n");
  auto c = read_record_config(tmp.path() / "a.yaml");
  ASSERT_TRUE(c) << c.error().message;
  ASSERT_EQ(c->skeletons.size(), 1u);
  EXPECT_EQ(c->skeletons[0].port, 9870);
  EXPECT_EQ(c->skeletons[0].host, "127.0.0.1");
  write_text(tmp.path() / "d.yaml",
             "depth_sensors:\n  - {id: front, driver: openni2, device: \"\", fps: 30}\n");
  auto d = read_record_config(tmp.path() / "d.yaml");
  ASSERT_TRUE(d) << d.error().message;
  ASSERT_EQ(d->depth_sensors.size(), 1u);
  EXPECT_EQ(d->depth_sensors[0].driver, "openni2");
  write_text(tmp.path() / "b.yaml", "skeletons:\n  - {id: s, udp: \"127.0.0.1:x\"}\n");
  auto b = read_record_config(tmp.path() / "b.yaml");
  ASSERT_FALSE(b);
  EXPECT_NE(b.error().message.find("skeletons[0].udp"), std::string::npos) << b.error().message;
}

}  // namespace
}  // namespace dreamsense::sources
