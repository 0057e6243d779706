#include "dreamsense/face_detection/camera_selection.hpp"

#include "dreamsense/perception/face_detection.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::face_detection {

float selection_quality(const DetectedFace& face) {
  return face.frontalness * std::min(1.f, face.score / kConfidentFaceScore);
}

float frontalness_from_yaw(double yaw_deg) {
  return static_cast<float>(std::clamp(1.0 - std::abs(yaw_deg) / 90.0, 0.0, 1.0));
}

float selection_quality_from_yaw(const DetectedFace& /*face*/, double yaw_deg) {
  // D4.2: the smallest yaw wins. The detection score is left out: it counts cascade windows,
  // which depend on the search (ROI searches run coarser), and only the face holding the
  // projected head gets a yaw, so it is the tracked face, not a stray detection.
  return frontalness_from_yaw(yaw_deg);
}

Status CameraSelectorOptions::check() const {
  if (!(switch_margin >= 0 && switch_margin <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "CameraSelectorOptions: switch_margin {} not in [0, 1]", switch_margin);
  if (!(yaw_switch_margin >= 0 && yaw_switch_margin <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "CameraSelectorOptions: yaw_switch_margin {} not in [0, 1]",
                      yaw_switch_margin);
  if (switch_ticks < 1 || yaw_switch_ticks < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "CameraSelectorOptions: switch_ticks {} / yaw_switch_ticks {} < 1",
                      switch_ticks, yaw_switch_ticks);
  return ok_status();
}

CameraSelector::CameraSelector(CameraSelectorOptions options) : options_(std::move(options)) {
  DS_CHECK(options_.check().has_value());
}

void CameraSelector::reset() {
  current_.reset();
  challenger_.reset();
  challenger_ticks_ = 0;
}

std::optional<SelectedCamera> CameraSelector::update(const FaceDetections& detections,
                                                     const std::vector<HeadYawHint>& yaw_hints) {
  // The best face of each camera (by quality), and the best camera overall.
  std::map<SensorId, SelectedCamera> candidates;
  std::map<SensorId, bool> rated_by_yaw;
  const SelectedCamera* best = nullptr;
  for (const auto& [id, cam] : detections.cameras) {
    for (size_t i = 0; i < cam.faces.size(); ++i) {
      const DetectedFace& face = cam.faces[i];
      float q = selection_quality(face);
      bool by_yaw = false;
      for (const auto& h : yaw_hints)
        if (h.camera == id && h.face_box_px == face.box_px) {
          q = selection_quality_from_yaw(face, h.yaw_deg);
          by_yaw = true;
        }
      auto it = candidates.find(id);
      if (it == candidates.end() || q > it->second.quality) {
        candidates[id] = SelectedCamera{id, i, face, q};
        rated_by_yaw[id] = by_yaw;
      }
    }
  }
  for (const auto& [id, c] : candidates)
    if (best == nullptr || c.quality > best->quality) best = &c;
  if (best == nullptr) {
    reset();
    return std::nullopt;
  }
  auto current = current_ ? candidates.find(*current_) : candidates.end();
  if (current == candidates.end()) {  // nothing selected, or the selected camera lost its face
    current_ = best->camera;
    challenger_.reset();
    challenger_ticks_ = 0;
    return *best;
  }
  const bool both_by_yaw = rated_by_yaw[best->camera] && rated_by_yaw[*current_];
  const double margin = both_by_yaw ? options_.yaw_switch_margin : options_.switch_margin;
  const int ticks = both_by_yaw ? options_.yaw_switch_ticks : options_.switch_ticks;
  if (best->camera != *current_ && best->quality > current->second.quality + margin) {
    if (challenger_ == best->camera)
      ++challenger_ticks_;
    else {
      challenger_ = best->camera;
      challenger_ticks_ = 1;
    }
    if (challenger_ticks_ >= ticks) {
      current_ = best->camera;
      challenger_.reset();
      challenger_ticks_ = 0;
      return *best;
    }
  } else {
    challenger_.reset();
    challenger_ticks_ = 0;
  }
  return current->second;
}

}  // namespace dreamsense::face_detection
