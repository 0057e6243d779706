#include "dreamsense/face_detection/camera_selection.hpp"

#include <algorithm>

namespace dreamsense::face_detection {

float selection_quality(const DetectedFace& face) {
  return face.frontalness * std::min(1.f, face.score / kConfidentFaceScore);
}

Status CameraSelectorOptions::check() const {
  if (!(switch_margin >= 0 && switch_margin <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "CameraSelectorOptions: switch_margin {} not in [0, 1]", switch_margin);
  if (switch_ticks < 1)
    return make_error(ErrorCode::kInvalidArgument, "CameraSelectorOptions: switch_ticks {} < 1",
                      switch_ticks);
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

std::optional<SelectedCamera> CameraSelector::update(const FaceDetections& detections) {
  // The best face of each camera (by quality), and the best camera overall.
  std::map<SensorId, SelectedCamera> candidates;
  const SelectedCamera* best = nullptr;
  for (const auto& [id, cam] : detections.cameras) {
    for (size_t i = 0; i < cam.faces.size(); ++i) {
      const float q = selection_quality(cam.faces[i]);
      auto it = candidates.find(id);
      if (it == candidates.end() || q > it->second.quality)
        candidates[id] = SelectedCamera{id, i, cam.faces[i], q};
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
  if (best->camera != *current_ &&
      best->quality > current->second.quality + options_.switch_margin) {
    if (challenger_ == best->camera)
      ++challenger_ticks_;
    else {
      challenger_ = best->camera;
      challenger_ticks_ = 1;
    }
    if (challenger_ticks_ >= options_.switch_ticks) {
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

int dream_camera_id(const std::optional<SensorId>& camera) {
  if (!camera) return -1;
  if (*camera == "camera_middle") return 0;
  if (*camera == "camera_left") return 1;
  if (*camera == "camera_right") return 2;
  return -1;
}

}  // namespace dreamsense::face_detection
