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
json ray_json(const GazeRay& r) {
  if (!r.valid) return nullptr;
  return {{"origin", vec_json(r.origin_world_m)},
          {"direction", vec_json(r.direction_world)},
          {"theta_deg", r.theta_deg},
          {"phi_deg", r.phi_deg},
          {"offset", json::array({r.features[0], r.features[1]})}};
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
  if (!(track_face_dt_s >= 0)) bad += " track_face_dt_s must be >= 0;";
  const cv::Vec3d n =
      (head_gaze_plane[1] - head_gaze_plane[0]).cross(head_gaze_plane[2] - head_gaze_plane[0]);
  if (!(cv::norm(n) > 1e-9)) bad += " the three head_gaze_plane points are collinear;";
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
  face_sensors_.clear();
  for (const auto& [id, m] : face_cameras_) face_sensors_.push_back(id);
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
  if (!face_cameras_.empty()) {
    evaluate_faces(tick, view, out);
    evaluate_head(tick, view, out);
    evaluate_track_face(tick, view, out);
    if (gaze_enabled_) evaluate_gaze(tick, view, out);
  }
  if (!speech_sensor_.empty()) evaluate_speech(tick, view, out);
  if (!voice_sensor_.empty()) evaluate_voice(tick, view, out);
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

// F21 identifyVoice: ok at the tick an utterance's speaker was decided (child, therapist or
// unknown); no_data otherwise. Legacy: DREAM's [1] child / [0] therapist; [-1] for anyone else
// (DREAM published nothing then; its consumer only tests element 0 > 0).
void Evaluator::evaluate_voice(const MultiFrame& tick, const BlackboardView& view,
                               std::vector<PrimitiveRecord>& out) {
  PrimitiveRecord& r = out[static_cast<int>(PrimitiveId::kIdentifyVoice) - 1];
  r.source = voice_sensor_;
  const auto entry = view.get(keys::kSpeakerIdentity);
  if (entry) r.data_stamp = entry->stamp;
  r.status = observation_status(entry, {voice_sensor_}, tick.stamp);
  if (r.status == PrimitiveStatus::kStale ||
      (r.status == PrimitiveStatus::kOk && entry->stamp != tick.stamp))
    r.status = PrimitiveStatus::kNoData;  // reported once, at the tick it was decided
  if (r.status != PrimitiveStatus::kOk) return;
  const SpeakerIdentity& s = *entry->value;
  r.confidence = entry->confidence;
  r.value = {{"speaker_id", s.speaker_id}, {"name", s.name},       {"score", s.score},
             {"start_ns", s.start.ns()},   {"end_ns", s.end.ns()}, {"method", s.method}};
  r.legacy = std::vector<double>{s.speaker_id == "child"       ? 1.0
                                 : s.speaker_id == "therapist" ? 0.0
                                                               : -1.0};
}

// F7 getFaces: faces across cameras with their 3-D position, plus what each camera saw (so that
// detection can be evaluated per camera) and the selected camera.
void Evaluator::evaluate_faces(const MultiFrame& tick, const BlackboardView& view,
                               std::vector<PrimitiveRecord>& out) {
  PrimitiveRecord& r = out[static_cast<int>(PrimitiveId::kGetFaces) - 1];
  const auto entry = view.get(keys::kFaceDetections);
  if (entry) r.data_stamp = entry->stamp;
  r.status = observation_status(entry, face_sensors_, tick.stamp);
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

// F10 getHead, F11 getHeadGaze, F12 getHeadGaze (plane) from the head pose (keys::kHeadPose).
void Evaluator::evaluate_head(const MultiFrame& tick, const BlackboardView& view,
                              std::vector<PrimitiveRecord>& out) {
  const auto entry = view.get(keys::kHeadPose);
  const PrimitiveStatus status = observation_status(entry, face_sensors_, tick.stamp);
  PrimitiveRecord& head = out[static_cast<int>(PrimitiveId::kGetHead) - 1];
  PrimitiveRecord& gaze = out[static_cast<int>(PrimitiveId::kGetHeadGaze) - 1];
  PrimitiveRecord& plane = out[static_cast<int>(PrimitiveId::kGetHeadGazePlane) - 1];
  const auto& pts = options_.head_gaze_plane;
  plane.query = {{"p1", vec_json(pts[0])}, {"p2", vec_json(pts[1])}, {"p3", vec_json(pts[2])}};
  for (PrimitiveRecord* r : {&head, &gaze, &plane}) {
    r->status = status;
    if (entry) r->data_stamp = entry->stamp;
    if (status == PrimitiveStatus::kOk) {
      r->confidence = entry->confidence;
      r->source = entry->value->camera;
    }
  }
  if (status != PrimitiveStatus::kOk) return;
  const HeadPose& p = *entry->value;
  head.value = {{"position_m", vec_json(p.position_world_m)}, {"camera", p.camera}};
  head.legacy.emplace();
  append_mm(*head.legacy, p.position_world_m);
  gaze.value = {{"origin", vec_json(p.gaze_origin_world_m)},
                {"direction", vec_json(p.gaze_direction_world)},
                {"roll_deg", p.roll_deg},
                {"yaw_deg", p.yaw_deg},
                {"pitch_deg", p.pitch_deg},
                {"camera", p.camera}};
  gaze.legacy = std::vector<double>{p.gaze_direction_world[0], p.gaze_direction_world[1],
                                    p.gaze_direction_world[2]};
  // Ray-plane intersection; no_data when the ray is parallel to the plane or points away.
  cv::Vec3d n = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
  n /= cv::norm(n);
  const double denom = n.dot(p.gaze_direction_world);
  const double t = std::abs(denom) < 1e-9 ? -1.0 : n.dot(pts[0] - p.gaze_origin_world_m) / denom;
  if (!(t > 0)) {
    plane.status = PrimitiveStatus::kNoData;
    plane.confidence = 0;
    return;
  }
  const cv::Vec3d hit = p.gaze_origin_world_m + t * p.gaze_direction_world;
  plane.value = {{"point_m", vec_json(hit)}, {"distance_m", t}, {"camera", p.camera}};
  plane.legacy.emplace();
  append_mm(*plane.legacy, hit);
}

// F23 trackFace(seed, dt): the face track nearest the seed, predicted dt ahead (constant
// velocity). Default query: the seed is the newest track's position (the child's face).
void Evaluator::evaluate_track_face(const MultiFrame& tick, const BlackboardView& view,
                                    std::vector<PrimitiveRecord>& out) {
  PrimitiveRecord& r = out[static_cast<int>(PrimitiveId::kTrackFace) - 1];
  const auto entry = view.get(keys::kFaceTracks);
  if (entry) r.data_stamp = entry->stamp;
  r.status = observation_status(entry, face_sensors_, tick.stamp);
  if (r.status != PrimitiveStatus::kOk) return;
  const FaceTracks& tracks = *entry->value;
  if (tracks.tracks.empty()) {
    r.status = PrimitiveStatus::kNoData;
    return;
  }
  const FaceTrack& seed_track = tracks.tracks.front();
  const cv::Vec3d seed = seed_track.position_world_m;
  const double dt = options_.track_face_dt_s;
  r.query = {{"seed_m", vec_json(seed)}, {"dt_s", dt}};
  // Prediction from the track's last update to tick + dt.
  const double ahead = dt + (tick.stamp - seed_track.last_update).seconds();
  const cv::Vec3d p = seed_track.position_world_m + ahead * seed_track.velocity_world_mps;
  r.confidence = entry->confidence;
  r.value = {{"position_m", vec_json(p)},
             {"track_id", seed_track.id},
             {"velocity_mps", vec_json(seed_track.velocity_world_mps)}};
  r.legacy.emplace();
  append_mm(*r.legacy, p);
}

// F1 checkMutualGaze, F5 getEyeGaze, F6 getEyes from the gaze analyser (keys::kEyeGaze,
// keys::kMutualGaze) and the eye centres (keys::kEyeCenters).
void Evaluator::evaluate_gaze(const MultiFrame& tick, const BlackboardView& view,
                              std::vector<PrimitiveRecord>& out) {
  PrimitiveRecord& mutual = out[static_cast<int>(PrimitiveId::kCheckMutualGaze) - 1];
  PrimitiveRecord& eye_gaze = out[static_cast<int>(PrimitiveId::kGetEyeGaze) - 1];
  PrimitiveRecord& eyes = out[static_cast<int>(PrimitiveId::kGetEyes) - 1];

  const auto m = view.get(keys::kMutualGaze);
  mutual.status = observation_status(m, face_sensors_, tick.stamp);
  if (m) mutual.data_stamp = m->stamp;
  if (mutual.status == PrimitiveStatus::kOk) {
    const MutualGaze& g = *m->value;
    mutual.confidence = m->confidence;
    mutual.value = {{"mutual", g.mutual}, {"held_s", g.held_s},
                    {"target", g.target}, {"raw", g.raw},
                    {"mode", g.mode},     {"miss_distance_m", g.miss_distance_m}};
    mutual.legacy = std::vector<double>{g.mutual ? 1.0 : 0.0};
  } else if (mutual.status == PrimitiveStatus::kNoData) {
    mutual.legacy = std::vector<double>{-1.0};  // DREAM: no face
  }

  const auto g = view.get(keys::kEyeGaze);
  eye_gaze.status = observation_status(g, face_sensors_, tick.stamp);
  if (g) eye_gaze.data_stamp = g->stamp;
  if (eye_gaze.status == PrimitiveStatus::kOk) {
    const EyeGaze& e = *g->value;
    eye_gaze.confidence = g->confidence;
    eye_gaze.source = e.camera;
    eye_gaze.query = {{"eye", "both"}};
    eye_gaze.value = {{"origin", vec_json(e.both.origin_world_m)},
                      {"direction", vec_json(e.both.direction_world)},
                      {"theta_deg", e.both.theta_deg},
                      {"phi_deg", e.both.phi_deg},
                      {"camera", e.camera},
                      {"method", e.method},
                      {"right", ray_json(e.right)},
                      {"left", ray_json(e.left)}};
    eye_gaze.legacy = std::vector<double>{e.both.direction_world[0], e.both.direction_world[1],
                                          e.both.direction_world[2],
                                          static_cast<double>(dream_camera_id(e.camera))};
  }

  // getEyes: 2-D centres from the eye-centre locator; 3-D positions from the gaze rays' origins
  // (head pose + half the interpupillary distance), so only with a gaze.
  const auto c = view.get(keys::kEyeCenters);
  eyes.status = observation_status(c, face_sensors_, tick.stamp);
  if (c) eyes.data_stamp = c->stamp;
  if (eyes.status != PrimitiveStatus::kOk) return;
  const EyeCenters& ec = *c->value;
  if (!ec.right.found && !ec.left.found) {
    eyes.status = PrimitiveStatus::kNoData;  // e.g. closed eyes
    return;
  }
  auto px = [](const EyeCenter& e) {
    return e.found ? json::array({e.center_px.x, e.center_px.y}) : json(nullptr);
  };
  const bool have_3d = eye_gaze.status == PrimitiveStatus::kOk && g->stamp == c->stamp;
  auto pos = [&](const GazeRay& r) { return have_3d ? vec_json(r.origin_world_m) : json(nullptr); };
  eyes.confidence = c->confidence;
  eyes.source = ec.camera;
  eyes.value = {{"camera", ec.camera},
                {"right_px", px(ec.right)},
                {"left_px", px(ec.left)},
                {"right_m", have_3d ? pos(g->value->right) : json(nullptr)},
                {"left_m", have_3d ? pos(g->value->left) : json(nullptr)},
                {"method", ec.method}};
  if (have_3d && g->value->right.valid && g->value->left.valid) {
    eyes.legacy.emplace();
    append_mm(*eyes.legacy, g->value->left.origin_world_m);  // DREAM: left first
    append_mm(*eyes.legacy, g->value->right.origin_world_m);
  }
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
