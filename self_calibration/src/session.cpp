#include "dreamsense/self_calibration/session.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/eye_centers/eye_center_locator.hpp"
#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_detection/face_tracker.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/gaze/gaze_estimator.hpp"
#include "dreamsense/head_pose/face_shape_fit.hpp"
#include "dreamsense/self_calibration/gaze_level.hpp"
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>

namespace dreamsense::self_calibration {
namespace {

// Frames closer than this belong to the same tick (cameras of one rig are triggered together;
// a recording's stamps may differ by a few ms).
constexpr int64_t kSameTickNs = 10'000'000;

nlohmann::json vec_json(const cv::Vec3d& v) { return {v[0], v[1], v[2]}; }

// Mean of the triangulated eye-opening points (landmarks 36-47) in the world; nullopt when none.
std::optional<cv::Vec3d> eye_openings_centre(const head_pose::TriangulatedFace& face,
                                             const std::vector<int>& landmark_index) {
  cv::Vec3d s(0, 0, 0);
  int n = 0;
  for (size_t k = 0; k < landmark_index.size() && k < face.points_world.size(); ++k) {
    const cv::Vec3d& p = face.points_world[k];
    if (landmark_index[k] < 36 || landmark_index[k] > 47 || !std::isfinite(p[0]) ||
        !std::isfinite(p[1]) || !std::isfinite(p[2]))
      continue;
    s += p;
    ++n;
  }
  if (n == 0) return std::nullopt;
  return s * (1.0 / n);
}

// A head tilted beyond the upright cascade's reach (face_detection README, "Tilted heads"): the
// region around the camera's last face searched rotated upright by that face's roll, when the
// roll is at least min_roll_deg (0 = never).
std::vector<DetectedFace> rolled_search(face_detection::FaceDetector& detector,
                                        const cv::Mat& image, const cv::Rect2d& last,
                                        double roll_deg, double min_roll_deg) {
  if (!(min_roll_deg > 0) || std::abs(roll_deg) < min_roll_deg) return {};
  const double size = std::max(last.width, last.height);
  return face_detection::detect_rolled(detector, image,
                                       cv::Rect(face_detection::grown_by(last, 0.75)), roll_deg,
                                       0.5 * size, 2.0 * size);
}

// Where a camera's face is looked for first, from its box at the last searched tick (`last`,
// null: none); nullopt: the full frame at once. The caller searches the full frame when this
// finds nothing. See SessionSelfCalibrationOptions::guided_search and size_guided_search.
std::optional<face_detection::SearchRegion> first_search(const cv::Rect2d* last, cv::Size image,
                                                         const SessionSelfCalibrationOptions& o) {
  if (last == nullptr) return std::nullopt;
  const double size = std::max(last->width, last->height);
  const cv::Rect whole(0, 0, image.width, image.height);
  if (o.guided_search) {
    // Around the last box (0.24 s ago at the defaults), as the face tracker searches between
    // full searches.
    const cv::Rect region = cv::Rect(face_detection::grown_by(*last, 0.75)) & whole;
    if (region.empty()) return std::nullopt;
    return face_detection::SearchRegion{region, 0.6 * size, 1.6 * size};
  }
  if (o.size_guided_search)
    return face_detection::SearchRegion{whole, 0.5 * size, 2.0 * size,
                                        /*shrink_to_min_face=*/false};
  return std::nullopt;
}

}  // namespace

Status SessionSelfCalibrationOptions::check() const {
  if (!(max_seconds > 0) || tick_step < 1 || enough_frames < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "SessionSelfCalibrationOptions: max_seconds > 0, tick_step >= 1 and "
                      "enough_frames >= 1 needed");
  if (!(rolled_search_min_deg >= 0 && rolled_search_min_deg <= 90))
    return make_error(ErrorCode::kInvalidArgument,
                      "SessionSelfCalibrationOptions: rolled_search_min_deg must be in [0, 90]");
  if (auto s = eyes.check(); !s) return s;
  if (auto s = pupils.check(); !s) return s;
  if (auto s = gaze_level.check(); !s) return s;
  return face.check();
}

nlohmann::json SessionSelfCalibration::to_json() const {
  nlohmann::json j;
  j["method"] = "self_calibration";
  j["status"] = head_pose::to_string(face.status);
  j["converged"] = face.converged();
  j["reason"] = face.reason;
  j["session"] = session;
  j["cameras"] = cameras;
  j["seconds_searched"] = seconds_searched;
  j["ticks_searched"] = ticks_searched;
  j["views_with_landmarks"] = views_with_landmarks;
  j["ticks_multi_view"] = face.frames_multi_view;
  j["ticks_triangulated"] = face.frames_triangulated;
  j["views_dropped"] = face.views_dropped;
  j["camera_pair_scale_spread"] = face.median_pair_scale_spread;         // per tick, median
  j["camera_pair_median_scale_spread"] = face.pair_median_scale_spread;  // what is checked
  j["level"] = face.level;
  j["fixation_ticks"] = face.fixation_ticks;
  j["fixation_correction_deg"] = face.fixation_correction_deg;
  j["gaze_level"] = {{"applied", gaze_level.applied},
                     {"ticks_with_gaze", gaze_level.ticks_with_gaze},
                     {"fixation_ticks", gaze_level.fixation_ticks},
                     {"correction_deg", gaze_level.correction_deg},
                     {"yaw_centre_deg", gaze_level.yaw_centre_deg},
                     {"eyeball_shift_x_mm", 1000 * gaze_level.eyeball_shift_x_m}};
  j["ticks_used"] = face.frames_used;
  j["points"] = face.model.points_m.size();
  j["residual_rms_mm"] = 1000 * face.median_rms_m;
  j["reprojection_rms_px"] = face.median_reprojection_px;
  j["interocular_mm"] = 1000 * face.interocular_m;
  j["upright"] = face.upright;
  j["upright_roll_correction_deg"] = face.upright_roll_correction_deg;
  j["roll_spread_deg"] = face.roll_spread_deg;
  j["level_pitch_correction_deg"] = face.level_pitch_correction_deg;
  j["pitch_spread_deg"] = face.pitch_spread_deg;
  j["cpu_s"] = cpu_s;
  if (face.converged()) {
    j["right_eyeball"] = {{"centre_head_m", vec_json(right_eyeball.centre_head_m)},
                          {"radius_m", right_eyeball.radius_m}};
    j["left_eyeball"] = {{"centre_head_m", vec_json(left_eyeball.centre_head_m)},
                         {"radius_m", left_eyeball.radius_m}};
  }
  return j;
}

struct TickSelfCalibration::State {
  std::map<SensorId, CameraModel> cameras;
  SessionSelfCalibrationOptions options;
  std::shared_ptr<const face_landmarks::Landmarker> landmarker;
  face_detection::FaceDetector detector;
  eye_centers::EyeCenterLocator pupil_locator;
  std::vector<head_pose::MultiViewLandmarks> ticks;
  std::vector<std::vector<EyeCenters>> pupils;  // per tick, per view of ticks[i]
  std::map<SensorId, cv::Rect2d> last_box;      // per camera: its face at the last searched tick
  // Per camera: the last face found and its roll (kept through misses), for the rotated search.
  struct SeenFace {
    cv::Rect2d box;
    double roll_deg = 0;
  };
  std::map<SensorId, SeenFace> last_seen;
  int ticks_searched = 0, views_with_landmarks = 0;
  int triangulated = 0, multi_view = 0;
};

TickSelfCalibration::TickSelfCalibration(std::unique_ptr<State> state) : state_(std::move(state)) {}
TickSelfCalibration::~TickSelfCalibration() = default;

Result<std::unique_ptr<TickSelfCalibration>> TickSelfCalibration::create(
    std::map<SensorId, CameraModel> cameras, const SessionSelfCalibrationOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto landmarker = face_landmarks::shared_dlib_landmarker();
  if (!landmarker) return tl::unexpected(landmarker.error());
  auto detector = face_detection::FaceDetector::create({});
  if (!detector) return tl::unexpected(detector.error());
  auto pupil_locator = eye_centers::EyeCenterLocator::create(options.pupils);
  if (!pupil_locator) return tl::unexpected(pupil_locator.error());
  auto state = std::unique_ptr<State>(new State{std::move(cameras), options, std::move(*landmarker),
                                                std::move(*detector), *pupil_locator});
  return std::unique_ptr<TickSelfCalibration>(new TickSelfCalibration(std::move(state)));
}

bool TickSelfCalibration::enough() const {
  // Ticks seen by two or more cameras (triangulated or not: when they do not, cameras that
  // disagree, the reason is clear by then).
  return state_->multi_view >= state_->options.enough_frames;
}

int TickSelfCalibration::ticks_searched() const { return state_->ticks_searched; }

Status TickSelfCalibration::add(int64_t stamp_ns, const std::vector<FramePtr>& frames) {
  State& st = *state_;
  const SessionSelfCalibrationOptions& options = st.options;
  // Only the gaze level uses the pupils.
  const bool locate_pupils =
      options.gaze_level.enabled && options.face.fixation_target_world_m.has_value();
  ++st.ticks_searched;
  head_pose::MultiViewLandmarks mv;
  mv.stamp_ns = stamp_ns;
  std::vector<const cv::Mat*> images;  // per view
  for (const FramePtr& f : frames) {
    const ColorImage* img = f ? f->as<ColorImage>() : nullptr;
    const auto camera = f ? st.cameras.find(f->sensor) : st.cameras.end();
    if (img == nullptr || camera == st.cameras.end()) continue;
    std::vector<DetectedFace> faces;
    const auto it = st.last_box.find(f->sensor);
    if (const auto first = first_search(it == st.last_box.end() ? nullptr : &it->second,
                                        img->image.size(), options))
      faces = st.detector.detect(img->image, *first, false);
    if (faces.empty()) faces = st.detector.detect(img->image, std::nullopt, false);
    if (faces.empty())
      if (const auto seen = st.last_seen.find(f->sensor); seen != st.last_seen.end())
        faces = rolled_search(st.detector, img->image, seen->second.box, seen->second.roll_deg,
                              options.rolled_search_min_deg);
    if (faces.empty()) {
      st.last_box.erase(f->sensor);
      continue;
    }
    st.last_box[f->sensor] = faces.front().box_px;
    auto pts = st.landmarker->fit(img->image, faces.front().box_px);
    if (!pts) return tl::unexpected(pts.error());
    if (!*pts) continue;
    st.last_seen[f->sensor] = {faces.front().box_px, eye_line_roll_deg(**pts)};
    ++st.views_with_landmarks;
    mv.views.push_back({&camera->second, std::move(**pts)});
    images.push_back(&img->image);
  }
  std::optional<cv::Vec3d> eyes_world;  // sizes the iris in each view (pixels per mm)
  if (mv.views.size() >= 2) {
    ++st.multi_view;
    if (const auto t = head_pose::triangulate_face(mv, options.face.triangulation)) {
      ++st.triangulated;
      eyes_world = eye_openings_centre(*t, options.face.triangulation.landmark_index);
    }
  }
  std::vector<EyeCenters> found;
  for (size_t v = 0; v < mv.views.size() && locate_pupils; ++v) {
    FaceLandmarks l;
    l.camera = mv.views[v].camera->frame;
    l.image_size = images[v]->size();
    l.points_px = mv.views[v].landmarks_px;
    const auto scale =
        eyes_world ? eye_centers::pixels_per_mm_at(*mv.views[v].camera, *eyes_world) : std::nullopt;
    auto p = st.pupil_locator.locate_both(*images[v], l, scale);
    found.push_back(p ? *p : EyeCenters{});  // a view without pupils only loses its gaze
  }
  st.pupils.push_back(std::move(found));
  st.ticks.push_back(std::move(mv));
  return ok_status();
}

SessionSelfCalibration TickSelfCalibration::finish(const std::string& session) const {
  const State& st = *state_;
  const SessionSelfCalibrationOptions& options = st.options;
  SessionSelfCalibration out;
  out.session = session;
  out.cameras = static_cast<int>(st.cameras.size());
  out.ticks_searched = st.ticks_searched;
  out.views_with_landmarks = st.views_with_landmarks;
  out.face = head_pose::self_calibrate_face(st.ticks, options.face);
  if (out.face.converged() && options.face.fixation_target_world_m) {
    out.gaze_level = level_from_gaze_fixations(out.face.model, st.ticks, st.pupils,
                                               *options.face.fixation_target_world_m, options.eyes,
                                               options.gaze_level);
    if (out.gaze_level.applied) {
      out.face.model = pitched(out.face.model, out.gaze_level.correction_deg);
      out.face.level = "gaze_fixations";
      out.face.level_pitch_correction_deg += out.gaze_level.correction_deg;
      out.face.reason +=
          fmt::format("; level refined from {} gaze fixations on the target ({:+.1f} deg)",
                      out.gaze_level.fixation_ticks, out.gaze_level.correction_deg);
    }
  }
  if (out.face.converged()) {
    if (const auto e =
            anatomical_eyeballs(out.face.model, options.eyes, out.gaze_level.eyeball_shift_x_m)) {
      out.right_eyeball = e->first;
      out.left_eyeball = e->second;
    }
  }
  return out;
}

Result<SessionSelfCalibrationOptions> with_fixation_target(
    const SessionSelfCalibrationOptions& options,
    const std::map<std::string, std::string>& metadata, const std::string& where) {
  SessionSelfCalibrationOptions o = options;
  if (o.face.fixation_target_world_m || !o.fixation_from_metadata) return o;
  if (const auto it = metadata.find("robot_head_m"); it != metadata.end()) {
    o.face.fixation_target_world_m = parse_vec3(it->second);
    if (!o.face.fixation_target_world_m)
      return make_error(ErrorCode::kCorruptData,
                        "{}: metadata robot_head_m must be three numbers \"x y z\" in metres "
                        "(got \"{}\")",
                        where, it->second);
  }
  return o;
}

Result<std::map<SensorId, CameraModel>> self_calibration_cameras(
    const std::filesystem::path& dir, const sources::SessionManifest& manifest,
    const SessionSelfCalibrationOptions& options) {
  auto calibrated = sources::read_color_calibrations(dir, manifest);
  if (!calibrated) return tl::unexpected(calibrated.error());
  auto roles = sources::stream_roles(manifest);
  if (!roles) return tl::unexpected(roles.error());
  std::map<SensorId, CameraModel> cameras;
  for (auto& [id, camera] : *calibrated) {
    const auto& r = (*roles)[id];
    const bool child_camera = std::find(r.begin(), r.end(), "child_camera") != r.end();
    if (options.cameras.empty() ? child_camera
                                : std::find(options.cameras.begin(), options.cameras.end(), id) !=
                                      options.cameras.end())
      cameras.emplace(id, std::move(camera));
  }
  if (cameras.empty())
    return make_error(ErrorCode::kNotFound, "{}: no calibrated colour stream to self-calibrate on",
                      dir.string());
  return cameras;
}

Result<SessionSelfCalibration> self_calibrate_session(
    const std::filesystem::path& dir, const SessionSelfCalibrationOptions& options_in) {
  if (auto s = options_in.check(); !s) return tl::unexpected(s.error());
  // dlib's model is the process's shared one (the analysis's face_landmarks uses it too, so it
  // is loaded once); its load (~1 s) is not a cost of self-calibrating, so the clock starts after.
  if (auto landmarker = face_landmarks::shared_dlib_landmarker(); !landmarker)
    return tl::unexpected(landmarker.error());
  const std::clock_t cpu0 = std::clock();
  auto manifest = sources::read_manifest(dir);
  if (!manifest) return tl::unexpected(manifest.error());
  DS_ASSIGN_OR_RETURN(
      const SessionSelfCalibrationOptions options,
      with_fixation_target(options_in, manifest->metadata, (dir / "session.yaml").string()));
  DS_ASSIGN_OR_RETURN(auto cameras, self_calibration_cameras(dir, *manifest, options));
  sources::SessionReaderOptions ro;
  for (const auto& [id, c] : cameras) ro.only.push_back(id);
  DS_ASSIGN_OR_RETURN(auto search, TickSelfCalibration::create(std::move(cameras), options));
  auto reader = sources::SessionReader::open(dir, ro);
  if (!reader) return tl::unexpected(reader.error());

  double seconds_searched = 0;
  std::vector<FramePtr> group;
  int64_t first_ns = 0, group_ns = 0;
  bool started = false;
  int tick_index = -1;
  auto flush = [&]() -> Status {
    if (group.empty()) return ok_status();
    ++tick_index;
    Status s = tick_index % options.tick_step == 0 ? search->add(group_ns, group) : ok_status();
    group.clear();
    return s;
  };
  const int64_t max_ns = static_cast<int64_t>(options.max_seconds * 1e9);

  // MJPEG cameras have an index: the ticks are grouped from it and only the chosen ticks' frames
  // are decoded (1 in tick_step). Decoding every frame in between was most of the CPU (11.2 s for
  // a 20 s session, issue 15). The same ticks and frames as reading them all; a tick whose frames
  // all fail to decode still counts in the 1-in-tick_step choice (the reader would skip it).
  struct IndexedFrame {
    int64_t stamp_ns = 0;
    SensorId id;
    size_t k = 0;
  };
  std::vector<IndexedFrame> indexed;
  bool all_indexed = true;
  for (const auto& stream : manifest->streams) {  // manifest order breaks ties, as in next()
    if (std::find(ro.only.begin(), ro.only.end(), stream.id) == ro.only.end()) continue;
    const auto records = (*reader)->records(stream.id);
    if (records.empty()) all_indexed = false;  // a video stream (or nothing to read)
    for (size_t k = 0; k < records.size(); ++k)
      indexed.push_back({records[k].stamp_ns, stream.id, k});
  }
  const bool from_index = all_indexed && !indexed.empty();
  if (from_index) {
    std::stable_sort(
        indexed.begin(), indexed.end(),
        [](const IndexedFrame& a, const IndexedFrame& b) { return a.stamp_ns < b.stamp_ns; });
    first_ns = indexed.front().stamp_ns;
    for (size_t i = 0; i < indexed.size() && !search->enough();) {
      const int64_t tick_ns = indexed[i].stamp_ns;
      if (tick_ns - first_ns > max_ns) break;
      size_t end = i;
      while (end < indexed.size() && indexed[end].stamp_ns - tick_ns <= kSameTickNs &&
             indexed[end].stamp_ns - first_ns <= max_ns)
        ++end;
      if (++tick_index % options.tick_step == 0) {
        for (size_t g = i; g < end; ++g) {
          auto frame = (*reader)->decode_record(indexed[g].id, indexed[g].k);
          if (!frame) {
            if (frame.error().code == ErrorCode::kCorruptData) continue;  // a damaged record
            return tl::unexpected(frame.error());
          }
          group.push_back(*frame);
        }
        if (!group.empty()) DS_RETURN_IF_ERROR(search->add(tick_ns, group));
        group.clear();
      }
      seconds_searched = static_cast<double>(indexed[end - 1].stamp_ns - first_ns) * 1e-9;
      i = end;
    }
  }
  while (!from_index) {  // video streams: every frame is read
    auto frame = (*reader)->next();
    if (!frame) {
      if (frame.error().code == ErrorCode::kEndOfStream) break;
      return tl::unexpected(frame.error());
    }
    const FramePtr& f = *frame;
    const int64_t ns = f->stamp.ns();
    if (!started) {
      first_ns = group_ns = ns;
      started = true;
    }
    if (ns - first_ns > max_ns) break;
    if (ns - group_ns > kSameTickNs) {
      DS_RETURN_IF_ERROR(flush());
      group_ns = ns;
      if (search->enough()) break;
    }
    seconds_searched = static_cast<double>(ns - first_ns) * 1e-9;
    group.push_back(f);
  }
  if (!search->enough()) DS_RETURN_IF_ERROR(flush());
  SessionSelfCalibration out = search->finish(manifest->name);
  out.seconds_searched = seconds_searched;
  out.cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  return out;
}

Status write_self_calibration(const SessionSelfCalibration& c, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", dir.string(), ec.message());
  if (c.face.converged()) {
    const std::string provenance =
        fmt::format("self-calibrated (no truth) from session {}: {}", c.session, c.face.reason);
    DS_RETURN_IF_ERROR(
        head_pose::write_face_model((dir / "face_model.yaml").string(), c.face.model, provenance));
    gaze::GazeModelFile g;
    g.plane = gaze::OffsetPlane::kHeadPlane;
    g.right_eyeball = c.right_eyeball;
    g.left_eyeball = c.left_eyeball;
    g.fixation_yaw = true;  // placed by anatomy: the gaze analyser learns their sideways bias
    g.provenance =
        "anatomical eyeballs (modalities/gaze/README.md) behind the eye openings of " + provenance;
    DS_RETURN_IF_ERROR(gaze::write_gaze_model(dir / "gaze.yaml", g));
  }
  const auto path = dir / "self_calibration.json";
  std::ofstream f(path);
  f << c.to_json().dump(2) << "\n";
  if (!f) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
  return ok_status();
}

}  // namespace dreamsense::self_calibration
