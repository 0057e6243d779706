#include "dreamsense/primitives/evaluator.hpp"

#include "dreamsense/body/arm_geometry.hpp"
#include "dreamsense/core/perception.hpp"
#include "dreamsense/primitives/body_primitives.hpp"

namespace dreamsense::primitives {
namespace {
using nlohmann::json;

json vec_json(const cv::Vec3d& v) { return json::array({v[0], v[1], v[2]}); }
void append_mm(std::vector<double>& out, const cv::Vec3d& v) {
  for (int i = 0; i < 3; ++i) out.push_back(v[i] * 1000.0);
}
json arm_json(const std::optional<body::ArmAngle>& a) {
  if (!a) return nullptr;
  return {{"azimuth_deg", a->azimuth_deg}, {"elevation_deg", a->elevation_deg}};
}
}  // namespace

Status EvaluatorOptions::check() const {
  std::string bad;
  if (freshness.ns() <= 0) bad += " freshness must be > 0;";
  if (offline_after <= freshness) bad += " offline_after must exceed freshness;";
  if (!(track_hand_dt_s >= 0)) bad += " track_hand_dt_s must be >= 0;";
  if (!(sound_direction_threshold >= 0 && sound_direction_threshold <= 1))
    bad += " sound_direction_threshold must be in [0, 1];";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "EvaluatorOptions:" + bad);
  return face_geometry.check();
}

Evaluator::Evaluator(EvaluatorOptions options, SensorId body_sensor, SensorId audio_sensor)
    : options_(std::move(options)),
      body_sensor_(std::move(body_sensor)),
      audio_sensor_(std::move(audio_sensor)) {}

PrimitiveRecord Evaluator::base(PrimitiveId id, Timestamp stamp) const {
  PrimitiveRecord r;
  r.stamp = stamp;
  r.id = id;
  r.status = PrimitiveStatus::kDisabled;
  r.value = nullptr;
  return r;
}

void Evaluator::enable_faces(std::map<SensorId, CameraModel> cameras) {
  face_cameras_ = std::move(cameras);
}

template <typename T>
PrimitiveStatus Evaluator::observation_status(const std::optional<Entry<T>>& entry,
                                              const std::vector<SensorId>& sensors,
                                              Timestamp tick) const {
  Timestamp last = first_tick_;
  for (const auto& s : sensors) {
    auto seen = last_seen_.find(s);
    if (seen != last_seen_.end()) last = std::max(last, seen->second);
  }
  if (tick - last > options_.offline_after) return PrimitiveStatus::kSensorOffline;
  if (!entry) return PrimitiveStatus::kNoData;
  if (tick - entry->stamp > options_.freshness) return PrimitiveStatus::kStale;
  if (!entry->present()) return PrimitiveStatus::kNoData;
  return PrimitiveStatus::kOk;
}

std::vector<PrimitiveRecord> Evaluator::evaluate(const MultiFrame& tick,
                                                 const BlackboardView& view) {
  if (!first_tick_.is_set()) first_tick_ = tick.stamp;
  for (const auto& [id, f] : tick.frames) last_seen_[id] = f->stamp;
  for (const auto& [id, c] : tick.chunks)
    if (!c.empty()) last_seen_[id] = c.back()->stamp;

  std::vector<PrimitiveRecord> out;
  out.reserve(kPrimitiveCount);
  for (const auto& i : catalogue()) out.push_back(base(i.id, tick.stamp));
  if (!body_sensor_.empty()) evaluate_body(tick, view, out);
  if (!audio_sensor_.empty()) evaluate_sound_direction(tick, view, out);
  if (!face_cameras_.empty()) evaluate_faces(tick, view, out);
  if (!speech_sensor_.empty()) evaluate_speech(tick, view, out);
  return out;
}

// F22 recognizeSpeech: ok at the tick an utterance in the grammar was recognised; no_data
// otherwise (nothing new said: the last utterance is not repeated).
void Evaluator::evaluate_speech(const MultiFrame& tick, const BlackboardView& view,
                                std::vector<PrimitiveRecord>& out) {
  PrimitiveRecord& r = out[static_cast<int>(PrimitiveId::kRecognizeSpeech) - 1];
  r.source = speech_sensor_;
  const auto entry = view.get(keys::kRecognizedSpeech);
  if (entry) r.data_stamp = entry->stamp;
  r.status = observation_status(entry, {speech_sensor_}, tick.stamp);
  if (r.status == PrimitiveStatus::kStale ||
      (r.status == PrimitiveStatus::kOk && entry->stamp != tick.stamp))
    r.status = PrimitiveStatus::kNoData;  // reported once, at the tick it was recognised
  if (r.status != PrimitiveStatus::kOk) return;
  const RecognizedSpeech& s = *entry->value;
  r.confidence = entry->confidence;
  r.value = {{"text", s.text},
             {"tag", s.tag},
             {"confidence", s.confidence},
             {"start_ns", s.start.ns()},
             {"end_ns", s.end.ns()}};
  r.legacy_text = s.tag;
}

