#include "dreamsense/primitives/face.hpp"

#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/primitives/registry.hpp"

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

Status FacePrimitiveOptions::check() const {
  std::string bad;
  if (!(track_face_dt_s >= 0)) bad += " track_face_dt_s must be >= 0;";
  const auto& p = head_gaze_plane.points;
  if (!(cv::norm((p[1] - p[0]).cross(p[2] - p[0])) > 1e-9))
    bad += " the three head_gaze_plane points are collinear;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "FacePrimitiveOptions:" + bad);
  return geometry.check();
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

std::vector<FaceInWorld> associate_faces(const FaceDetections& detections,
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
  std::vector<FaceInWorld> out;
  std::vector<double> weight;
  for (const View& v : views) {
    FaceInWorld* match = nullptr;
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

namespace {
EyeRay eye_ray(const GazeRay& r) {
  return EyeRay{r.origin_world_m, r.direction_world, r.theta_deg, r.phi_deg, r.features};
}
}  // namespace

Answer<MutualGazeValue> check_mutual_gaze(const PrimitiveContext& ctx) {
  const auto m = ctx.observe(keys::kMutualGaze);
  auto a = Answer<MutualGazeValue>::from(m);
  if (a.status != PrimitiveStatus::kOk) return a;
  const MutualGaze& g = m.value();
  a.confidence = m.entry->confidence;
  a.value = MutualGazeValue{g.mutual, g.raw, g.held_s, g.miss_distance_m, g.mode, g.target};
  return a;
}

Answer<EyeGazeValue> get_eye_gaze(const PrimitiveContext& ctx, const EyeQuery& query) {
  const auto g = ctx.observe(keys::kEyeGaze);
  auto a = Answer<EyeGazeValue>::from(g);
  if (a.status != PrimitiveStatus::kOk) return a;
  const EyeGaze& e = g.value();
  const GazeRay& chosen = query.eye == "left" ? e.left : query.eye == "right" ? e.right : e.both;
  if (query.eye != "both" && !chosen.valid) {
    a.status = PrimitiveStatus::kNoData;  // that eye has no ray (closed, not found)
    return a;
  }
  a.confidence = g.entry->confidence;
  a.source = e.camera;
  a.query = query;
  EyeGazeValue v;
  v.both = eye_ray(chosen);
  if (e.right.valid) v.right = eye_ray(e.right);
  if (e.left.valid) v.left = eye_ray(e.left);
  v.camera = e.camera;
  v.method = e.method;
  v.fixation_yaw_deg = e.fixation_yaw_deg;
  a.value = std::move(v);
  return a;
}

// 2-D centres from the eye-centre locator; 3-D positions from the gaze rays' origins (the pupils:
// on the eyeballs, or with eq. 4 the head pose + half the interpupillary distance), so only with
// a gaze of the same frame.
Answer<EyesValue> get_eyes(const PrimitiveContext& ctx) {
  const auto c = ctx.observe(keys::kEyeCenters);
  auto a = Answer<EyesValue>::from(c);
  if (a.status != PrimitiveStatus::kOk) return a;
  const EyeCenters& ec = c.value();
  if (!ec.right.found && !ec.left.found) {
    a.status = PrimitiveStatus::kNoData;  // e.g. closed eyes
    return a;
  }
  const auto g = ctx.observe(keys::kEyeGaze);
  const bool have_3d = g.ok() && g.entry->stamp == c.entry->stamp;
  EyesValue v;
  v.camera = ec.camera;
  if (ec.right.found) v.right_px = ec.right.center_px;
  if (ec.left.found) v.left_px = ec.left.center_px;
  if (have_3d) {
    v.right_m = g.value().right.origin_world_m;
    v.left_m = g.value().left.origin_world_m;
    v.right_valid = g.value().right.valid;
    v.left_valid = g.value().left.valid;
  }
  v.method = ec.method;
  a.confidence = c.entry->confidence;
  a.source = ec.camera;
  a.value = std::move(v);
  return a;
}

// Faces across cameras with their 3-D position, plus what each camera saw (so that detection
// can be evaluated per camera) and the selected camera.
Answer<FacesValue> get_faces(const PrimitiveContext& ctx) {
  const auto d = ctx.observe(keys::kFaceDetections);
  auto a = Answer<FacesValue>::from(d);
  if (a.status != PrimitiveStatus::kOk) return a;
  const auto selected = ctx.view().get(keys::kSelectedCamera);
  const SelectedCamera* sel = selected && selected->present() && selected->stamp == d.entry->stamp
                                  ? selected->value.get()
                                  : nullptr;
  FacesValue v;
  v.faces = associate_faces(d.value(), sel, ctx.cameras(),
                            ctx.family_options<FacePrimitiveOptions>().geometry);
  for (const auto& [cam, cf] : d.value().cameras) {
    auto& list = v.cameras[cam];
    for (const auto& f : cf.faces) list.push_back(CameraFace{f.box_px, f.score, f.frontalness});
  }
  if (sel) v.selected_camera = sel->camera;
  // The most frontal camera by this tick's head pose, when there is one (HeadPose::
  // frontal_camera): face detection chose `sel` from the previous tick's pose.
  if (const auto pose = ctx.view().get(keys::kHeadPose);
      sel && pose && pose->present() && pose->stamp == d.entry->stamp &&
      !pose->value->frontal_camera.empty() && d.value().cameras.count(pose->value->frontal_camera))
    v.selected_camera = pose->value->frontal_camera;
  a.confidence = d.entry->confidence;
  if (v.selected_camera)
    a.source = *v.selected_camera;
  else if (!v.faces.empty())
    a.source = v.faces.front().camera;
  a.value = std::move(v);
  return a;
}

namespace {
template <typename V>
Answer<V> from_head_pose(const Observation<HeadPose>& p) {
  auto a = Answer<V>::from(p);
  if (a.status == PrimitiveStatus::kOk) {
    a.confidence = p.entry->confidence;
    a.source = p.value().camera;
  }
  return a;
}
}  // namespace

Answer<HeadValue> get_head(const PrimitiveContext& ctx) {
  const auto p = ctx.observe(keys::kHeadPose);
  auto a = from_head_pose<HeadValue>(p);
  if (a.status == PrimitiveStatus::kOk)
    a.value = HeadValue{p.value().position_world_m, p.value().camera};
  return a;
}

Answer<HeadGazeValue> get_head_gaze(const PrimitiveContext& ctx) {
  const auto p = ctx.observe(keys::kHeadPose);
  auto a = from_head_pose<HeadGazeValue>(p);
  if (a.status != PrimitiveStatus::kOk) return a;
  const HeadPose& h = p.value();
  a.value = HeadGazeValue{
      h.gaze_origin_world_m, h.gaze_direction_world, h.roll_deg, h.yaw_deg, h.pitch_deg, h.camera};
  return a;
}

Answer<HeadGazePlaneValue> get_head_gaze_plane(const PrimitiveContext& ctx,
                                               const PlaneQuery& query) {
  const auto p = ctx.observe(keys::kHeadPose);
  auto a = from_head_pose<HeadGazePlaneValue>(p);
  if (a.status == PrimitiveStatus::kDisabled) return a;
  a.query = query;
  if (a.status != PrimitiveStatus::kOk) return a;
  const HeadPose& h = p.value();
  const auto& pts = query.points;
  cv::Vec3d n = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
  const double nn = cv::norm(n);
  if (nn > 1e-12) n /= nn;  // collinear points: no plane, answered as no_data below
  const double denom = nn > 1e-12 ? n.dot(h.gaze_direction_world) : 0.0;
  const double t = std::abs(denom) < 1e-9 ? -1.0 : n.dot(pts[0] - h.gaze_origin_world_m) / denom;
  if (!(t > 0)) {
    a.status = PrimitiveStatus::kNoData;
    a.confidence = 0;
    return a;
  }
  a.value = HeadGazePlaneValue{h.gaze_origin_world_m + t * h.gaze_direction_world, t, h.camera};
  return a;
}

Answer<TrackValue> track_face(const PrimitiveContext& ctx, const std::optional<TrackQuery>& query) {
  const auto e = ctx.observe(keys::kFaceTracks);
  auto a = Answer<TrackValue>::from(e);
  if (a.status != PrimitiveStatus::kOk) return a;
  const FaceTracks& tracks = e.value();
  if (tracks.tracks.empty()) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  const FaceTrack* track = &tracks.tracks.front();
  TrackQuery q{track->position_world_m, ctx.family_options<FacePrimitiveOptions>().track_face_dt_s};
  if (query) {
    q = *query;
    for (const auto& t : tracks.tracks)
      if (cv::norm(t.position_world_m - q.seed_m) < cv::norm(track->position_world_m - q.seed_m))
        track = &t;
  }
  a.query = q;
  // Prediction from the track's last update to tick + dt.
  const double ahead = q.dt_s + (ctx.tick() - track->last_update).seconds();
  TrackValue v;
  v.position_m = track->position_world_m + ahead * track->velocity_world_mps;
  v.velocity_mps = track->velocity_world_mps;
  v.track_id = track->id;
  a.confidence = e.entry->confidence;
  a.value = v;
  return a;
}

// The rows of the face chain's family.
void register_face_primitives(PrimitiveRegistry& r) {
  using P = PrimitiveId;
  r.add(P::kCheckMutualGaze, {keys::kMutualGaze.name}, check_mutual_gaze);
  r.add(P::kGetEyeGaze, {keys::kEyeGaze.name},
        [](const PrimitiveContext& c) { return get_eye_gaze(c); });
  r.add(P::kGetEyes, {keys::kEyeCenters.name}, get_eyes);
  r.add(P::kGetFaces, {keys::kFaceDetections.name}, get_faces);
  r.add(P::kGetHead, {keys::kHeadPose.name}, get_head);
  r.add(P::kGetHeadGaze, {keys::kHeadPose.name}, get_head_gaze);
  r.add(P::kGetHeadGazePlane, {keys::kHeadPose.name}, [](const PrimitiveContext& c) {
    return get_head_gaze_plane(c, c.family_options<FacePrimitiveOptions>().head_gaze_plane);
  });
  r.add(P::kTrackFace, {keys::kFaceTracks.name},
        [](const PrimitiveContext& c) { return track_face(c); });
}

}  // namespace dreamsense::primitives
