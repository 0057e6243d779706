#include "dreamsense/dream/writers.hpp"
#include "dreamsense/perception/body.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <fmt/format.h>

#include <ctime>

namespace dreamsense::dream {
namespace {
using nlohmann::json;

// DREAM's joint names (with the format's own spelling "sholder") for our first ten joints.
constexpr std::pair<JointId, const char*> kDreamJoints[] = {
    {JointId::kShoulderCenter, "sholder_center"}, {JointId::kHead, "head"},
    {JointId::kShoulderLeft, "sholder_left"},     {JointId::kElbowLeft, "elbow_left"},
    {JointId::kWristLeft, "wrist_left"},          {JointId::kHandLeft, "hand_left"},
    {JointId::kShoulderRight, "sholder_right"},   {JointId::kElbowRight, "elbow_right"},
    {JointId::kWristRight, "wrist_right"},        {JointId::kHandRight, "hand_right"},
};

std::string iso_utc(int64_t unix_ns) {
  const std::time_t secs = static_cast<std::time_t>(unix_ns / 1'000'000'000LL);
  const int us = static_cast<int>((unix_ns % 1'000'000'000LL) / 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  return fmt::format("{:04d}-{:02d}-{:02d}T{:02d}:{:02d}:{:02d}.{:06d}Z", tm.tm_year + 1900,
                     tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, us);
}

json rot_arrays(const std::vector<DreamExport::Frame>& frames,
                std::optional<cv::Vec3d> DreamExport::Frame::*member) {
  json rx = json::array(), ry = json::array(), rz = json::array();
  for (const auto& f : frames) {
    const auto& v = f.*member;
    if (v) {
      const cv::Vec3d u = *v / cv::norm(*v);
      rx.push_back(u[0]);
      ry.push_back(u[1]);
      rz.push_back(u[2]);
    } else {
      rx.push_back(nullptr);
      ry.push_back(nullptr);
      rz.push_back(nullptr);
    }
  }
  return {{"rx", rx}, {"ry", ry}, {"rz", rz}};
}
}  // namespace

json DreamExport::build(const sources::SessionManifest& m) const {
  json skeleton = json::object();
  for (const auto& [joint, name] : kDreamJoints) {
    json x = json::array(), y = json::array(), z = json::array(), c = json::array();
    for (const auto& f : frames_) {
      if (f.skeleton && f.skeleton->joint(joint).valid()) {
        const auto& j = f.skeleton->joint(joint);
        x.push_back(j.position_m[0] * 1000.0);
        y.push_back(j.position_m[1] * 1000.0);
        z.push_back(j.position_m[2] * 1000.0);
        c.push_back(j.confidence);
      } else {
        x.push_back(nullptr);
        y.push_back(nullptr);
        z.push_back(nullptr);
        c.push_back(nullptr);
      }
    }
    skeleton[name] = {{"x", x}, {"y", y}, {"z", z}, {"confidence", c}};
  }
  json participant = {{"id", m.participant.id}};
  participant["gender"] = m.participant.gender ? json(*m.participant.gender) : json(nullptr);
  participant["ageInMonths"] =
      m.participant.age_months ? json(*m.participant.age_months) : json(nullptr);
  json out;
  out["date"] = iso_utc(m.clock_origin_unix_ns);
  out["condition"] = m.condition.empty() ? json(nullptr) : json(m.condition);
  out["task"] = m.task;
  out["participant"] = participant;
  out["frame_rate"] = m.frame_rate;
  out["eye_gaze"] = rot_arrays(frames_, &Frame::eye_gaze);
  out["head_gaze"] = rot_arrays(frames_, &Frame::head_gaze);
  out["skeleton"] = skeleton;
  // Extra attributes are allowed by the schema; they make the units explicit.
  out["dreamsense"] = {{"session", m.name},
                       {"frames", frames_.size()},
                       {"position_unit", "mm"},
                       {"frame", "world (front sensor optical frame unless calibrated otherwise)"}};
  return out;
}

void DreamExport::add(const BlackboardView& view, Timestamp tick, Duration freshness) {
  Frame f;
  if (auto body = view.get(keys::kChildBody);
      body && body->present() && tick - body->stamp <= freshness)
    f.skeleton = body->value->body;
  if (auto h = view.get(keys::kHeadPose); h && h->present() && tick - h->stamp <= freshness)
    f.head_gaze = h->value->gaze_direction_world;
  if (auto g = view.get(keys::kEyeGaze); g && g->present() && tick - g->stamp <= freshness)
    f.eye_gaze = g->value->both.direction_world;
  add(f);
}

Status DreamExport::write(const std::filesystem::path& path,
                          const sources::SessionManifest& manifest) const {
  OutputFile f;
  if (auto s = f.open(path); !s) return s;
  if (auto s = f.write(build(manifest).dump()); !s) return s;
  return f.commit();
}

}  // namespace dreamsense::dream
