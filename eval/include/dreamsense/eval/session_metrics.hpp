#pragma once
// `eval session` metrics, one group per modality (eval/src/session/<group>.cpp), each declaring
// the metrics it computes and the primitive each needs. A group reads the analysis as typed
// primitive records and the session's truth.jsonl; a metric whose primitive is disabled, or that
// the truth does not cover, is null with the reason under "not_evaluated". A new analyser adds
// its group's file and one line to the table in session_eval.cpp.

#include "dreamsense/primitives/catalogue.hpp"

#include <nlohmann/json.hpp>

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace dreamsense::eval {

struct SessionData {
  std::vector<nlohmann::json> truth;                 // truth.jsonl records
  std::vector<primitives::PrimitiveRecord> records;  // primitives.jsonl, typed
  // Records of one primitive, in file order.
  std::vector<const primitives::PrimitiveRecord*> of(primitives::PrimitiveId id) const;
  // Truth records of one type ("face", "speech", ...).
  std::vector<const nlohmann::json*> truth_of(const std::string& type) const;
  bool enabled(primitives::PrimitiveId id) const;  // some record is not `disabled`
};

struct MetricGroup {
  std::string name;
  // Each metric with the primitive it needs (null and "disabled" when that one is).
  std::vector<std::pair<std::string, primitives::PrimitiveId>> metrics;
  // Fills `metrics` (numbers) and `not_evaluated` (metric -> reason) for its own metrics.
  std::function<void(const SessionData&, nlohmann::json& metrics, nlohmann::json& not_evaluated)>
      compute;
};

// The groups of each modality (session/*.cpp).
MetricGroup body_metrics();
MetricGroup sound_direction_metrics();
MetricGroup face_detection_metrics();
MetricGroup head_and_gaze_metrics();
MetricGroup speech_metrics();
MetricGroup speaker_metrics();
MetricGroup robot_voice_metrics();
MetricGroup face_recognition_metrics();  // faces (issue 12): F17, F18 (session/faces.cpp)
// Declared for the analysers being added (issues 13, 14); they fill in their computations.
MetricGroup action_metrics();
MetricGroup object_metrics();

// Small helpers shared by the groups.
double angle_between_deg(const cv::Vec3d& a, const cv::Vec3d& b);
cv::Vec3d truth_vec3(const nlohmann::json& a);             // [x, y, z]
cv::Matx33d truth_rotation(const nlohmann::json& record);  // yaw_deg, pitch_deg, roll_deg

}  // namespace dreamsense::eval
