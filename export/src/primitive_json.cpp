#include "dreamsense/export/primitive_json.hpp"

#include "dreamsense/dream/legacy.hpp"

#include <cmath>
#include <fstream>

namespace dreamsense::exporters {
namespace {
using namespace primitives;
using nlohmann::json;

json vec(const cv::Vec3d& v) { return json::array({v[0], v[1], v[2]}); }
json opt_vec(const std::optional<cv::Vec3d>& v) { return v ? vec(*v) : json(nullptr); }
json rect(const cv::Rect2d& b) { return json::array({b.x, b.y, b.width, b.height}); }
json ray(const EyeRay& r) {
  return {{"origin", vec(r.origin_m)},
          {"direction", vec(r.direction)},
          {"theta_deg", r.theta_deg},
          {"phi_deg", r.phi_deg},
          {"offset", json::array({r.offset[0], r.offset[1]})}};
}
json arm(const std::optional<ArmAngle>& a) {
  if (!a) return nullptr;
  return {{"azimuth_deg", a->azimuth_deg}, {"elevation_deg", a->elevation_deg}};
}

struct ValueJson {
  PrimitiveId id;
  json operator()(const std::monostate&) const { return nullptr; }
  json operator()(const MutualGazeValue& v) const {
    return {{"mutual", v.mutual}, {"held_s", v.held_s}, {"target", v.target},
            {"raw", v.raw},       {"mode", v.mode},     {"miss_distance_m", v.miss_distance_m}};
  }
  json operator()(const ArmAnglesValue& v) const {
    return {{"left", arm(v.left)}, {"right", arm(v.right)}};
  }
  json operator()(const BodyValue& v) const {
    return {{"position_m", vec(v.position_m)}, {"bodies_in_view", v.bodies_in_view}};
  }
  json operator()(const BodyPoseValue& v) const {
    json joints = json::object();
    for (const auto& j : v.joints)
      joints[std::string(joint_name(j.joint))] = {{"position_m", vec(j.position_m)},
                                                  {"confidence", j.confidence}};
    return {{"joints", joints}};
  }
  json operator()(const EyeGazeValue& v) const {
    return {{"origin", vec(v.both.origin_m)},
            {"direction", vec(v.both.direction)},
            {"theta_deg", v.both.theta_deg},
            {"phi_deg", v.both.phi_deg},
            {"camera", v.camera},
            {"method", v.method},
            {"fixation_yaw_deg", v.fixation_yaw_deg},
            {"right", v.right ? ray(*v.right) : json(nullptr)},
            {"left", v.left ? ray(*v.left) : json(nullptr)}};
  }
  json operator()(const EyesValue& v) const {
    auto px = [](const std::optional<cv::Point2d>& p) {
      return p ? json::array({p->x, p->y}) : json(nullptr);
    };
    return {{"camera", v.camera},          {"right_px", px(v.right_px)},
            {"left_px", px(v.left_px)},    {"right_m", opt_vec(v.right_m)},
            {"left_m", opt_vec(v.left_m)}, {"method", v.method}};
  }
  json operator()(const FacesValue& v) const {
    json faces = json::array();
    for (const auto& f : v.faces) {
      json boxes = json::object();
      for (const auto& [cam, b] : f.boxes) boxes[cam] = rect(b);
      faces.push_back({{"position_m", vec(f.position_m)},
                       {"score", f.score},
                       {"camera", f.camera},
                       {"boxes", boxes}});
    }
    json cameras = json::object();
    for (const auto& [cam, list] : v.cameras) {
      json l = json::array();
      for (const auto& d : list)
        l.push_back(
            {{"box_px", rect(d.box_px)}, {"score", d.score}, {"frontalness", d.frontalness}});
      cameras[cam] = l;
    }
    return {{"faces", faces},
            {"cameras", cameras},
            {"selected_camera", v.selected_camera ? json(*v.selected_camera) : json(nullptr)}};
  }
  json operator()(const GripLocationValue& v) const {
    return {{"position_m", vec(v.position_m)},
            {"approach_direction", vec(v.approach_direction)},
            {"width_m", v.width_m},
            {"object_id", v.object_id},
            {"closing_axis", vec(v.closing_axis)},
            {"track_id", v.track_id}};
  }
  json operator()(const HandsValue& v) const {
    return {{"left", opt_vec(v.left)}, {"right", opt_vec(v.right)}};
  }
  json operator()(const HeadValue& v) const {
    return {{"position_m", vec(v.position_m)}, {"camera", v.camera}};
  }
  json operator()(const HeadGazeValue& v) const {
    return {{"origin", vec(v.origin_m)}, {"direction", vec(v.direction)}, {"roll_deg", v.roll_deg},
            {"yaw_deg", v.yaw_deg},      {"pitch_deg", v.pitch_deg},      {"camera", v.camera}};
  }
  json operator()(const HeadGazePlaneValue& v) const {
    return {{"point_m", vec(v.point_m)}, {"distance_m", v.distance_m}, {"camera", v.camera}};
  }
  json operator()(const ObjectsValue& v) const {
    json objects = json::array();
    for (const auto& o : v.objects)
      objects.push_back({{"id", o.id},
                         {"label", o.label},
                         {"position_m", vec(o.position_m)},
                         {"score", o.score},
                         {"track_id", o.track_id},
                         {"box_px", rect(o.box_px)},
                         {"detected", o.detected}});
    return {{"objects", objects}};
  }
  json operator()(const ObjectIdentityValue& v) const {
    return {{"id", v.id}, {"label", v.label}, {"score", v.score}, {"track_id", v.track_id}};
  }
  json operator()(const ObjectTableDistanceValue& v) const {
    return {{"distance_m", v.distance_m},
            {"object_id", v.object_id},
            {"lift_m", v.lift_m},
            {"measured", v.measured},
            {"track_id", v.track_id}};
  }
  json operator()(const SoundDirectionValue& v) const {
    return {{"azimuth_deg", v.azimuth_deg},
            {"elevation_deg", v.elevation_deg ? json(*v.elevation_deg) : json(nullptr)},
            {"confidence", v.confidence},
            {"direction", vec(v.direction)}};
  }
  json operator()(const FaceIdentityValue& v) const {
    return {{"id", v.id}, {"name", v.name}, {"score", v.score}};
  }
  json operator()(const ClassLabelValue& v) const {
    return {{"label", v.label}, {"id", v.id}, {"scores", v.scores}};
  }
  json operator()(const VoiceValue& v) const {
    return {{"speaker_id", v.speaker_id}, {"name", v.name},     {"score", v.score},
            {"start_ns", v.start_ns},     {"end_ns", v.end_ns}, {"method", v.method}};
  }
  json operator()(const SpeechValue& v) const {
    return {{"text", v.text},
            {"tag", v.tag},
            {"confidence", v.confidence},
            {"start_ns", v.start_ns},
            {"end_ns", v.end_ns}};
  }
  json operator()(const TrackValue& v) const {
    if (id == PrimitiveId::kTrackHand)
      return {{"position_m", vec(v.position_m)},
              {"velocity_mps", vec(v.velocity_mps)},
              {"hand", v.hand},
              {"samples", v.samples}};
    return {{"position_m", vec(v.position_m)},
            {"track_id", v.track_id},
            {"velocity_mps", vec(v.velocity_mps)}};
  }
};

struct QueryJson {
  json operator()(const std::monostate&) const { return nullptr; }
  json operator()(const EyeQuery& q) const { return {{"eye", q.eye}}; }
  json operator()(const PlaneQuery& q) const {
    return {{"p1", vec(q.points[0])}, {"p2", vec(q.points[1])}, {"p3", vec(q.points[2])}};
  }
  json operator()(const CircleQuery& q) const {
    return {{"centre_m", vec(q.centre_m)}, {"radius_m", q.radius_m}};
  }
  json operator()(const PositionQuery& q) const { return {{"position_m", opt_vec(q.position_m)}}; }
  json operator()(const ThresholdQuery& q) const { return {{"threshold", q.threshold}}; }
  json operator()(const WindowQuery& q) const { return {{"window_s", q.window_s}}; }
  json operator()(const TrackQuery& q) const {
    return {{"seed_m", vec(q.seed_m)}, {"dt_s", q.dt_s}};
  }
};

// ---- reading ----

cv::Vec3d vec3(const json& j) {
  if (!j.is_array() || j.size() != 3) throw std::invalid_argument("expected [x, y, z]");
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}
std::optional<cv::Vec3d> opt_vec3(const json& j) {
  if (j.is_null()) return std::nullopt;
  return vec3(j);
}
cv::Rect2d rect2d(const json& j) {
  if (!j.is_array() || j.size() != 4) throw std::invalid_argument("expected [x, y, w, h]");
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>(), j[3].get<double>()};
}
EyeRay eye_ray(const json& j) {
  EyeRay r;
  r.origin_m = vec3(j.at("origin"));
  r.direction = vec3(j.at("direction"));
  r.theta_deg = j.at("theta_deg").get<double>();
  r.phi_deg = j.at("phi_deg").get<double>();
  if (j.contains("offset"))
    r.offset = {j["offset"].at(0).get<double>(), j["offset"].at(1).get<double>()};
  return r;
}
std::optional<ArmAngle> arm_angle(const json& j) {
  if (j.is_null()) return std::nullopt;
  return ArmAngle{j.at("azimuth_deg").get<double>(), j.at("elevation_deg").get<double>()};
}

PrimitiveValue parse_value(PrimitiveId id, const json& v) {
  using P = PrimitiveId;
  switch (id) {
    case P::kCheckMutualGaze:
      return MutualGazeValue{v.at("mutual").get<bool>(),      v.at("raw").get<bool>(),
                             v.at("held_s").get<double>(),    v.at("miss_distance_m").get<double>(),
                             v.at("mode").get<std::string>(), v.at("target").get<std::string>()};
    case P::kGetArmAngle:
      return ArmAnglesValue{arm_angle(v.at("left")), arm_angle(v.at("right"))};
    case P::kGetBody:
      return BodyValue{vec3(v.at("position_m")), v.at("bodies_in_view").get<int>()};
    case P::kGetBodyPose: {
      BodyPoseValue b;
      for (int i = 0; i < kDreamJointCount; ++i) {
        const auto joint = static_cast<JointId>(i);
        const json& j = v.at("joints").at(std::string(joint_name(joint)));
        b.joints.push_back({joint, vec3(j.at("position_m")), j.at("confidence").get<float>()});
      }
      return b;
    }
    case P::kGetEyeGaze: {
      EyeGazeValue e;
      e.both = eye_ray(v);
      if (!v.at("right").is_null()) e.right = eye_ray(v["right"]);
      if (!v.at("left").is_null()) e.left = eye_ray(v["left"]);
      e.camera = v.at("camera").get<std::string>();
      e.method = v.at("method").get<std::string>();
      e.fixation_yaw_deg = v.value("fixation_yaw_deg", 0.0);  // written since 2026-12-02
      return e;
    }
    case P::kGetEyes: {
      EyesValue e;
      e.camera = v.at("camera").get<std::string>();
      for (auto [key, out] : {std::pair{"right_px", &e.right_px}, std::pair{"left_px", &e.left_px}})
        if (!v.at(key).is_null())
          *out = cv::Point2d(v[key].at(0).get<double>(), v[key].at(1).get<double>());
      e.right_m = opt_vec3(v.at("right_m"));
      e.left_m = opt_vec3(v.at("left_m"));
      e.right_valid = e.right_m.has_value();
      e.left_valid = e.left_m.has_value();
      e.method = v.at("method").get<std::string>();
      return e;
    }
    case P::kGetFaces: {
      FacesValue f;
      for (const auto& face : v.at("faces")) {
        FaceInWorld w;
        w.position_m = vec3(face.at("position_m"));
        w.score = face.at("score").get<float>();
        w.camera = face.at("camera").get<std::string>();
        for (const auto& [cam, b] : face.at("boxes").items()) w.boxes[cam] = rect2d(b);
        f.faces.push_back(std::move(w));
      }
      for (const auto& [cam, list] : v.at("cameras").items()) {
        auto& out = f.cameras[cam];
        for (const auto& d : list)
          out.push_back({rect2d(d.at("box_px")), d.at("score").get<float>(),
                         d.at("frontalness").get<float>()});
      }
      if (!v.at("selected_camera").is_null())
        f.selected_camera = v["selected_camera"].get<std::string>();
      return f;
    }
    case P::kGetGripLocation: {
      GripLocationValue g{vec3(v.at("position_m")), vec3(v.at("approach_direction")),
                          v.at("width_m").get<double>(), v.at("object_id").get<int>()};
      if (v.contains("closing_axis")) g.closing_axis = vec3(v["closing_axis"]);
      g.track_id = v.value("track_id", -1);
      return g;
    }
    case P::kGetHands:
      return HandsValue{opt_vec3(v.at("left")), opt_vec3(v.at("right"))};
    case P::kGetHead:
      return HeadValue{vec3(v.at("position_m")), v.at("camera").get<std::string>()};
    case P::kGetHeadGaze:
      return HeadGazeValue{vec3(v.at("origin")),
                           vec3(v.at("direction")),
                           v.at("roll_deg").get<double>(),
                           v.at("yaw_deg").get<double>(),
                           v.at("pitch_deg").get<double>(),
                           v.at("camera").get<std::string>()};
    case P::kGetHeadGazePlane:
      return HeadGazePlaneValue{vec3(v.at("point_m")), v.at("distance_m").get<double>(),
                                v.at("camera").get<std::string>()};
    case P::kGetObjects:
    case P::kGetObjectsCircle: {
      ObjectsValue o;
      for (const auto& j : v.at("objects")) {
        ObjectValue ov{j.at("id").get<int>(), j.at("label").get<std::string>(),
                       vec3(j.at("position_m")), j.at("score").get<double>(),
                       j.value("track_id", -1)};
        if (j.contains("box_px")) ov.box_px = rect2d(j["box_px"]);
        ov.detected = j.value("detected", true);
        o.objects.push_back(std::move(ov));
      }
      return o;
    }
    case P::kGetObjectTableDistance:
      return ObjectTableDistanceValue{v.at("distance_m").get<double>(),
                                      v.at("object_id").get<int>(), v.value("lift_m", 0.0),
                                      v.value("measured", false), v.value("track_id", -1)};
    case P::kGetSoundDirection: {
      SoundDirectionValue s;
      s.azimuth_deg = v.at("azimuth_deg").get<double>();
      if (!v.at("elevation_deg").is_null()) s.elevation_deg = v["elevation_deg"].get<double>();
      s.confidence = v.at("confidence").get<double>();
      s.direction = vec3(v.at("direction"));
      return s;
    }
    case P::kIdentifyFace:
      return FaceIdentityValue{v.at("id").get<int>(), v.at("name").get<std::string>(),
                               v.at("score").get<double>()};
    case P::kIdentifyFaceExpression:
    case P::kIdentifyTrajectory:
      return ClassLabelValue{v.at("label").get<std::string>(), v.at("id").get<int>(),
                             v.at("scores").get<std::map<std::string, double>>()};
    case P::kIdentifyObject:
      return ObjectIdentityValue{v.at("id").get<int>(), v.at("label").get<std::string>(),
                                 v.at("score").get<double>(), v.value("track_id", -1)};
    case P::kIdentifyVoice:
      return VoiceValue{v.at("speaker_id").get<std::string>(), v.at("name").get<std::string>(),
                        v.at("score").get<double>(),           v.at("start_ns").get<int64_t>(),
                        v.at("end_ns").get<int64_t>(),         v.at("method").get<std::string>()};
    case P::kRecognizeSpeech:
      return SpeechValue{v.at("text").get<std::string>(), v.at("tag").get<std::string>(),
                         v.at("confidence").get<double>(), v.at("start_ns").get<int64_t>(),
                         v.at("end_ns").get<int64_t>()};
    case P::kTrackFace:
    case P::kTrackHand:
    case P::kTrackObject: {
      TrackValue t;
      t.position_m = vec3(v.at("position_m"));
      t.velocity_mps = vec3(v.at("velocity_mps"));
      t.track_id = v.value("track_id", -1);
      t.hand = v.value("hand", "");
      t.samples = v.value("samples", 0);
      return t;
    }
  }
  return std::monostate{};
}

PrimitiveQuery parse_query(PrimitiveId id, const json& q) {
  using P = PrimitiveId;
  switch (id) {
    case P::kGetEyeGaze:
      return EyeQuery{q.at("eye").get<std::string>()};
    case P::kGetHeadGazePlane:
      return PlaneQuery{{vec3(q.at("p1")), vec3(q.at("p2")), vec3(q.at("p3"))}};
    case P::kGetObjectsCircle:
      return CircleQuery{vec3(q.at("centre_m")), q.at("radius_m").get<double>()};
    case P::kGetGripLocation:
    case P::kGetObjectTableDistance:
    case P::kIdentifyFace:
    case P::kIdentifyFaceExpression:
    case P::kIdentifyObject:
      return PositionQuery{opt_vec3(q.at("position_m"))};
    case P::kGetSoundDirection:
      return ThresholdQuery{q.at("threshold").get<double>()};
    case P::kIdentifyTrajectory:
      return WindowQuery{q.at("window_s").get<double>()};
    case P::kTrackFace:
    case P::kTrackHand:
    case P::kTrackObject:
      return TrackQuery{vec3(q.at("seed_m")), q.at("dt_s").get<double>()};
    default:
      throw std::invalid_argument("this primitive takes no query");
  }
}

}  // namespace

