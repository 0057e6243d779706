#pragma once
// The 25 perception primitives (D4.2 Table 1; ../shared/spec/primitives.md) and record statuses.

#include "dreamsense/core/timestamp.hpp"
#include "dreamsense/primitives/values.hpp"

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
  bool parametrised;  // takes query parameters (evaluated with the configured default query)
};

const std::array<PrimitiveInfo, kPrimitiveCount>& catalogue();
const PrimitiveInfo& info(PrimitiveId id);

std::optional<PrimitiveId> primitive_from_name(std::string_view name);  // name or code ("F12")

enum class PrimitiveStatus { kOk, kNoData, kStale, kSensorOffline, kDisabled };
const char* to_string(PrimitiveStatus s);
std::optional<PrimitiveStatus> status_from_string(std::string_view s);

// One answer of one primitive at one tick (a line of primitives.jsonl). Typed: the value is the
// primitive's own type (values.hpp), monostate unless status is ok; the query is the one that was
// answered (monostate for unparametrised primitives). JSON, CSV, DDS and DREAM's legacy vectors
// are made from it at the edge (export/, publish/, dream/).
struct PrimitiveRecord {
  Timestamp stamp;  // the tick
  PrimitiveId id = PrimitiveId::kCheckMutualGaze;
  PrimitiveStatus status = PrimitiveStatus::kDisabled;
  std::optional<double> confidence;
  PrimitiveValue value;
  PrimitiveQuery query;
  std::string source;    // sensor that produced the data, empty if none
  Timestamp data_stamp;  // stamp of the observation used (unset if none)
  bool ok() const { return status == PrimitiveStatus::kOk; }
  // The value as V, or null when the record holds another type (or none).
  template <typename V>
  const V* value_as() const {
    return std::get_if<V>(&value);
  }
};

}  // namespace dreamsense::primitives