// F7 getFaces: faces across cameras with their 3-D position, plus what each camera saw (so that
// detection can be evaluated per camera) and the selected camera.
void Evaluator::evaluate_faces(const MultiFrame& tick, const BlackboardView& view,
                               std::vector<PrimitiveRecord>& out) {
  PrimitiveRecord& r = out[static_cast<int>(PrimitiveId::kGetFaces) - 1];
  std::vector<SensorId> sensors;
  for (const auto& [id, m] : face_cameras_) sensors.push_back(id);
  const auto entry = view.get(keys::kFaceDetections);
  if (entry) r.data_stamp = entry->stamp;
  r.status = observation_status(entry, sensors, tick.stamp);
  if (r.status != PrimitiveStatus::kOk) return;
  const auto selected = view.get(keys::kSelectedCamera);
  const SelectedCamera* sel = selected && selected->present() && selected->stamp == entry->stamp
                                  ? selected->value.get()
                                  : nullptr;
  const auto faces = associate_faces(*entry->value, sel, face_cameras_, options_.face_geometry);
  json faces_json = json::array();
  std::vector<double> legacy{static_cast<double>(std::min<size_t>(faces.size(), 5))};
  for (size_t i = 0; i < faces.size(); ++i) {
    const auto& f = faces[i];
    json boxes = json::object();
    for (const auto& [cam, b] : f.boxes) boxes[cam] = json::array({b.x, b.y, b.width, b.height});
    faces_json.push_back({{"position_m", vec_json(f.position_m)},
                          {"score", f.score},
                          {"camera", f.camera},
                          {"boxes", boxes}});
    if (i < 5) append_mm(legacy, f.position_m);
  }
  legacy.resize(16, 0.0);  // DREAM: up to 5 faces, unused slots 0
  json cameras = json::object();
  for (const auto& [cam, cf] : entry->value->cameras) {
    json list = json::array();
    for (const auto& d : cf.faces)
      list.push_back(
          {{"box_px", json::array({d.box_px.x, d.box_px.y, d.box_px.width, d.box_px.height})},
           {"score", d.score},
           {"frontalness", d.frontalness}});
    cameras[cam] = list;
  }
  r.confidence = entry->confidence;
  r.value = {{"faces", faces_json},
             {"cameras", cameras},
             {"selected_camera", sel ? json(sel->camera) : json(nullptr)}};
  r.legacy = legacy;
  if (sel)
    r.source = sel->camera;
  else if (!faces.empty())
    r.source = faces.front().camera;
}

// F16 getSoundDirection, default query threshold = options_.sound_direction_threshold.
void Evaluator::evaluate_sound_direction(const MultiFrame& tick, const BlackboardView& view,
                                         std::vector<PrimitiveRecord>& out) {
  PrimitiveRecord& r = out[static_cast<int>(PrimitiveId::kGetSoundDirection) - 1];
  r.source = audio_sensor_;
  r.query = {{"threshold", options_.sound_direction_threshold}};
  const auto entry = view.get(keys::kSoundDirection);
  if (entry) r.data_stamp = entry->stamp;
  r.status = observation_status(entry, {audio_sensor_}, tick.stamp);  // absent = silence
  if (r.status != PrimitiveStatus::kOk) return;
  if (entry->confidence < options_.sound_direction_threshold) {
    r.status = PrimitiveStatus::kNoData;  // heard something, not confident enough
    r.confidence = entry->confidence;
    return;
  }
  const SoundDirection& d = *entry->value;
  r.confidence = entry->confidence;
  r.value = {{"azimuth_deg", d.azimuth_deg},
             {"elevation_deg", d.elevation_deg ? json(*d.elevation_deg) : json(nullptr)},
             {"confidence", entry->confidence},
             {"direction", vec_json(d.direction_world)}};
  r.legacy = std::vector<double>{d.azimuth_deg, static_cast<double>(entry->confidence)};
}

