#include "dreamsense/primitives/catalogue.hpp"

namespace dreamsense::primitives {

const std::array<PrimitiveInfo, kPrimitiveCount>& catalogue() {
  using P = PrimitiveId;
  static const std::array<PrimitiveInfo, kPrimitiveCount> kTable = {{
      {P::kCheckMutualGaze, "F1", "checkMutualGaze", "checkMutualGaze:o", false},
      {P::kGetArmAngle, "F2", "getArmAngle", "getArmAngle:o", false},
      {P::kGetBody, "F3", "getBody", "getBody:o", false},
      {P::kGetBodyPose, "F4", "getBodyPose", "getBodyPose:o", false},
      {P::kGetEyeGaze, "F5", "getEyeGaze", "getEyeGaze:o", true},
      {P::kGetEyes, "F6", "getEyes", "getEyes:o", false},
      {P::kGetFaces, "F7", "getFaces", "getFaces:o", false},
      {P::kGetGripLocation, "F8", "getGripLocation", "getGripLocation:o", true},
      {P::kGetHands, "F9", "getHands", "getHands:o", false},
      {P::kGetHead, "F10", "getHead", "getHead:o", false},
      {P::kGetHeadGaze, "F11", "getHeadGaze", "getHeadGaze:o", false},
      {P::kGetHeadGazePlane, "F12", "getHeadGaze (plane)", "getHeadGaze:o", true},
      {P::kGetObjects, "F13", "getObjects", "getObjects:o", false},
      {P::kGetObjectsCircle, "F14", "getObjects (circle)", "getObjects:o", true},
      {P::kGetObjectTableDistance, "F15", "getObjectTableDistance", "getObjectTableDistance:o",
       true},
      {P::kGetSoundDirection, "F16", "getSoundDirection", "getSoundDirection:o", true},
      {P::kIdentifyFace, "F17", "identifyFace", "identifyFace:o", true},
      {P::kIdentifyFaceExpression, "F18", "identifyFaceExpression", "identifyFaceExpression:o",
       true},
      {P::kIdentifyObject, "F19", "identifyObject", "identifyObject:o", true},
      {P::kIdentifyTrajectory, "F20", "identifyTrajectory", "identifyTrajectory:o", true},
      {P::kIdentifyVoice, "F21", "identifyVoice", "identifyVoice:o", false},
      {P::kRecognizeSpeech, "F22", "recognizeSpeech", "recognizeSpeech:o", false},
      {P::kTrackFace, "F23", "trackFace", "trackFace:o", true},
      {P::kTrackHand, "F24", "trackHand", "trackHand:o", true},
      {P::kTrackObject, "F25", "trackObject", "trackObject:o", true},
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

nlohmann::json to_json(const PrimitiveRecord& r) {
  const PrimitiveInfo& i = info(r.id);
  nlohmann::json j;
  j["stamp_ns"] = r.stamp.ns();
  j["primitive"] = i.name;
  j["id"] = i.code;
  j["status"] = to_string(r.status);
  j["confidence"] = r.confidence ? nlohmann::json(*r.confidence) : nlohmann::json(nullptr);
  j["value"] = r.value;
  j["legacy"] = r.legacy_text ? nlohmann::json::array({*r.legacy_text})
                : r.legacy    ? nlohmann::json(*r.legacy)
                              : nlohmann::json(nullptr);
  j["source"] = r.source.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.source);
  if (r.data_stamp.is_set()) j["data_stamp_ns"] = r.data_stamp.ns();
  if (!r.query.is_null()) j["query"] = r.query;
  return j;
}

}  // namespace dreamsense::primitives
