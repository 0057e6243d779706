// The typed ROS 2 / ROS4HRI messages of `live --publish dds`, received by plain Fast DDS readers of
// the types generated from the project's own IDL (publish/idl): topic names, ROS 2 type names,
// fields, and header stamps equal to the analysis stamps.

#include "dreamsense/publish/dds_publisher.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <mutex>
#include <unistd.h>

#include "ExpressionPubSubTypes.h"
#include "GazePubSubTypes.h"
#include "IdsListPubSubTypes.h"
#include "LiveSpeechPubSubTypes.h"
#include "MutualGazePubSubTypes.h"
#include "NormalizedRegionOfInterest2DPubSubTypes.h"
#include "fastdds_asan_options.hpp"

namespace dreamsense::publish {
namespace {
namespace dds = eprosima::fastdds::dds;
using primitives::PrimitiveId;
using primitives::PrimitiveRecord;
using primitives::PrimitiveStatus;

// A participant like the publisher's (this machine only).
dds::DomainParticipant* local_participant(int domain) {
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.transport().use_builtin_transports = false;
  qos.transport().user_transports.push_back(
      std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>());
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.emplace_back("127.0.0.1");
  qos.transport().user_transports.push_back(udp);
  return dds::DomainParticipantFactory::get_instance()->create_participant(domain, qos);
}

// Collects the samples of one topic of message type Msg.
template <typename Msg, typename PubSub>
class Reader : public dds::DataReaderListener {
 public:
  Reader(dds::DomainParticipant* p, const std::string& topic) {
    dds::TypeSupport type(new PubSub());
    type_name_ = type.get_type_name();
    type.register_type(p);
    dds::Topic* t = p->create_topic(topic, type_name_, dds::TOPIC_QOS_DEFAULT);
    dds::Subscriber* s = p->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    dds::DataReaderQos q = dds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    q.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
    q.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    q.history().depth = 100;
    ok_ = t != nullptr && s != nullptr && s->create_datareader(t, q, this) != nullptr;
  }
  bool ok() const { return ok_; }
  const std::string& type_name() const { return type_name_; }
  void on_data_available(dds::DataReader* reader) override {
    Msg m;
    dds::SampleInfo info;
    while (reader->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) {
        std::lock_guard lock(mutex_);
        got_.push_back(m);
        cv_.notify_all();
      }
  }
  std::vector<Msg> wait_for(size_t n, int ms) {
    std::unique_lock lock(mutex_);
    cv_.wait_for(lock, std::chrono::milliseconds(ms), [&] { return got_.size() >= n; });
    return got_;
  }

