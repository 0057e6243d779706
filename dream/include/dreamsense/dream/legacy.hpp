#pragma once
// Every DREAM compatibility rule in one place (../shared/spec/primitives.md, original-dream.md):
// the legacy vectors the original YARP ports carried (millimetres, DREAM's layouts and ids), the
// port short names, DREAM's camera ids and label ids. Everything else in dreamsense is typed and
// in SI units; these functions translate at the edge (events.log, primitives.jsonl's "legacy",
// DDS).

#include "dreamsense/primitives/catalogue.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::dream {

// DREAM's camera ids (SelectCameraID): 0 camera_middle, 1 camera_left, 2 camera_right, -1 any
// other stream.
int camera_id(std::string_view camera);

// The YARP port short name of a primitive ("getHeadGaze:o"). DREAM answered F11 and F12 on one
// getHeadGaze port and F13 and F14 on one getObjects port (the parametrised forms were never
// used, original-dream.md 1.10); here they are told apart as getHeadGaze_plane:o and
// getObjects_circle:o (the names of their CSV tables), so an events.log line names its primitive.
const char* port(primitives::PrimitiveId id);

// DREAM's expression ids (identifyFaceExpression): 0 happy, 1 sad, 2 angry, 3 fear, 4 neutral;
// -1 for any other label.
int expression_id(std::string_view label);
// DREAM's identifyTrajectory classes: 0 none, 1 hand wave, 2 hands cover eyes, 3 hands on head,
// 4 fly (arms out), 5 drive car, 6 drink/smell, 7-11 custom trajectories 1-5; -1 otherwise.
// Labels: none, wave, cover_eyes, hands_on_head, fly, drive_car, drink, custom1..custom5.
int trajectory_id(std::string_view label);
// DREAM's toy ids (identifyObject): 0 car, 1 cup, 2 flower, 3 plane; -1 otherwise.
int object_id(std::string_view label);

// The legacy vector of a record, in DREAM's layout (only when the record is ok, except
// checkMutualGaze's [-1] for "no face"); nullopt when DREAM sent nothing.
std::optional<std::vector<double>> legacy_vector(const primitives::PrimitiveRecord& record);
// DREAM's string payload (recognizeSpeech sent the grammar tag), only when ok.
std::optional<std::string> legacy_text(const primitives::PrimitiveRecord& record);

}  // namespace dreamsense::dream