void Evaluator::evaluate_body(const MultiFrame& tick, const BlackboardView& view,
                              std::vector<PrimitiveRecord>& out) {
  const auto entry = view.get(keys::kChildBody);
  const PrimitiveStatus status = observation_status(entry, {body_sensor_}, tick.stamp);

  const PrimitiveId ids[] = {PrimitiveId::kGetArmAngle, PrimitiveId::kGetBody,
                             PrimitiveId::kGetBodyPose, PrimitiveId::kGetHands,
                             PrimitiveId::kTrackHand};
  for (PrimitiveId id : ids) {
    PrimitiveRecord& r = out[static_cast<int>(id) - 1];
    r.status = status;
    r.source = body_sensor_;
    if (entry) r.data_stamp = entry->stamp;
  }
  if (status != PrimitiveStatus::kOk) return;

  const SkeletonBody& b = entry->value->body;
  const double conf = entry->confidence;
  auto ok = [&](PrimitiveId id, json value, std::optional<std::vector<double>> legacy) {
    PrimitiveRecord& r = out[static_cast<int>(id) - 1];
    r.value = std::move(value);
    r.legacy = std::move(legacy);
    r.confidence = conf;
  };
  auto none = [&](PrimitiveId id) {
    out[static_cast<int>(id) - 1].status = PrimitiveStatus::kNoData;
  };

  // F2 getArmAngle
  const body::ArmAngles arms = body::arm_angles(b);
  if (arms.left || arms.right) {
    std::optional<std::vector<double>> legacy;
    if (arms.left && arms.right)
      legacy = std::vector<double>{arms.left->elevation_deg, arms.left->azimuth_deg,
                                   arms.right->elevation_deg, arms.right->azimuth_deg};
    ok(PrimitiveId::kGetArmAngle, {{"left", arm_json(arms.left)}, {"right", arm_json(arms.right)}},
       legacy);
  } else {
    none(PrimitiveId::kGetArmAngle);
  }

  // F3 getBody
  if (auto c = body_centre(b)) {
    std::vector<double> legacy;
    append_mm(legacy, *c);
    ok(PrimitiveId::kGetBody,
       {{"position_m", vec_json(*c)}, {"bodies_in_view", entry->value->bodies_in_view}}, legacy);
  } else {
    none(PrimitiveId::kGetBody);
  }

  // F4 getBodyPose
  {
    json joints = json::object();
    std::vector<double> legacy;
    for (const auto& j : body_pose(b)) {
      joints[std::string(joint_name(j.joint))] = {{"position_m", vec_json(j.position_m)},
                                                  {"confidence", j.confidence}};
      append_mm(legacy, j.position_m);
    }
    ok(PrimitiveId::kGetBodyPose, {{"joints", joints}}, legacy);
  }

  // F9 getHands
  const Hands h = hands(b);
  if (h.left || h.right) {
    std::optional<std::vector<double>> legacy;
    if (h.left && h.right) {
      legacy.emplace();
      append_mm(*legacy, *h.left);
      append_mm(*legacy, *h.right);
    }
    ok(PrimitiveId::kGetHands,
       {{"left", h.left ? vec_json(*h.left) : json(nullptr)},
        {"right", h.right ? vec_json(*h.right) : json(nullptr)}},
       legacy);
  } else {
    none(PrimitiveId::kGetHands);
  }

  // F24 trackHand, default query: seed = the right hand (else left), dt = track_hand_dt_s.
  PrimitiveRecord& th = out[static_cast<int>(PrimitiveId::kTrackHand) - 1];
  const std::optional<cv::Vec3d> seed = h.right ? h.right : h.left;
  if (seed) {
    th.query = {{"seed_m", vec_json(*seed)}, {"dt_s", options_.track_hand_dt_s}};
    auto p = predict_hand(view.history(keys::kChildBody, 16), *seed, options_.track_hand_dt_s);
    if (p) {
      std::vector<double> legacy;
      append_mm(legacy, p->position_m);
      ok(PrimitiveId::kTrackHand,
         {{"position_m", vec_json(p->position_m)},
          {"velocity_mps", vec_json(p->velocity_mps)},
          {"hand", p->left ? "left" : "right"},
          {"samples", p->samples}},
         legacy);
    } else {
      none(PrimitiveId::kTrackHand);
    }
  } else {
    none(PrimitiveId::kTrackHand);
  }
}

}  // namespace dreamsense::primitives
