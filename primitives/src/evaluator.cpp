#include "dreamsense/primitives/evaluator.hpp"

#include "dreamsense/primitives/actions.hpp"
#include "dreamsense/primitives/audio.hpp"
#include "dreamsense/primitives/body.hpp"
#include "dreamsense/primitives/face.hpp"
#include "dreamsense/primitives/face_recognition.hpp"  // faces (issue 12): F17, F18
#include "dreamsense/primitives/objects.hpp"

#include <functional>

namespace dreamsense::primitives {
namespace {

using Evaluate = std::function<PrimitiveRecord(const PrimitiveContext&)>;

// One row per primitive: the keys it reads and how it is answered with the default query.
// A row without a function (a primitive whose analyser has not landed) is always disabled.
struct PrimitiveSpec {
  PrimitiveId id;
  std::vector<std::string> reads;
  Evaluate evaluate;
};

template <typename F>
Evaluate answer(PrimitiveId id, F f) {
  return [id, f](const PrimitiveContext& ctx) { return to_record(id, ctx.tick(), f(ctx)); };
}

const std::vector<PrimitiveSpec>& table() {
  using P = PrimitiveId;
  static const std::vector<PrimitiveSpec> kTable = {
      {P::kCheckMutualGaze, {"face.mutual_gaze"}, answer(P::kCheckMutualGaze, check_mutual_gaze)},
      {P::kGetArmAngle, {"body.child"}, answer(P::kGetArmAngle, get_arm_angle)},
      {P::kGetBody, {"body.child"}, answer(P::kGetBody, get_body)},
      {P::kGetBodyPose, {"body.child"}, answer(P::kGetBodyPose, get_body_pose)},
      {P::kGetEyeGaze,
       {"face.eye_gaze"},
       answer(P::kGetEyeGaze, [](const PrimitiveContext& c) { return get_eye_gaze(c); })},
      {P::kGetEyes, {"face.eye_centers"}, answer(P::kGetEyes, get_eyes)},
      {P::kGetFaces, {"face.detections"}, answer(P::kGetFaces, get_faces)},
      {P::kGetGripLocation,
       {"objects.table"},
       answer(P::kGetGripLocation, [](const PrimitiveContext& c) { return get_grip_location(c); })},
      {P::kGetHands, {"body.child"}, answer(P::kGetHands, get_hands)},
      {P::kGetHead, {"face.head_pose"}, answer(P::kGetHead, get_head)},
      {P::kGetHeadGaze, {"face.head_pose"}, answer(P::kGetHeadGaze, get_head_gaze)},
      {P::kGetHeadGazePlane,
       {"face.head_pose"},
       answer(P::kGetHeadGazePlane,
              [](const PrimitiveContext& c) {
                return get_head_gaze_plane(c, PlaneQuery{c.options().head_gaze_plane});
              })},
      {P::kGetObjects, {"objects.table"}, answer(P::kGetObjects, get_objects)},
      {P::kGetObjectsCircle,
       {"objects.table"},
       answer(P::kGetObjectsCircle,
              [](const PrimitiveContext& c) {
                return get_objects_in_circle(c, CircleQuery{c.options().objects_circle_centre_m,
                                                            c.options().objects_circle_radius_m});
              })},
      {P::kGetObjectTableDistance,
       {"objects.table"},
       answer(P::kGetObjectTableDistance,
              [](const PrimitiveContext& c) { return get_object_table_distance(c); })},
      {P::kGetSoundDirection,
       {"audio.sound_direction"},
       answer(P::kGetSoundDirection,
              [](const PrimitiveContext& c) {
                return get_sound_direction(c,
                                           ThresholdQuery{c.options().sound_direction_threshold});
              })},
      {P::kIdentifyFace, {"face.identity"}, answer(P::kIdentifyFace, identify_face)},
      {P::kIdentifyFaceExpression,
       {"face.expression"},
       answer(P::kIdentifyFaceExpression, identify_face_expression)},
      {P::kIdentifyObject,
       {"objects.table"},
       answer(P::kIdentifyObject, [](const PrimitiveContext& c) { return identify_object(c); })},
      {P::kIdentifyTrajectory,
       {"body.action"},
       answer(P::kIdentifyTrajectory,
              [](const PrimitiveContext& c) { return identify_trajectory(c); })},
      {P::kIdentifyVoice, {"audio.speaker"}, answer(P::kIdentifyVoice, identify_voice)},
      {P::kRecognizeSpeech, {"audio.speech"}, answer(P::kRecognizeSpeech, recognize_speech)},
      {P::kTrackFace,
       {"face.tracks"},
       answer(P::kTrackFace, [](const PrimitiveContext& c) { return track_face(c); })},
      {P::kTrackHand,
       {"body.child"},
       answer(P::kTrackHand, [](const PrimitiveContext& c) { return track_hand(c); })},
      {P::kTrackObject,
       {"objects.table"},
       answer(P::kTrackObject, [](const PrimitiveContext& c) { return track_object(c); })},
  };
  return kTable;
}

const PrimitiveSpec& spec(PrimitiveId id) { return table()[static_cast<size_t>(id) - 1]; }

}  // namespace

const std::vector<std::string>& keys_read(PrimitiveId id) { return spec(id).reads; }

Evaluator::Evaluator(EvaluatorOptions options, KeySensors key_sensors,
                     std::map<SensorId, CameraModel> cameras)
    : options_(std::move(options)),
      key_sensors_(std::move(key_sensors)),
      cameras_(std::move(cameras)) {}

bool Evaluator::enabled(PrimitiveId id) const {
  const PrimitiveSpec& s = spec(id);
  if (!s.evaluate) return false;
  for (const auto& k : s.reads)
    if (key_sensors_.count(k) == 0) return false;
  return true;
}

PrimitiveContext Evaluator::context(BlackboardView view, Timestamp tick) const {
  return PrimitiveContext(std::move(view), tick, options_, key_sensors_, last_seen_, first_tick_,
                          cameras_);
}

std::vector<PrimitiveRecord> Evaluator::evaluate(const MultiFrame& tick,
                                                 const BlackboardView& view) {
  if (!first_tick_.is_set()) first_tick_ = tick.stamp;
  for (const auto& [id, f] : tick.frames) last_seen_[id] = f->stamp;
  for (const auto& [id, c] : tick.chunks)
    if (!c.empty()) last_seen_[id] = c.back()->stamp;

  const PrimitiveContext ctx = context(view, tick.stamp);
  std::vector<PrimitiveRecord> out;
  out.reserve(kPrimitiveCount);
  for (const auto& i : catalogue()) {
    if (enabled(i.id)) {
      out.push_back(spec(i.id).evaluate(ctx));
    } else {
      PrimitiveRecord r;
      r.stamp = tick.stamp;
      r.id = i.id;
      out.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace dreamsense::primitives
