#pragma once
// The 25 perception primitives (D4.2 Table 1; ../shared/spec/primitives.md) and record statuses.

#include "dreamsense/core/timestamp.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::primitives {

enum class PrimitiveId : int {
  kCheckMutualGaze = 1,
  kGetArmAngle,
  kGetBody,
  kGetBodyPose,
  kGetEyeGaze,
  kGetEyes,
  kGetFaces,
  kGetGripLocation,
  kGetHands,
  kGetHead,
  kGetHeadGaze,
  kGetHeadGazePlane,
  kGetObjects,
  kGetObjectsCircle,
  kGetObjectTableDistance,
  kGetSoundDirection,
  kIdentifyFace,
  kIdentifyFaceExpression,
  kIdentifyObject,
  kIdentifyTrajectory,
  kIdentifyVoice,
  kRecognizeSpeech,
  kTrackFace,
  kTrackHand,
  kTrackObject,
};
inline constexpr int kPrimitiveCount = 25;

struct PrimitiveInfo {
  PrimitiveId id;
  const char* code;   // "F1"
  const char* name;   // as in the contract table, e.g. "getHeadGaze (plane)"
  const char* port;   // DREAM YARP port short name, e.g. "getHeadGaze:o"
  bool parametrised;  // takes query parameters (evaluated with the configured default query)
};

const std::array<PrimitiveInfo, kPrimitiveCount>& catalogue();
const PrimitiveInfo& info(PrimitiveId id);

enum class PrimitiveStatus { kOk, kNoData, kStale, kSensorOffline, kDisabled };
const char* to_string(PrimitiveStatus s);

// One answer of one primitive at one tick (a line of primitives.jsonl).
struct PrimitiveRecord {
  Timestamp stamp;  // the tick
  PrimitiveId id;
  PrimitiveStatus status = PrimitiveStatus::kDisabled;
  std::optional<double> confidence;
  nlohmann::json value;                       // null unless status is ok
  std::optional<std::vector<double>> legacy;  // DREAM layout, only when ok (or DREAM's "no face")
  std::optional<std::string> legacy_text;     // DREAM strings (recognizeSpeech's tag) instead
  std::string source;                         // sensor that produced the data, empty if none
  Timestamp data_stamp;                       // stamp of the observation used (unset if none)
  nlohmann::json query;  // parameters of parametrised primitives (null otherwise)
};

nlohmann::json to_json(const PrimitiveRecord& r);

}  // namespace dreamsense::primitives
