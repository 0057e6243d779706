#include "dreamsense/primitives/catalogue.hpp"

namespace dreamsense::primitives {

const std::array<PrimitiveInfo, kPrimitiveCount>& catalogue() {
  using P = PrimitiveId;
  static const std::array<PrimitiveInfo, kPrimitiveCount> kTable = {{
      {P::kCheckMutualGaze, "F1", "checkMutualGaze", false},
      {P::kGetArmAngle, "F2", "getArmAngle", false},
      {P::kGetBody, "F3", "getBody", false},
      {P::kGetBodyPose, "F4", "getBodyPose", false},
      {P::kGetEyeGaze, "F5", "getEyeGaze", true},
      {P::kGetEyes, "F6", "getEyes", false},
      {P::kGetFaces, "F7", "getFaces", false},
      {P::kGetGripLocation, "F8", "getGripLocation", true},
      {P::kGetHands, "F9", "getHands", false},
      {P::kGetHead, "F10", "getHead", false},
      {P::kGetHeadGaze, "F11", "getHeadGaze", false},
      {P::kGetHeadGazePlane, "F12", "getHeadGaze (plane)", true},
      {P::kGetObjects, "F13", "getObjects", false},
      {P::kGetObjectsCircle, "F14", "getObjects (circle)", true},
      {P::kGetObjectTableDistance, "F15", "getObjectTableDistance", true},
      {P::kGetSoundDirection, "F16", "getSoundDirection", true},
      {P::kIdentifyFace, "F17", "identifyFace", true},
      {P::kIdentifyFaceExpression, "F18", "identifyFaceExpression", true},
      {P::kIdentifyObject, "F19", "identifyObject", true},
      {P::kIdentifyTrajectory, "F20", "identifyTrajectory", true},
      {P::kIdentifyVoice, "F21", "identifyVoice", false},
      {P::kRecognizeSpeech, "F22", "recognizeSpeech", false},
      {P::kTrackFace, "F23", "trackFace", true},
      {P::kTrackHand, "F24", "trackHand", true},
      {P::kTrackObject, "F25", "trackObject", true},
  }};
  return kTable;
}

const PrimitiveInfo& info(PrimitiveId id) { return catalogue()[static_cast<int>(id) - 1]; }

const char* to_string(PrimitiveStatus s) {
  switch (s) {
    case PrimitiveStatus::kOk:
      return "ok";
    case PrimitiveStatus::kNoData:
      return "no_data";
    case PrimitiveStatus::kStale:
      return "stale";
    case PrimitiveStatus::kSensorOffline:
      return "sensor_offline";
    case PrimitiveStatus::kDisabled:
      return "disabled";
  }
  return "unknown";
}

std::optional<PrimitiveId> primitive_from_name(std::string_view name) {
  for (const auto& i : catalogue())
    if (name == i.name || name == i.code) return i.id;
  return std::nullopt;
}

std::optional<PrimitiveStatus> status_from_string(std::string_view s) {
  for (PrimitiveStatus st :
       {PrimitiveStatus::kOk, PrimitiveStatus::kNoData, PrimitiveStatus::kStale,
        PrimitiveStatus::kSensorOffline, PrimitiveStatus::kDisabled})
    if (s == to_string(st)) return st;
  return std::nullopt;
}

}  // namespace dreamsense::primitives
