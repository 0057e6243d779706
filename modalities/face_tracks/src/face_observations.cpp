#include "dreamsense/face_tracks/face_observations.hpp"

#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <algorithm>
#include <string>

namespace dreamsense::face_tracks {

Status FaceObservationOptions::check() const {
  std::string bad;
  if (!(face_width_m > 0)) bad += " face_width_m must be > 0;";
  if (!(merge_distance_m >= 0)) bad += " merge_distance_m must be >= 0;";
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "FaceObservationOptions:{}", bad);
  return ok_status();
}

std::optional<cv::Vec3d> position_from_box(const cv::Rect2d& box_px, const cv::Size& image_size,
                                           const CameraModel& camera, double face_width_m) {
  if (!(box_px.width > 0) || !(box_px.height > 0)) return std::nullopt;
  // Boxes refer to the frame's size; the model may have been calibrated at another resolution.
  double sx = 1, sy = 1;
  if (image_size.width > 0 && image_size.height > 0 && image_size != camera.image_size) {
    sx = static_cast<double>(camera.image_size.width) / image_size.width;
    sy = static_cast<double>(camera.image_size.height) / image_size.height;
  }
  const cv::Point2d centre((box_px.x + box_px.width / 2) * sx, (box_px.y + box_px.height / 2) * sy);
  const double depth_m = camera.K(0, 0) * face_width_m / (box_px.width * sx);
  const cv::Vec3d ray = camera.pixel_ray(centre);
  if (!(ray[2] > 0)) return std::nullopt;
  return camera.to_world(ray * (depth_m / ray[2]));
}

namespace {

struct Raw {
  FaceView3d view;
  cv::Vec3d position;
  bool from_head_pose = false;
  float score = 0.f;
};

// The face of `head`'s camera whose box holds the projected head position (smallest such box).
std::optional<size_t> face_holding_head(const CameraFaces& faces, const HeadPose& head,
                                        const CameraModel& camera) {
  const auto px = camera.project(head.position_world_m);
  if (!px) return std::nullopt;
  double sx = 1, sy = 1;
  if (faces.image_size.width > 0 && faces.image_size.height > 0 &&
      faces.image_size != camera.image_size) {
    sx = static_cast<double>(faces.image_size.width) / camera.image_size.width;
    sy = static_cast<double>(faces.image_size.height) / camera.image_size.height;
  }
  const cv::Point2d p(px->x * sx, px->y * sy);
  std::optional<size_t> best;
  for (size_t i = 0; i < faces.faces.size(); ++i) {
    const cv::Rect2d& b = faces.faces[i].box_px;
    if (!b.contains(p)) continue;
    if (!best || b.area() < faces.faces[*best].box_px.area()) best = i;
  }
  return best;
}

}  // namespace

Result<std::vector<FaceObservation3d>> face_observations(
    const FaceDetections& detections, const SelectedCamera* selected, const HeadPose* head,
    const std::map<SensorId, CameraModel>& cameras, const FaceObservationOptions& options) {
  // Which face the head pose belongs to.
  std::optional<FaceView3d> head_view;
  if (head != nullptr) {
    const auto det = detections.cameras.find(head->camera);
    if (det != detections.cameras.end()) {
      if (selected != nullptr && selected->camera == head->camera &&
          selected->face_index < det->second.faces.size()) {
        head_view = FaceView3d{head->camera, selected->face_index};
      } else {
        const auto cam = cameras.find(head->camera);
        if (cam == cameras.end())
          return make_error(ErrorCode::kNotFound, "face_tracks: no camera model for '{}'",
                            head->camera);
        if (auto i = face_holding_head(det->second, *head, cam->second))
          head_view = FaceView3d{head->camera, *i};
      }
    }
  }

  std::vector<Raw> raw;
  for (const auto& [id, faces] : detections.cameras) {
    if (faces.faces.empty()) continue;
    const auto cam = cameras.find(id);
    if (cam == cameras.end())
      return make_error(ErrorCode::kNotFound, "face_tracks: no camera model for '{}'", id);
    for (size_t i = 0; i < faces.faces.size(); ++i) {
      const DetectedFace& f = faces.faces[i];
      if (head_view && head_view->camera == id && head_view->face_index == i) {
        raw.push_back({{id, i}, head->position_world_m, true, f.score});
        continue;
      }
      if (auto p = position_from_box(f.box_px, faces.image_size, cam->second, options.face_width_m))
        raw.push_back({{id, i}, *p, false, f.score});
    }
  }
  // Head pose first, then by score (stable: camera id, face index order otherwise).
  std::stable_sort(raw.begin(), raw.end(), [](const Raw& a, const Raw& b) {
    if (a.from_head_pose != b.from_head_pose) return a.from_head_pose;
    return a.score > b.score;
  });

  struct Group {
    std::vector<const Raw*> members;
  };
  std::vector<Group> groups;
  for (const Raw& r : raw) {
    Group* best = nullptr;
    double best_d = 0;
    for (Group& g : groups) {
      const bool same_camera = std::any_of(g.members.begin(), g.members.end(), [&](const Raw* m) {
        return m->view.camera == r.view.camera;
      });
      if (same_camera) continue;
      const double d = cv::norm(g.members.front()->position - r.position);
      if (d <= options.merge_distance_m && (best == nullptr || d < best_d)) {
        best = &g;
        best_d = d;
      }
    }
    if (best != nullptr)
      best->members.push_back(&r);
    else
      groups.push_back({{&r}});
  }

  std::vector<FaceObservation3d> out;
  for (const Group& g : groups) {
    FaceObservation3d o;
    const Raw* lead = g.members.front();  // the head-pose one if any (sorted first)
    o.from_head_pose = lead->from_head_pose;
    if (o.from_head_pose) {
      o.position_world_m = lead->position;
    } else {
      cv::Vec3d sum(0, 0, 0);
      double w = 0;
      for (const Raw* m : g.members) {
        const double wi = std::max(1e-3, static_cast<double>(m->score));
        sum += m->position * wi;
        w += wi;
      }
      o.position_world_m = sum * (1.0 / w);
    }
    for (const Raw* m : g.members) {
      o.score = std::max(o.score, m->score);
      o.views.push_back(m->view);
    }
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace dreamsense::face_tracks
