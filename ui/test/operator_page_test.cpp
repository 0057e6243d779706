// The operator page serves the latest primitives and camera frames over HTTP on localhost.

#include "dreamsense/ui/operator_page.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <httplib.h>

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
