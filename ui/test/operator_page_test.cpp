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

}  // namespace
}  // namespace dreamsense::ui
