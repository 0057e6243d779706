// The operator page serves the latest primitives and camera frames over HTTP on localhost.

#include "dreamsense/ui/operator_page.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <vector>

namespace dreamsense::ui {
namespace {

using primitives::PrimitiveId;
using primitives::PrimitiveRecord;
using primitives::PrimitiveStatus;

TEST(OperatorPage, ServesLatestPrimitivesFramesAndStatus) {
  OperatorPageOptions o;
  o.port = 0;  // any free port
  o.max_image_width = 320;
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  ASSERT_GT((*page)->port(), 0);
  EXPECT_EQ((*page)->url(), "http://127.0.0.1:" + std::to_string((*page)->port()) + "/");

  PrimitiveRecord faces;
  faces.id = PrimitiveId::kGetFaces;
  faces.status = PrimitiveStatus::kOk;
  faces.stamp = Timestamp::from_ns(40'000'000);
  faces.value = primitives::FacesValue{{}, {}, std::string("camera_left")};
  PrimitiveRecord voice;
  voice.id = PrimitiveId::kIdentifyVoice;
  voice.status = PrimitiveStatus::kNoData;
  voice.stamp = faces.stamp;
  (*page)->update({faces, voice});
  faces.stamp = Timestamp::from_ns(80'000'000);
  faces.value = primitives::FacesValue{{}, {}, std::string("camera_middle")};
  (*page)->update({faces});  // the newer record replaces the older one
  (*page)->update_frame("camera_middle",
                        make_frame("camera_middle", faces.stamp, 0,
                                   ColorImage{cv::Mat(480, 640, CV_8UC3, cv::Scalar(0, 0, 255))}));
  (*page)->set_status({{"ticks", 2}});

  httplib::Client client("127.0.0.1", (*page)->port());
  auto root = client.Get("/");
  ASSERT_TRUE(root);
  EXPECT_EQ(root->status, 200);
  EXPECT_NE(root->body.find("/api/primitives"), std::string::npos);

  auto prims = client.Get("/api/primitives");
  ASSERT_TRUE(prims);
  const auto j = nlohmann::json::parse(prims->body);
  EXPECT_EQ(j["stamp_ns"], 80'000'000);
  EXPECT_EQ(j["primitives"]["getFaces"]["value"]["selected_camera"], "camera_middle");
  EXPECT_EQ(j["primitives"]["identifyVoice"]["status"], "no_data");

  auto status = client.Get("/api/status");
  ASSERT_TRUE(status);
  EXPECT_EQ(nlohmann::json::parse(status->body)["ticks"], 2);

  auto cams = client.Get("/api/cameras");
  ASSERT_TRUE(cams);
  EXPECT_EQ(nlohmann::json::parse(cams->body), nlohmann::json::array({"camera_middle"}));
  auto jpeg = client.Get("/camera/camera_middle.jpg");
  ASSERT_TRUE(jpeg);
  ASSERT_EQ(jpeg->status, 200);
  const cv::Mat img =
      cv::imdecode(std::vector<uchar>(jpeg->body.begin(), jpeg->body.end()), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 320);  // scaled to max_image_width
  EXPECT_EQ(img.rows, 240);
  EXPECT_GT(img.at<cv::Vec3b>(100, 100)[2], 200);  // red stays red
  auto missing = client.Get("/camera/camera_left.jpg");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
}

// live --blur-faces: the served picture is pixelated inside the latest getFaces boxes only.
TEST(OperatorPage, BlurFacesPixelatesTheFaceBoxesOfTheServedPicture) {
  OperatorPageOptions o;
  o.port = 0;
  o.blur_faces = true;
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  // A fine black/white checkerboard (2 px squares): blurred, it turns grey.
  cv::Mat board(480, 640, CV_8UC3);
  for (int y = 0; y < board.rows; ++y)
    for (int x = 0; x < board.cols; ++x)
      board.at<cv::Vec3b>(y, x) = cv::Vec3b::all(((x / 2 + y / 2) % 2) ? 255 : 0);
  PrimitiveRecord faces;
  faces.id = PrimitiveId::kGetFaces;
  faces.status = PrimitiveStatus::kOk;
  faces.stamp = Timestamp::from_ns(40'000'000);
  primitives::FacesValue v;
  v.cameras["camera_middle"].push_back({cv::Rect2d(200, 100, 160, 160), 0.9f, 1.f});
  faces.value = v;
  (*page)->update({faces});
  (*page)->update_frame("camera_middle",
                        make_frame("camera_middle", faces.stamp, 0, ColorImage{board}));
  httplib::Client client("127.0.0.1", (*page)->port());
  auto jpeg = client.Get("/camera/camera_middle.jpg");
  ASSERT_TRUE(jpeg);
  ASSERT_EQ(jpeg->status, 200);
  const cv::Mat img =
      cv::imdecode(std::vector<uchar>(jpeg->body.begin(), jpeg->body.end()), cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(img.size(), cv::Size(640, 480));
  auto contrast = [&](cv::Rect r) {
    cv::Scalar mean, sd;
    cv::meanStdDev(img(r), mean, sd);
    return sd[0];
  };
  EXPECT_LT(contrast({240, 140, 80, 80}), 30) << "inside the face box: blurred";
  EXPECT_GT(contrast({480, 300, 80, 80}), 50) << "elsewhere: the checkerboard is untouched";
}

// DNS rebinding: a page elsewhere that resolves its own name to 127.0.0.1 sends its own Host.
TEST(OperatorPage, RefusesForeignHostHeaders) {
  OperatorPageOptions o;
  o.port = 0;
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  httplib::Client client("127.0.0.1", (*page)->port());
  auto own = client.Get("/api/status");
  ASSERT_TRUE(own);
  EXPECT_EQ(own->status, 200);
  auto foreign = client.Get("/api/primitives", {{"Host", "attacker.example:80"}});
  ASSERT_TRUE(foreign);
  EXPECT_EQ(foreign->status, 403);
  auto localhost = client.Get("/api/status", {{"Host", "localhost:1234"}});
  ASSERT_TRUE(localhost);
  EXPECT_EQ(localhost->status, 200);
  // Values are written into the page as text, never as HTML.
  auto root = client.Get("/");
  ASSERT_TRUE(root);
  EXPECT_EQ(root->body.find("innerHTML"), std::string::npos);
}

// Slow clients that open connections and send headers byte by byte do not stop the page.
TEST(OperatorPage, AnswersWhileEightSlowConnectionsAreOpen) {
  OperatorPageOptions o;
  o.port = 0;
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  std::vector<int> slow;
  for (int i = 0; i < 8; ++i) {
    const int s = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>((*page)->port()));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(s, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
    const char partial[] = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";
    ASSERT_GT(::send(s, partial, sizeof(partial) - 1, 0), 0);
    slow.push_back(s);
  }
  httplib::Client client("127.0.0.1", (*page)->port());
  client.set_connection_timeout(2, 0);
  client.set_read_timeout(2, 0);
  auto r = client.Get("/api/status");
  ASSERT_TRUE(r) << "the page did not answer while 8 slow connections were open";
  EXPECT_EQ(r->status, 200);
  for (auto s : slow) ::close(s);
}

TEST(OperatorPage, BusyPortAndBadOptionsAreErrors) {
  OperatorPageOptions o;
  o.port = 0;
  auto first = OperatorPage::start(o);
  ASSERT_TRUE(first) << first.error().message;
  o.port = (*first)->port();
  auto second = OperatorPage::start(o);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find(std::to_string(o.port)), std::string::npos);
  o.port = 70000;
  EXPECT_FALSE(o.check());
}

// The mark button's request: a marker through the handler, answered 201 and listed on the page;
// refused when it is not JSON (a cross-site form) or comes from another web page.
TEST(OperatorPage, MarkerPostReachesTheHandlerAndIsListed) {
  OperatorPageOptions o;
  o.port = 0;
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  httplib::Client client("127.0.0.1", (*page)->port());
  auto none = client.Post("/api/marker", R"({"label":"mark"})", "application/json");
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 503) << "no handler: markers are not recorded";

