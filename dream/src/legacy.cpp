#include "dreamsense/dream/legacy.hpp"

#include <array>

namespace dreamsense::dream {
namespace {
using namespace primitives;

void append_mm(std::vector<double>& out, const cv::Vec3d& v) {
  for (int i = 0; i < 3; ++i) out.push_back(v[i] * 1000.0);
}
std::vector<double> mm(const cv::Vec3d& v) {
  std::vector<double> out;
  append_mm(out, v);
  return out;
}

// One visitor per value type; the record's id disambiguates types that several primitives share.
struct LegacyOf {
  const PrimitiveRecord& r;
  std::optional<std::vector<double>> operator()(const std::monostate&) const { return {}; }
  std::optional<std::vector<double>> operator()(const MutualGazeValue& v) const {
    return std::vector<double>{v.mutual ? 1.0 : 0.0};
  }
  std::optional<std::vector<double>> operator()(const ArmAnglesValue& v) const {
    if (!v.left || !v.right) return {};  // DREAM's four numbers need both arms
    return std::vector<double>{v.left->elevation_deg, v.left->azimuth_deg, v.right->elevation_deg,
                               v.right->azimuth_deg};
  }
  std::optional<std::vector<double>> operator()(const BodyValue& v) const {
    return mm(v.position_m);
  }
  std::optional<std::vector<double>> operator()(const BodyPoseValue& v) const {
    std::vector<double> out;
    for (const auto& j : v.joints) append_mm(out, j.position_m);
    return out;
  }
  std::optional<std::vector<double>> operator()(const EyeGazeValue& v) const {
    return std::vector<double>{v.both.direction[0], v.both.direction[1], v.both.direction[2],
                               static_cast<double>(camera_id(v.camera))};
  }
  std::optional<std::vector<double>> operator()(const EyesValue& v) const {
    if (!v.left_m || !v.right_m || !v.left_valid || !v.right_valid) return {};
    std::vector<double> out;  // DREAM: left eye first
    append_mm(out, *v.left_m);
    append_mm(out, *v.right_m);
    return out;
  }
  std::optional<std::vector<double>> operator()(const FacesValue& v) const {
    std::vector<double> out{static_cast<double>(std::min<size_t>(v.faces.size(), 5))};
    for (size_t i = 0; i < v.faces.size() && i < 5; ++i) append_mm(out, v.faces[i].position_m);
    out.resize(16, 0.0);  // up to 5 faces, unused slots 0
    return out;
  }
  std::optional<std::vector<double>> operator()(const GripLocationValue& v) const {
    return mm(v.position_m);
  }
  std::optional<std::vector<double>> operator()(const HandsValue& v) const {
    if (!v.left || !v.right) return {};
    std::vector<double> out;
    append_mm(out, *v.left);
    append_mm(out, *v.right);
    return out;
  }
  std::optional<std::vector<double>> operator()(const HeadValue& v) const {
    return mm(v.position_m);
  }
  std::optional<std::vector<double>> operator()(const HeadGazeValue& v) const {
    return std::vector<double>{v.direction[0], v.direction[1], v.direction[2]};
  }
  std::optional<std::vector<double>> operator()(const HeadGazePlaneValue& v) const {
    return mm(v.point_m);
  }
  std::optional<std::vector<double>> operator()(const ObjectsValue& v) const {
    std::vector<double> out{static_cast<double>(v.objects.size())};
    for (const auto& o : v.objects) {
      append_mm(out, o.position_m);
      out.push_back(o.id);
    }
    return out;
  }
  std::optional<std::vector<double>> operator()(const ObjectIdentityValue& v) const {
    return std::vector<double>{static_cast<double>(v.id)};
  }
  std::optional<std::vector<double>> operator()(const ObjectTableDistanceValue& v) const {
    return std::vector<double>{v.distance_m * 1000.0};
  }
  std::optional<std::vector<double>> operator()(const SoundDirectionValue& v) const {
    return std::vector<double>{v.azimuth_deg, v.confidence};
  }
  std::optional<std::vector<double>> operator()(const FaceIdentityValue& v) const {
    return std::vector<double>{static_cast<double>(v.id)};
  }
  std::optional<std::vector<double>> operator()(const ClassLabelValue& v) const {
    if (r.id == PrimitiveId::kIdentifyTrajectory) {
      std::vector<double> one_hot(12, 0.0);  // 0 none ... 11 custom 5
      // The value's F20 id (custom gestures carry their own labels, ids 7-11); a label of
      // DREAM's list when the id is not one; all zeros for a class outside DREAM's list.
      const int id = v.id >= 0 && v.id < 12 ? v.id : trajectory_id(v.label);
      if (id >= 0) one_hot[static_cast<size_t>(id)] = 1.0;
      return one_hot;
    }
    return std::vector<double>{static_cast<double>(expression_id(v.label))};
  }
  std::optional<std::vector<double>> operator()(const VoiceValue& v) const {
    return std::vector<double>{v.speaker_id == "child"       ? 1.0
                               : v.speaker_id == "therapist" ? 0.0
                                                             : -1.0};
  }
  std::optional<std::vector<double>> operator()(const SpeechValue&) const { return {}; }
  std::optional<std::vector<double>> operator()(const TrackValue& v) const {
    return mm(v.position_m);
  }
};

}  // namespace

int camera_id(std::string_view camera) {
  if (camera == "camera_middle") return 0;
  if (camera == "camera_left") return 1;
  if (camera == "camera_right") return 2;
  return -1;
}

const char* port(PrimitiveId id) {
  static const std::array<const char*, kPrimitiveCount> kPorts = {
      "checkMutualGaze:o",   "getArmAngle:o",        "getBody:o",
      "getBodyPose:o",       "getEyeGaze:o",         "getEyes:o",
      "getFaces:o",          "getGripLocation:o",    "getHands:o",
      "getHead:o",           "getHeadGaze:o",        "getHeadGaze_plane:o",
      "getObjects:o",        "getObjects_circle:o",  "getObjectTableDistance:o",
      "getSoundDirection:o", "identifyFace:o",       "identifyFaceExpression:o",
      "identifyObject:o",    "identifyTrajectory:o", "identifyVoice:o",
      "recognizeSpeech:o",   "trackFace:o",          "trackHand:o",
      "trackObject:o"};
  return kPorts[static_cast<size_t>(id) - 1];
}

int expression_id(std::string_view label) {
  constexpr std::array<std::string_view, 5> kIds = {"happy", "sad", "angry", "fear", "neutral"};
  for (size_t i = 0; i < kIds.size(); ++i)
    if (label == kIds[i]) return static_cast<int>(i);
  // faces (issue 12): the expression analyser's CK+ spellings of sad and angry.
  if (label == "sadness") return 1;
  if (label == "anger") return 2;
  return -1;
}

int trajectory_id(std::string_view label) {
  constexpr std::array<std::string_view, 12> kIds = {
      "none",  "wave",    "cover_eyes", "hands_on_head", "fly",     "drive_car",
      "drink", "custom1", "custom2",    "custom3",       "custom4", "custom5"};
  for (size_t i = 0; i < kIds.size(); ++i)
    if (label == kIds[i]) return static_cast<int>(i);
  return -1;
}

int object_id(std::string_view label) {
  constexpr std::array<std::string_view, 4> kIds = {"car", "cup", "flower", "plane"};
  for (size_t i = 0; i < kIds.size(); ++i)
    if (label == kIds[i]) return static_cast<int>(i);
  return -1;
}

std::optional<std::vector<double>> legacy_vector(const PrimitiveRecord& r) {
  if (r.status == PrimitiveStatus::kNoData && r.id == PrimitiveId::kCheckMutualGaze)
    return std::vector<double>{-1.0};  // DREAM: no face
  if (r.status != PrimitiveStatus::kOk) return std::nullopt;
  return std::visit(LegacyOf{r}, r.value);
}

std::optional<std::string> legacy_text(const PrimitiveRecord& r) {
  if (r.status != PrimitiveStatus::kOk) return std::nullopt;
  if (const auto* s = r.value_as<SpeechValue>()) return s->tag;
  return std::nullopt;
}

}  // namespace dreamsense::dream
