// DDS publishing: topic names, options, and a round trip through Fast DDS on this machine
// (publisher and subscriber participants in one process, localhost-only transports).

#include "dreamsense/publish/dds_publisher.hpp"

#include "dreamsense/export/primitive_json.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <thread>
#include <unistd.h>

#include "fastdds_asan_options.hpp"

namespace dreamsense::publish {
namespace {

using primitives::PrimitiveId;
using primitives::PrimitiveRecord;
using primitives::PrimitiveStatus;

TEST(DdsTopics, RosNamesForEveryPrimitive) {
  DdsPublisherOptions o;
  EXPECT_EQ(dds_topic_name(o, "getFaces"), "rt/dreamsense/getFaces");
  EXPECT_EQ(dds_topic_name(o, "getHeadGaze (plane)"), "rt/dreamsense/getHeadGaze_plane");
  o.topic_prefix = "robot1/perception";
  EXPECT_EQ(dds_topic_name(o, "getObjects (circle)"), "rt/robot1/perception/getObjects_circle");
  for (const auto& i : primitives::catalogue()) {
    const std::string token = dds_topic_token(i.name);
    ASSERT_FALSE(token.empty()) << i.name;
    for (char c : token)
      EXPECT_TRUE(std::isalnum(static_cast<unsigned char>(c)) || c == '_') << token;
  }
}

TEST(DdsPublisherOptions, BadOptionsAreNamed) {
  DdsPublisherOptions o;
  EXPECT_TRUE(o.check());
  o.domain_id = 300;
  o.topic_prefix = "/x";
  o.only = {"getFaces", "getFace"};
  auto st = o.check();
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("domain_id"), std::string::npos);
  EXPECT_NE(st.error().message.find("topic_prefix"), std::string::npos);
  EXPECT_NE(st.error().message.find("'getFace' is not a primitive name"), std::string::npos);
  DdsPublisherOptions none;
  none.ros_topics = none.json_topics = false;
  EXPECT_FALSE(none.check()) << "nothing to publish";
}

TEST(RosMapping, TimeExpressionAndNormalisedBox) {
  const RosTime t = ros_time(Timestamp::from_ns(12'345'678'901LL));
  EXPECT_EQ(t.sec, 12);
  EXPECT_EQ(t.nanosec, 345'678'901u);
  const RosTime neg = ros_time(Timestamp::from_ns(-1));
  EXPECT_EQ(neg.sec, -1);
  EXPECT_EQ(neg.nanosec, 999'999'999u);
  EXPECT_EQ(hri_expression("sadness"), "sad");
  EXPECT_EQ(hri_expression("fear"), "scared");
  EXPECT_EQ(hri_expression("neutral"), "neutral");
  EXPECT_EQ(hri_expression("contempt"), "contempt") << "no ROS4HRI equivalent: unchanged";
  const auto roi = normalized_roi({320, 240, 640, 480}, {1280, 960});
  ASSERT_TRUE(roi);
  EXPECT_FLOAT_EQ((*roi)[0], 0.25f);
  EXPECT_FLOAT_EQ((*roi)[3], 0.75f);
  EXPECT_FALSE(normalized_roi({2000, 10, 50, 50}, {1280, 960})) << "outside the image";
  EXPECT_FALSE(normalized_roi({0, 0, 50, 50}, {0, 0}));
  const auto clipped = normalized_roi({-100, -100, 200, 200}, {1000, 1000});
  ASSERT_TRUE(clipped);
  EXPECT_FLOAT_EQ((*clipped)[0], 0.f);
  EXPECT_FLOAT_EQ((*clipped)[2], 0.1f);
}

PrimitiveRecord record(PrimitiveId id, PrimitiveStatus status, int64_t stamp_ns) {
  PrimitiveRecord r;
  r.id = id;
  r.status = status;
  r.stamp = Timestamp::from_ns(stamp_ns);
  if (status == PrimitiveStatus::kOk) {
    primitives::FacesValue faces;
    faces.faces.push_back({{0.1, -0.2, 1.1}, 0.9f, "camera_left", {}});
    r.value = faces;
    r.confidence = 0.9;
  }
  return r;
}

TEST(DdsPublisher, SubscriberReceivesOkRecordsAsPrimitivesJsonLines) {
  DdsPublisherOptions o;
  o.domain_id = 100 + static_cast<int>(::getpid() % 100);  // parallel test runs do not mix
  o.json_topics = true;
  o.ros_topics = false;
  auto sub = DdsStringSubscriber::create(o, "getFaces");
  if (!sub && sub.error().code == ErrorCode::kUnsupported) GTEST_SKIP() << sub.error().message;
  ASSERT_TRUE(sub) << sub.error().message;
  auto pub = DdsPublisher::create(o);
  ASSERT_TRUE(pub) << pub.error().message;
  // Discovery takes a moment: publish one tick every 100 ms until the subscriber has heard one.
  std::vector<std::string> got;
  for (int tick = 0; tick < 50 && got.empty(); ++tick) {
    ASSERT_TRUE((*pub)->publish({record(PrimitiveId::kGetFaces, PrimitiveStatus::kOk, tick),
                                 record(PrimitiveId::kGetHead, PrimitiveStatus::kNoData, tick)}));
    got = (*sub)->wait_for(1, 100);
  }
  ASSERT_FALSE(got.empty()) << "nothing received over DDS in 5 s";
  const auto j = nlohmann::json::parse(got.front());
  EXPECT_EQ(j["primitive"], "getFaces");
  EXPECT_EQ(j["status"], "ok");
  EXPECT_DOUBLE_EQ(j["value"]["faces"][0]["position_m"][2].get<double>(), 1.1);
  EXPECT_EQ(j.dump(), exporters::to_json(record(PrimitiveId::kGetFaces, PrimitiveStatus::kOk,
                                                j["stamp_ns"].get<int64_t>()))
                          .dump());
  // Only ok records by default: getHead's no_data ticks were not published.
  const auto s = (*pub)->stats();
  EXPECT_GE(s.published, 1u);
  EXPECT_EQ(s.failed, 0u);
  auto head = DdsStringSubscriber::create(o, "getHead");
  ASSERT_TRUE(head);
  EXPECT_TRUE((*head)->wait_for(1, 300).empty());
}

}  // namespace
}  // namespace dreamsense::publish