  std::vector<std::string> labels;
  (*page)->set_marker_handler([&labels](const std::string& label) -> Result<nlohmann::json> {
    labels.push_back(label);
    return nlohmann::json{{"n", static_cast<int>(labels.size())},
                          {"stamp_ns", int64_t{62'345'000'000}},
                          {"label", label}};
  });
  auto made = client.Post("/api/marker", R"({"label":"child left the room"})", "application/json");
  ASSERT_TRUE(made);
  ASSERT_EQ(made->status, 201) << made->body;
  const auto j = nlohmann::json::parse(made->body);
  EXPECT_EQ(j["n"], 1);
  EXPECT_EQ(j["clock"], "01:02.3");
  ASSERT_EQ(labels, std::vector<std::string>{"child left the room"});

  auto form = client.Post("/api/marker", "label=x", "application/x-www-form-urlencoded");
  ASSERT_TRUE(form);
  EXPECT_EQ(form->status, 415);
  httplib::Headers foreign = {{"Origin", "http://attacker.example"}};
  auto cross = client.Post("/api/marker", foreign, R"({})", "application/json");
  ASSERT_TRUE(cross);
  EXPECT_EQ(cross->status, 403);
  httplib::Headers own = {{"Origin", "http://127.0.0.1:" + std::to_string((*page)->port())}};
  auto same = client.Post("/api/marker", own, R"({"label":"\u0007"})", "application/json");
  ASSERT_TRUE(same);
  EXPECT_EQ(same->status, 201) << same->body;
  EXPECT_EQ(labels.size(), 2u);
  EXPECT_EQ(labels.back(), "mark") << "control characters are dropped; empty -> mark";

  const auto state = nlohmann::json::parse(client.Get("/api/operator")->body);
  ASSERT_EQ(state["markers"].size(), 2u);
  EXPECT_EQ(state["markers"][0]["label"], "child left the room");
  EXPECT_EQ(state["markers"][0]["clock"], "01:02.3");
  EXPECT_EQ(state["marker_count"], 2);
}

// Off loopback every request needs the token (made at random, carried by url()); on loopback
// none is needed unless one is given.
TEST(OperatorPage, TokenRequiredOffLoopback) {
  OperatorPageOptions o;
  o.port = 0;
  o.host = "0.0.0.0";
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  const std::string token = (*page)->token();
  ASSERT_GE(token.size(), 16u);
  EXPECT_NE((*page)->url().find("?token=" + token), std::string::npos) << (*page)->url();
  httplib::Client client("127.0.0.1", (*page)->port());
  EXPECT_EQ(client.Get("/api/operator")->status, 401);
  EXPECT_EQ(client.Get("/")->status, 401);
  EXPECT_EQ(client.Get("/api/operator?token=wrong")->status, 401);
  EXPECT_EQ(client.Get("/api/operator?token=" + token)->status, 200);
  EXPECT_EQ(client.Get("/api/operator", {{"X-Dreamsense-Token", token}})->status, 200);
  EXPECT_EQ(client.Post("/api/marker", R"({})", "application/json")->status, 401);

  // Another page off loopback gets another token.
  auto other = OperatorPage::start(o);
  ASSERT_TRUE(other) << other.error().message;
  EXPECT_NE((*other)->token(), token);

  OperatorPageOptions local;
  local.port = 0;
  auto open = OperatorPage::start(local);
  ASSERT_TRUE(open);
  EXPECT_TRUE((*open)->token().empty());
  httplib::Client lc("127.0.0.1", (*open)->port());
  EXPECT_EQ(lc.Get("/api/operator")->status, 200);
  local.token = "given-token";
  auto given = OperatorPage::start(local);
  ASSERT_TRUE(given);
  httplib::Client gc("127.0.0.1", (*given)->port());
  EXPECT_EQ(gc.Get("/api/operator")->status, 401);
  EXPECT_EQ(gc.Get("/api/operator?token=given-token")->status, 200);
  local.token = "bad token<>";
  EXPECT_FALSE(local.check());
}

// The indicators and the status strip come rounded and with units.
TEST(OperatorPage, StateIsRoundedWithUnits) {
  EXPECT_EQ(session_clock_text(0), "00:00.0");
  EXPECT_EQ(session_clock_text(83'456'789'012), "01:23.4");
  EXPECT_EQ(session_clock_text(3'723'400'000'000), "1:02:03.4");
  EXPECT_EQ(byte_size_text(512), "512 B");
  EXPECT_EQ(byte_size_text(830'400), "830 kB");
  EXPECT_EQ(byte_size_text(12'345'678), "12.3 MB");
  EXPECT_EQ(byte_size_text(1'234'567'890), "1.23 GB");

  OperatorPageOptions o;
  o.port = 0;
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  const Timestamp t = Timestamp::from_ns(83'456'789'012);
  auto record = [&](PrimitiveId id, primitives::PrimitiveValue v,
                    PrimitiveStatus st = PrimitiveStatus::kOk) {
    PrimitiveRecord r;
    r.id = id;
    r.status = st;
    r.stamp = t;
    r.value = std::move(v);
    return r;
  };
  primitives::MutualGazeValue gaze;
  gaze.mutual = true;
  gaze.held_s = 1.23456789;
  primitives::SpeechValue speech;
  speech.text = "hello robot";
  speech.confidence = 0.87654321;
  speech.end_ns = 80'456'789'012;
  primitives::VoiceValue voice;
  voice.speaker_id = "child";
  primitives::SoundDirectionValue dir;
  dir.azimuth_deg = 31.4159265;
  primitives::ClassLabelValue gesture;
  gesture.label = "wave";
  gesture.scores = {{"wave", 0.912345}, {"none", 0.1}};
  (*page)->update(
      {record(PrimitiveId::kCheckMutualGaze, gaze), record(PrimitiveId::kRecognizeSpeech, speech),
       record(PrimitiveId::kIdentifyVoice, voice), record(PrimitiveId::kGetSoundDirection, dir),
       record(PrimitiveId::kIdentifyTrajectory, gesture)});
  // A later no_data speech record does not erase the last utterance.
  (*page)->update({record(PrimitiveId::kRecognizeSpeech, {}, PrimitiveStatus::kNoData)});
  (*page)->set_status({{"stamp_ns", t.ns()},
                       {"ticks", 2087},
                       {"recording", {{"on", true}, {"bytes", 12'345'678}}},
                       {"streams",
                        {{"camera_left", {{"dropped", 3}, {"offline", false}}},
                         {"mic_array", {{"dropped", 0}, {"offline", true}}}}},
                       {"face_model", "generic model, self-calibrating"}});
  httplib::Client client("127.0.0.1", (*page)->port());
  auto r = client.Get("/api/operator");
  ASSERT_TRUE(r);
  const auto s = nlohmann::json::parse(r->body);
  EXPECT_EQ(s["clock"], "01:23.4");
  EXPECT_DOUBLE_EQ(s["clock_s"].get<double>(), 83.5);
  EXPECT_EQ(s["recording"]["size"], "12.3 MB");
  EXPECT_EQ(s["recording"]["on"], true);
  EXPECT_EQ(s["sensors_offline"], nlohmann::json::array({"mic_array"}));
  EXPECT_EQ(s["face_model"], "generic model, self-calibrating");
  EXPECT_EQ(s["streams"][0]["id"], "camera_left");
  EXPECT_EQ(s["streams"][0]["dropped"], 3);
  EXPECT_EQ(s["mutual_gaze"]["state"], "mutual");
  EXPECT_EQ(s["mutual_gaze"]["held"], "1.2 s");
  EXPECT_DOUBLE_EQ(s["mutual_gaze"]["held_s"].get<double>(), 1.2);
  EXPECT_EQ(s["mutual_gaze"]["text"], "Looking at the robot");
  ASSERT_TRUE(s["utterance"].is_object()) << s.dump();
  EXPECT_EQ(s["utterance"]["text"], "hello robot");
  EXPECT_EQ(s["utterance"]["speaker"], "child");
  EXPECT_EQ(s["utterance"]["direction"], "31\u00b0 azimuth");
  EXPECT_EQ(s["utterance"]["at"], "01:20.4");
  EXPECT_EQ(s["utterance"]["ago"], "3 s");
  EXPECT_DOUBLE_EQ(s["utterance"]["confidence"].get<double>(), 0.88);
  EXPECT_EQ(s["gesture"]["text"], "wave");
  EXPECT_EQ(s["gesture"]["detail"], "score 0.91");
  // No 17-digit floats anywhere in what the page shows.
  EXPECT_EQ(r->body.find("1.23456789"), std::string::npos);
  EXPECT_EQ(r->body.find("31.41"), std::string::npos);

  gaze.mutual = false;
  (*page)->update({record(PrimitiveId::kCheckMutualGaze, gaze)});
  EXPECT_EQ((*page)->operator_state_json()["mutual_gaze"]["state"], "not_mutual");
  (*page)->update({record(PrimitiveId::kCheckMutualGaze, {}, PrimitiveStatus::kNoData)});
  EXPECT_EQ((*page)->operator_state_json()["mutual_gaze"]["text"], "no gaze estimate");
  // Without a live self-calibration the strip has no face-model item.
  (*page)->set_status({{"stamp_ns", t.ns()}, {"ticks", 2088}});
  EXPECT_TRUE((*page)->operator_state_json()["face_model"].is_null());
}

// With the tick's blackboard the picture carries the overlay (tick time, camera name, mutual-gaze
// box), drawn when asked.
TEST(OperatorPage, ViewedFramesAreServedWithTheOverlay) {
  OperatorPageOptions o;
  o.port = 0;
  auto page = OperatorPage::start(o);
  ASSERT_TRUE(page) << page.error().message;
  MultiFrame tick;
  tick.stamp = Timestamp::from_ns(40'000'000);
  tick.tick = 1;
  tick.frames["camera_middle"] =
      make_frame("camera_middle", tick.stamp, 0,
                 ColorImage{cv::Mat(480, 640, CV_8UC3, cv::Scalar(0, 0, 255))});
  (*page)->update_view(tick, BlackboardView());
  httplib::Client client("127.0.0.1", (*page)->port());
  auto jpeg = client.Get("/camera/camera_middle.jpg");
  ASSERT_TRUE(jpeg);
  ASSERT_EQ(jpeg->status, 200);
  const cv::Mat img =
      cv::imdecode(std::vector<uchar>(jpeg->body.begin(), jpeg->body.end()), cv::IMREAD_COLOR);
  ASSERT_EQ(img.size(), cv::Size(640, 480));
  cv::Mat not_red;
  cv::inRange(img, cv::Scalar(0, 0, 200), cv::Scalar(60, 60, 255), not_red);
  EXPECT_GT(img.total() - cv::countNonZero(not_red), 500u) << "overlay drawn on the frame";
  EXPECT_EQ(nlohmann::json::parse(client.Get("/api/cameras")->body),
            nlohmann::json::array({"camera_middle"}));
}

}  // namespace
}  // namespace dreamsense::ui
