#include "dreamsense/primitives/face_primitives.hpp"

#include <algorithm>

namespace dreamsense::primitives {

Status FaceGeometryOptions::check() const {
  if (!(face_width_m > 0.05 && face_width_m < 0.5))
    return make_error(ErrorCode::kInvalidArgument,
                      "FaceGeometryOptions: face_width_m must be in (0.05, 0.5) m");
  if (!(same_face_distance_m > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "FaceGeometryOptions: same_face_distance_m must be > 0");
  return ok_status();
}

std::optional<cv::Vec3d> face_position_from_box(const CameraModel& camera, const cv::Rect2d& box,
                                                double face_width_m) {
  if (box.width <= 0 || box.height <= 0) return std::nullopt;
  const cv::Point2d centre(box.x + box.width / 2, box.y + box.height / 2);
  const cv::Vec3d ray = camera.pixel_ray(centre);  // unit, camera frame
  const double distance = camera.K(0, 0) * face_width_m / box.width;
  // `distance` is along the optical axis for a fronto-parallel face: scale the ray to that depth.
  const cv::Vec3d in_camera = ray * (distance / ray[2]);
  return camera.to_world(in_camera);
}

std::vector<FaceObservation> associate_faces(const FaceDetections& detections,
                                             const SelectedCamera* selected,
                                             const std::map<SensorId, CameraModel>& cameras,
                                             const FaceGeometryOptions& options) {
  struct View {
    SensorId camera;
    const DetectedFace* face;
    cv::Vec3d position;
    bool is_selected;
  };
  std::vector<View> views;
  for (const auto& [id, cam_faces] : detections.cameras) {
    auto model = cameras.find(id);
    if (model == cameras.end()) continue;
    for (size_t i = 0; i < cam_faces.faces.size(); ++i) {
      const auto& f = cam_faces.faces[i];
      auto p = face_position_from_box(model->second, f.box_px, options.face_width_m);
      if (!p) continue;
      const bool sel = selected != nullptr && selected->camera == id && selected->face_index == i;
      views.push_back({id, &f, *p, sel});
    }
  }
  // Selected view first, then by score (stable for determinism).
  std::stable_sort(views.begin(), views.end(), [](const View& a, const View& b) {
    if (a.is_selected != b.is_selected) return a.is_selected;
    return a.face->score > b.face->score;
  });
  std::vector<FaceObservation> out;
  std::vector<double> weight;
  for (const View& v : views) {
    FaceObservation* match = nullptr;
    for (size_t k = 0; k < out.size(); ++k) {
      const cv::Vec3d mean = out[k].position_m;
      if (cv::norm(mean - v.position) <= options.same_face_distance_m &&
          out[k].boxes.count(v.camera) == 0) {
        match = &out[k];
        const double w = std::max(1e-3, static_cast<double>(v.face->score));
        match->position_m = (mean * weight[k] + v.position * w) / (weight[k] + w);
        weight[k] += w;
        break;
      }
    }
    if (match == nullptr) {
      out.push_back({v.position, v.face->score, v.camera, {}});
      weight.push_back(std::max(1e-3, static_cast<double>(v.face->score)));
      match = &out.back();
    }
    match->boxes[v.camera] = v.face->box_px;
  }
  return out;
}

}  // namespace dreamsense::primitives