 private:
  bool ok_ = false;
  std::string type_name_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<Msg> got_;
};

PrimitiveRecord ok_record(PrimitiveId id, int64_t stamp_ns, primitives::PrimitiveValue value,
                          const std::string& source = "") {
  PrimitiveRecord r;
  r.id = id;
  r.status = PrimitiveStatus::kOk;
  r.stamp = Timestamp::from_ns(stamp_ns);
  r.value = std::move(value);
  r.confidence = 0.8;
  r.source = source;
  return r;
}

// One tick of the child's perception: a face (track 7) in camera_middle, happy, gazing, mutual
// gaze held 1.5 s, and "go forward" said by the child.
std::vector<PrimitiveRecord> tick(int64_t ns) {
  primitives::FacesValue faces;
  primitives::FaceInWorld f;
  f.position_m = {0, 0, 1};
  f.score = 0.9f;
  f.camera = "camera_middle";
  f.boxes["camera_middle"] = cv::Rect2d(320, 240, 320, 240);
  faces.faces.push_back(f);
  primitives::TrackValue track;
  track.track_id = 7;
  primitives::ClassLabelValue expression;
  expression.label = "happy";
  expression.scores = {{"happy", 0.75}, {"sadness", 0.25}};
  primitives::EyeGazeValue gaze;
  gaze.both.origin_m = {0.1, 0.2, 1.0};
  gaze.both.direction = {0, 0, -1};
  gaze.both.theta_deg = 4;
  gaze.camera = "camera_middle";
  primitives::MutualGazeValue mutual;
  mutual.mutual = true;
  mutual.held_s = 1.5;
  primitives::SpeechValue speech;
  speech.text = "go forward";
  speech.confidence = 0.9;
  primitives::VoiceValue voice;
  voice.speaker_id = "child";
  return {ok_record(PrimitiveId::kGetFaces, ns, faces),
          ok_record(PrimitiveId::kTrackFace, ns, track),
          ok_record(PrimitiveId::kIdentifyFaceExpression, ns, expression, "camera_middle"),
          ok_record(PrimitiveId::kGetEyeGaze, ns, gaze),
          ok_record(PrimitiveId::kCheckMutualGaze, ns, mutual),
          ok_record(PrimitiveId::kRecognizeSpeech, ns, speech, "mic_array"),
          ok_record(PrimitiveId::kIdentifyVoice, ns, voice, "mic_array")};
}

TEST(RosHriTopics, TypedReadersReceiveFacesGazeExpressionAndSpeech) {
  if (!have_ros_messages()) GTEST_SKIP() << "built without fastddsgen";
  DdsPublisherOptions o;
  o.domain_id = 150 + static_cast<int>(::getpid() % 80);
  o.image_sizes["camera_middle"] = cv::Size(1280, 960);
  dds::DomainParticipant* p = local_participant(o.domain_id);
  ASSERT_NE(p, nullptr);
  using namespace hri_msgs::msg::dds_;
  using namespace dreamsense_msgs::msg::dds_;
  Reader<IdsList_, IdsList_PubSubType> tracked(p, "rt/humans/faces/tracked");
  Reader<NormalizedRegionOfInterest2D_, NormalizedRegionOfInterest2D_PubSubType> roi(
      p, "rt/humans/faces/face_7/roi");
  Reader<Expression_, Expression_PubSubType> expression(p, "rt/humans/faces/face_7/expression");
  Reader<Gaze_, Gaze_PubSubType> gaze(p, "rt/humans/faces/face_7/gaze");
  Reader<MutualGaze_, MutualGaze_PubSubType> mutual(p, "rt/dreamsense/mutual_gaze");
  Reader<LiveSpeech_, LiveSpeech_PubSubType> speech(p, "rt/humans/voices/child/speech");
  ASSERT_TRUE(tracked.ok() && roi.ok() && expression.ok() && gaze.ok() && mutual.ok() &&
              speech.ok());
  // ROS 2 type names, so ROS 2 nodes match them.
  EXPECT_EQ(tracked.type_name(), "hri_msgs::msg::dds_::IdsList_");
  EXPECT_EQ(speech.type_name(), "hri_msgs::msg::dds_::LiveSpeech_");
  {
    auto pub = DdsPublisher::create(o);
    ASSERT_TRUE(pub) << pub.error().message;
    // Until discovery: one tick every 100 ms (each its own stamp).
    int64_t ns = 2'500'000'000LL;
    for (int i = 0; i < 50 && speech.wait_for(1, 100).empty(); ++i, ns += 40'000'000LL)
      ASSERT_TRUE((*pub)->publish(tick(ns)));
    EXPECT_EQ((*pub)->stats().failed, 0u);
  }  // the publisher waits for acknowledgements at shutdown
  const auto s = speech.wait_for(1, 2000);
  ASSERT_FALSE(s.empty()) << "nothing received in 5 s";
  EXPECT_EQ(s.front().final(), "go forward");
  EXPECT_DOUBLE_EQ(s.front().confidence(), 0.9);
  EXPECT_EQ(s.front().header().frame_id(), "mic_array");
  // The header stamp is the analysis stamp of that tick (ns -> sec + nanosec).
  const int64_t stamp = int64_t{s.front().header().stamp().sec()} * 1'000'000'000LL +
                        s.front().header().stamp().nanosec();
  EXPECT_GE(stamp, 2'500'000'000LL);
  EXPECT_EQ((stamp - 2'500'000'000LL) % 40'000'000LL, 0);

  const auto t = tracked.wait_for(1, 2000);
  ASSERT_FALSE(t.empty());
  ASSERT_EQ(t.front().ids().size(), 1u);
  EXPECT_EQ(t.front().ids()[0], "face_7");
  const auto r = roi.wait_for(1, 2000);
  ASSERT_FALSE(r.empty());
  EXPECT_FLOAT_EQ(r.front().xmin(), 0.25f);
  EXPECT_FLOAT_EQ(r.front().ymax(), 0.5f);
  EXPECT_FLOAT_EQ(r.front().c(), 0.9f);
  EXPECT_EQ(r.front().header().frame_id(), "camera_middle");
  const auto e = expression.wait_for(1, 2000);
  ASSERT_FALSE(e.empty());
  EXPECT_EQ(e.front().expression(), "happy");
  EXPECT_FLOAT_EQ(e.front().confidence(), 0.75f);
  EXPECT_TRUE(std::isnan(e.front().valence())) << "not estimated";
  const auto g = gaze.wait_for(1, 2000);
  ASSERT_FALSE(g.empty());
  EXPECT_DOUBLE_EQ(g.front().origin().y(), 0.2);
  EXPECT_DOUBLE_EQ(g.front().direction().z(), -1.0);
  EXPECT_EQ(g.front().header().frame_id(), "world");
  const auto m = mutual.wait_for(1, 2000);
  ASSERT_FALSE(m.empty());
  EXPECT_TRUE(m.front().mutual());
  EXPECT_DOUBLE_EQ(m.front().held_s(), 1.5);
  p->delete_contained_entities();
  dds::DomainParticipantFactory::get_instance()->delete_participant(p);
}

// Without typed messages in the build, asking for them is a clear error, not silence.
TEST(RosHriTopics, JsonOnlyWorksAndTypedNeedsTheBuild) {
  DdsPublisherOptions o;
  o.domain_id = 231;
  o.ros_topics = false;
  o.json_topics = true;
  auto pub = DdsPublisher::create(o);
  if (!pub && pub.error().code == ErrorCode::kUnsupported) GTEST_SKIP() << "no Fast DDS";
  ASSERT_TRUE(pub) << pub.error().message;
  o.ros_topics = true;
  auto typed = DdsPublisher::create(o);
  EXPECT_EQ(static_cast<bool>(typed), have_ros_messages());
}

}  // namespace
}  // namespace dreamsense::publish
