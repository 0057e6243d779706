#include "ros_hri.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#ifdef DREAMSENSE_HAVE_ROS_MSGS
#include "ExpressionPubSubTypes.h"
#include "GazePubSubTypes.h"
#include "IdsListPubSubTypes.h"
#include "LiveSpeechPubSubTypes.h"
#include "MutualGazePubSubTypes.h"
#include "NormalizedRegionOfInterest2DPubSubTypes.h"
#endif

namespace dreamsense::publish {

RosTime ros_time(Timestamp t) {
  const int64_t ns = t.is_set() ? t.ns() : 0;
  RosTime r;
  int64_t sec = ns / 1'000'000'000LL, rest = ns % 1'000'000'000LL;
  if (rest < 0) {  // builtin_interfaces/Time: nanosec in [0, 1e9)
    rest += 1'000'000'000LL;
    --sec;
  }
  r.sec = static_cast<int32_t>(sec);
  r.nanosec = static_cast<uint32_t>(rest);
  return r;
}

std::string hri_expression(const std::string& label) {
  // hri_msgs/Expression's constants for the labels our expression models use.
  static const std::map<std::string, std::string> kNames = {
      {"anger", "angry"},    {"angry", "angry"},        {"sadness", "sad"},
      {"sad", "sad"},        {"happy", "happy"},        {"happiness", "happy"},
      {"fear", "scared"},    {"surprise", "surprised"}, {"disgust", "disgusted"},
      {"neutral", "neutral"}};
  const auto it = kNames.find(label);
  return it == kNames.end() ? label : it->second;
}

std::optional<std::array<float, 4>> normalized_roi(const cv::Rect2d& box, cv::Size image) {
  if (image.width <= 0 || image.height <= 0) return std::nullopt;
  const double x0 = std::clamp(box.x / image.width, 0.0, 1.0);
  const double y0 = std::clamp(box.y / image.height, 0.0, 1.0);
  const double x1 = std::clamp((box.x + box.width) / image.width, 0.0, 1.0);
  const double y1 = std::clamp((box.y + box.height) / image.height, 0.0, 1.0);
  if (!(x1 > x0) || !(y1 > y0)) return std::nullopt;
  return std::array<float, 4>{static_cast<float>(x0), static_cast<float>(y0),
                              static_cast<float>(x1), static_cast<float>(y1)};
}

#ifdef DREAMSENSE_HAVE_ROS_MSGS
bool have_ros_messages() { return true; }

namespace detail {
namespace dds = eprosima::fastdds::dds;
using primitives::PrimitiveId;
using primitives::PrimitiveRecord;

namespace {
template <typename Header>
void fill_header(Header& h, Timestamp stamp, const std::string& frame_id) {
  const RosTime t = ros_time(stamp);
  h.stamp().sec(t.sec);
  h.stamp().nanosec(t.nanosec);
  h.frame_id(frame_id);
}

const PrimitiveRecord* find(const std::vector<PrimitiveRecord>& records, PrimitiveId id,
                            bool ok_only = true) {
  for (const auto& r : records)
    if (r.id == id && (!ok_only || r.ok())) return &r;
  return nullptr;
}
}  // namespace

struct RosHriTopics::Impl {
  dds::TypeSupport ids{new hri_msgs::msg::dds_::IdsList_PubSubType()};
  dds::TypeSupport roi{new hri_msgs::msg::dds_::NormalizedRegionOfInterest2D_PubSubType()};
  dds::TypeSupport expression{new hri_msgs::msg::dds_::Expression_PubSubType()};
  dds::TypeSupport speech{new hri_msgs::msg::dds_::LiveSpeech_PubSubType()};
  dds::TypeSupport gaze{new dreamsense_msgs::msg::dds_::Gaze_PubSubType()};
  dds::TypeSupport mutual{new dreamsense_msgs::msg::dds_::MutualGaze_PubSubType()};
  // The child's face id: "face_<track>" from the newest trackFace answer, kept while it is
  // silent, so /humans/faces/<id>/* does not change name from tick to tick.
  std::string face_id = "face_0";
};

RosHriTopics::RosHriTopics() : impl_(std::make_unique<Impl>()) {}
RosHriTopics::~RosHriTopics() = default;

Status RosHriTopics::register_types(dds::DomainParticipant* participant) {
  Impl& m = *impl_;
  for (dds::TypeSupport* t : {&m.ids, &m.roi, &m.expression, &m.speech, &m.gaze, &m.mutual})
    if (t->register_type(participant) != ReturnCode_t::RETCODE_OK)
      return make_error(ErrorCode::kInternal, "DDS: cannot register type {}", t->get_type_name());
  return ok_status();
}

Status RosHriTopics::publish(const std::vector<PrimitiveRecord>& records,
                             const DdsPublisherOptions& options, const WriterLookup& writer,
                             DdsPublisherStats& stats) {
  Impl& m = *impl_;
  auto wanted = [&](PrimitiveId id) {
    return options.only.empty() || options.only.count(primitives::info(id).name) > 0;
  };
  Status status = ok_status();
  auto write = [&](const std::string& topic, dds::TypeSupport& type, void* msg) {
    dds::DataWriter* w = writer(topic, type);
    if (w == nullptr) {
      status = make_error(ErrorCode::kIoError, "DDS: cannot create the writer of {}", topic);
      return;
    }
    if (w->write(msg))
      ++stats.published;
    else
      ++stats.failed;
  };
  if (const PrimitiveRecord* track = find(records, PrimitiveId::kTrackFace))
    if (const auto* v = track->value_as<primitives::TrackValue>(); v && v->track_id >= 0)
      m.face_id = fmt::format("face_{}", v->track_id);
  const std::string face_topic = "rt/humans/faces/" + m.face_id + "/";

  // /humans/faces/tracked every tick getFaces answers (empty list: no face), and the face's roi.
  if (const PrimitiveRecord* faces = find(records, PrimitiveId::kGetFaces, false);
      faces != nullptr && wanted(PrimitiveId::kGetFaces)) {
    const auto* v = faces->ok() ? faces->value_as<primitives::FacesValue>() : nullptr;
    hri_msgs::msg::dds_::IdsList_ list;
    fill_header(list.header(), faces->stamp, "");
    if (v != nullptr && !v->faces.empty()) list.ids().push_back(m.face_id);
    write(kRosTrackedFacesTopic, m.ids, &list);
    if (v != nullptr && !v->faces.empty()) {
      const primitives::FaceInWorld& f = v->faces.front();
      const auto box = f.boxes.find(f.camera);
      const auto size = options.image_sizes.find(f.camera);
      if (box != f.boxes.end() && size != options.image_sizes.end())
        if (const auto n = normalized_roi(box->second, size->second)) {
          hri_msgs::msg::dds_::NormalizedRegionOfInterest2D_ roi;
          fill_header(roi.header(), faces->stamp, f.camera);
          roi.xmin((*n)[0]);
          roi.ymin((*n)[1]);
          roi.xmax((*n)[2]);
          roi.ymax((*n)[3]);
          roi.c(f.score);
          write(face_topic + "roi", m.roi, &roi);
        }
    }
  }
  if (const PrimitiveRecord* r = find(records, PrimitiveId::kIdentifyFaceExpression);
      r != nullptr && wanted(r->id))
    if (const auto* v = r->value_as<primitives::ClassLabelValue>()) {
      hri_msgs::msg::dds_::Expression_ e;
      fill_header(e.header(), r->stamp, r->source);
      e.expression(hri_expression(v->label));
      // Not estimated: the classifier gives categories only.
      e.valence(std::numeric_limits<float>::quiet_NaN());
      e.arousal(std::numeric_limits<float>::quiet_NaN());
      const auto score = v->scores.find(v->label);
      e.confidence(static_cast<float>(score != v->scores.end() ? score->second
                                                               : r->confidence.value_or(0.0)));
      write(face_topic + "expression", m.expression, &e);
    }
  if (const PrimitiveRecord* r = find(records, PrimitiveId::kGetEyeGaze);
      r != nullptr && wanted(r->id))
    if (const auto* v = r->value_as<primitives::EyeGazeValue>()) {
      dreamsense_msgs::msg::dds_::Gaze_ g;
      fill_header(g.header(), r->stamp, "world");
      g.origin().x(v->both.origin_m[0]);
      g.origin().y(v->both.origin_m[1]);
      g.origin().z(v->both.origin_m[2]);
      g.direction().x(v->both.direction[0]);
      g.direction().y(v->both.direction[1]);
      g.direction().z(v->both.direction[2]);
      g.theta_deg(v->both.theta_deg);
      g.phi_deg(v->both.phi_deg);
      g.camera(v->camera);
      write(face_topic + "gaze", m.gaze, &g);
    }
  if (const PrimitiveRecord* r = find(records, PrimitiveId::kCheckMutualGaze);
      r != nullptr && wanted(r->id))
    if (const auto* v = r->value_as<primitives::MutualGazeValue>()) {
      dreamsense_msgs::msg::dds_::MutualGaze_ g;
      fill_header(g.header(), r->stamp, "world");
      g.mutual(v->mutual);
      g.raw(v->raw);
      g.held_s(v->held_s);
      g.miss_distance_m(v->miss_distance_m);
      g.target(v->target);
      write("rt/" + options.topic_prefix + "/mutual_gaze", m.mutual, &g);
    }
  // Speech: on the voice of its speaker (identifyVoice of the same utterance), else "anonymous".
  if (const PrimitiveRecord* r = find(records, PrimitiveId::kRecognizeSpeech);
      r != nullptr && wanted(r->id))
    if (const auto* v = r->value_as<primitives::SpeechValue>()) {
      std::string voice = "anonymous";
      if (const PrimitiveRecord* who = find(records, PrimitiveId::kIdentifyVoice))
        if (const auto* w = who->value_as<primitives::VoiceValue>(); w && !w->speaker_id.empty())
          voice = w->speaker_id;
      hri_msgs::msg::dds_::IdsList_ list;
      fill_header(list.header(), r->stamp, "");
      list.ids().push_back(voice);
      write(kRosTrackedVoicesTopic, m.ids, &list);
      hri_msgs::msg::dds_::LiveSpeech_ s;
      fill_header(s.header(), r->stamp, r->source);
      s.final(v->text);
      s.confidence(v->confidence);
      s.language("en");  // the recogniser's acoustic models are English
      write("rt/humans/voices/" + voice + "/speech", m.speech, &s);
    }
  return status;
}

}  // namespace detail
#else
bool have_ros_messages() { return false; }
#endif

}  // namespace dreamsense::publish