json value_json(const PrimitiveRecord& r) { return std::visit(ValueJson{r.id}, r.value); }

json query_json(const PrimitiveQuery& q) { return std::visit(QueryJson{}, q); }

json to_json(const PrimitiveRecord& r) {
  const PrimitiveInfo& i = info(r.id);
  json j;
  j["stamp_ns"] = r.stamp.ns();
  j["primitive"] = i.name;
  j["id"] = i.code;
  j["status"] = to_string(r.status);
  j["confidence"] = r.confidence ? json(*r.confidence) : json(nullptr);
  j["value"] = r.status == PrimitiveStatus::kOk ? value_json(r) : json(nullptr);
  const auto text = dream::legacy_text(r);
  const auto legacy = dream::legacy_vector(r);
  j["legacy"] = text ? json::array({*text}) : legacy ? json(*legacy) : json(nullptr);
  j["source"] = r.source.empty() ? json(nullptr) : json(r.source);
  if (r.data_stamp.is_set()) j["data_stamp_ns"] = r.data_stamp.ns();
  if (!std::holds_alternative<std::monostate>(r.query)) j["query"] = query_json(r.query);
  return j;
}

Result<PrimitiveRecord> record_from_json(const json& j) {
  PrimitiveRecord r;
  std::string member = "primitive";
  try {
    const auto id = primitive_from_name(j.at("primitive").get<std::string>());
    if (!id)
      return make_error(ErrorCode::kCorruptData, "unknown primitive '{}'",
                        j["primitive"].get<std::string>());
    r.id = *id;
    member = "stamp_ns";
    r.stamp = Timestamp::from_ns(j.at("stamp_ns").get<int64_t>());
    member = "status";
    const auto status = status_from_string(j.at("status").get<std::string>());
    if (!status)
      return make_error(ErrorCode::kCorruptData, "unknown status '{}'",
                        j["status"].get<std::string>());
    r.status = *status;
    member = "confidence";
    if (j.contains("confidence") && !j["confidence"].is_null())
      r.confidence = j["confidence"].get<double>();
    member = "source";
    if (j.contains("source") && !j["source"].is_null()) r.source = j["source"].get<std::string>();
    member = "data_stamp_ns";
    if (j.contains("data_stamp_ns"))
      r.data_stamp = Timestamp::from_ns(j["data_stamp_ns"].get<int64_t>());
    member = "value";
    if (r.status == PrimitiveStatus::kOk) r.value = parse_value(r.id, j.at("value"));
    member = "query";
    if (j.contains("query") && !j["query"].is_null()) r.query = parse_query(r.id, j["query"]);
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "member '{}' is malformed ({})", member, e.what());
  }
  return r;
}

Result<std::vector<PrimitiveRecord>> read_primitives_jsonl(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot read", path.string());
  std::vector<PrimitiveRecord> out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    json j;
    try {
      j = json::parse(line);
    } catch (const json::exception&) {
      return make_error(ErrorCode::kCorruptData, "{}: line {}: malformed JSON", path.string(), n);
    }
    auto r = record_from_json(j);
    if (!r)
      return make_error(ErrorCode::kCorruptData, "{}: line {}: {}", path.string(), n,
                        r.error().message);
    out.push_back(std::move(*r));
  }
  return out;
}

namespace {
bool all_finite(const nlohmann::json& j) {
  if (j.is_number_float()) return std::isfinite(j.get<double>());
  if (j.is_array() || j.is_object()) {
    for (const auto& v : j)
      if (!all_finite(v)) return false;
  }
  return true;
}
}  // namespace

bool value_is_finite(const primitives::PrimitiveRecord& record) {
  if (record.confidence && !std::isfinite(*record.confidence)) return false;
  return all_finite(value_json(record));
}

}  // namespace dreamsense::exporters
