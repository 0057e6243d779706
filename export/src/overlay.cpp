#include "dreamsense/export/overlay.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/core/output_file.hpp"
#include "dreamsense/core/skeleton_bones.hpp"
#include "dreamsense/dream/legacy.hpp"
#include "dreamsense/perception/actions.hpp"
#include "dreamsense/perception/body.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/speech.hpp"
#include "dreamsense/perception/voice_id.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace dreamsense::exporters {
namespace {

namespace fs = std::filesystem;

// The newest entry of `key` if it was written in this tick and holds a value.
template <typename T>
const T* this_tick(const BlackboardView& view, Key<T> key, Timestamp tick,
                   std::shared_ptr<const T>& keep) {
  const auto e = view.get(key);
  if (!e || e->stamp != tick || !e->present()) return nullptr;
  keep = e->value;
  return keep.get();
}

// The newest entry of `key` holding a value, if it is at most `max_age` older than the tick.
template <typename T>
const T* recent(const BlackboardView& view, Key<T> key, Timestamp tick, Duration max_age,
                std::shared_ptr<const T>& keep) {
  const auto e = view.get(key);
  if (!e || !e->present() || e->stamp > tick || tick - e->stamp > max_age) return nullptr;
  keep = e->value;
  return keep.get();
}

const cv::Mat* color_image(const MultiFrame& tick, const SensorId& camera) {
  const FramePtr f = tick.frame(camera);
  if (f == nullptr) return nullptr;
  const ColorImage* c = f->as<ColorImage>();
  if (c == nullptr || c->image.empty()) return nullptr;
  return &c->image;
}

// Image pixels -> canvas pixels.
struct Mapping {
  double scale = 1;
  cv::Point2d offset;
  cv::Point operator()(const cv::Point2d& p) const {
    return {static_cast<int>(std::lround(p.x * scale + offset.x)),
            static_cast<int>(std::lround(p.y * scale + offset.y))};
  }
};

// Factor from coordinates measured on an image of `measured` size to the shown image's pixels.
double rescale(const cv::Size& measured, const cv::Size& shown) {
  return measured.width > 0 ? static_cast<double>(shown.width) / measured.width : 1.0;
}

struct Style {
  double font = 0.5;
  int thin = 1, thick = 2;
};

void label(cv::Mat& img, const std::string& text, cv::Point org, const cv::Scalar& fg,
           const cv::Scalar& bg, const Style& st) {
  int baseline = 0;
  const cv::Size sz = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, st.font, st.thin, &baseline);
  const int pad = 3;
  org.x = std::clamp(org.x, pad, std::max(pad, img.cols - sz.width - pad));
  org.y = std::clamp(org.y, sz.height + pad, std::max(sz.height + pad, img.rows - baseline - pad));
  cv::rectangle(img, {org.x - pad, org.y - sz.height - pad},
                {org.x + sz.width + pad, org.y + baseline + pad}, bg, cv::FILLED);
  cv::putText(img, text, org, cv::FONT_HERSHEY_SIMPLEX, st.font, fg, st.thin, cv::LINE_AA);
}

std::optional<cv::Point2d> project(const CameraModel* model, const cv::Size& image,
                                   const cv::Vec3d& world) {
  if (model == nullptr) return std::nullopt;
  const auto px = model->project(world);
  if (!px) return std::nullopt;
  return *px * rescale(model->image_size, image);
}

void draw_segment(cv::Mat& canvas, const Mapping& map, const CameraModel* model,
                  const cv::Size& image, const cv::Vec3d& a, const cv::Vec3d& b,
                  const cv::Scalar& colour, int thickness) {
  const auto pa = project(model, image, a), pb = project(model, image, b);
  if (!pa || !pb) return;
  // Guard against huge coordinates from points near the camera plane.
  const cv::Point ca = map(*pa), cb = map(*pb);
  if (std::abs(ca.x) > 100000 || std::abs(ca.y) > 100000 || std::abs(cb.x) > 100000 ||
      std::abs(cb.y) > 100000)
    return;
  cv::line(canvas, ca, cb, colour, thickness, cv::LINE_AA);
}

}  // namespace

std::vector<cv::Rect> face_regions_px(const SensorId& camera, Timestamp tick,
                                      const BlackboardView& view, const CameraModel* model,
                                      cv::Size shown) {
  std::vector<cv::Rect2d> found;
  const Duration max_age = Duration::from_seconds(1.0);
  auto recent = [&](Timestamp stamp) { return stamp <= tick && tick - stamp <= max_age; };
  if (const auto e = view.get(keys::kFaceDetections); e && e->present() && recent(e->stamp)) {
    const auto cam = e->value->cameras.find(camera);
    if (cam != e->value->cameras.end()) {
      const double k = rescale(cam->second.image_size, shown);
      for (const DetectedFace& f : cam->second.faces)
        found.emplace_back(f.box_px.x * k, f.box_px.y * k, f.box_px.width * k, f.box_px.height * k);
    }
  }
  if (const auto e = view.get(keys::kFaceLandmarks); e && e->present() && recent(e->stamp) &&
                                                     e->value->camera == camera &&
                                                     !e->value->points_px.empty()) {
    const double k = rescale(e->value->image_size, shown);
    std::vector<cv::Point2f> pts;
    for (const cv::Point2d& p : e->value->points_px)
      pts.emplace_back(static_cast<float>(p.x * k), static_cast<float>(p.y * k));
    found.push_back(cv::Rect2d(cv::boundingRect(pts)));
  }
  if (const auto e = view.get(keys::kFaceTracks);
      model != nullptr && e && e->present() && recent(e->stamp)) {
    for (const FaceTrack& t : e->value->tracks) {
      const double dt = (tick - t.last_update).seconds();
      if (dt < 0 || dt > max_age.seconds()) continue;
      const cv::Vec3d centre = t.position_world_m + t.velocity_world_mps * dt;
      const cv::Vec3d c = model->to_camera(centre);
      if (!(c[2] > 0.05)) continue;
      const auto px = project(model, shown, centre);
      if (!px) continue;
      // Half of a 0.24 m square at the head's depth, in shown pixels.
      const double half = model->K(0, 0) * 0.12 / c[2] * rescale(model->image_size, shown);
      if (!(half > 0) || half > 1e5) continue;
      found.emplace_back(px->x - half, px->y - half, 2 * half, 2 * half);
    }
  }
  std::vector<cv::Rect> out;
  const cv::Rect2d frame(0, 0, shown.width, shown.height);
  for (const cv::Rect2d& r : found) {
    if (!(r.width > 0 && r.height > 0)) continue;
    const double mx = 0.25 * r.width, my = 0.25 * r.height;
    const cv::Rect2d grown =
        cv::Rect2d(r.x - mx, r.y - my, r.width + 2 * mx, r.height + 2 * my) & frame;
    if (grown.width < 1 || grown.height < 1) continue;
    out.emplace_back(static_cast<int>(std::floor(grown.x)), static_cast<int>(std::floor(grown.y)),
                     static_cast<int>(std::ceil(grown.br().x) - std::floor(grown.x)),
                     static_cast<int>(std::ceil(grown.br().y) - std::floor(grown.y)));
    out.back() &= cv::Rect(0, 0, shown.width, shown.height);
  }
  return out;
}

void blur_regions(cv::Mat& image, const std::vector<cv::Rect>& regions) {
  for (cv::Rect r : regions) {
    r &= cv::Rect(0, 0, image.cols, image.rows);
    if (r.width < 2 || r.height < 2) continue;
    cv::Mat roi = image(r);
    const int cells = 8;
    const double f = static_cast<double>(cells) / std::max(r.width, r.height);
    cv::Mat small;
    cv::resize(roi, small,
               {std::max(1, static_cast<int>(std::lround(r.width * f))),
                std::max(1, static_cast<int>(std::lround(r.height * f)))},
               0, 0, cv::INTER_AREA);
    cv::Mat big;
    cv::resize(small, big, r.size(), 0, 0, cv::INTER_NEAREST);
    const int k = (std::max(r.width, r.height) / cells) | 1;
    cv::GaussianBlur(big, big, {k, k}, 0, 0, cv::BORDER_REPLICATE);
    big.copyTo(roi);
  }
}

Status OverlayOptions::check() const {
  std::string bad;
  if (camera.empty()) bad += " camera must be \"selected\" or a stream id;";
  if (width_px < 16 || width_px > 7680) bad += " width_px must be in [16, 7680];";
  if (!(fps > 0) || fps > 1000) bad += " fps must be in (0, 1000];";
  if (fourcc.size() != 4) bad += " fourcc must have 4 characters;";
  if (!(head_axis_length_m > 0)) bad += " head_axis_length_m must be > 0;";
  if (!(gaze_length_m > 0)) bad += " gaze_length_m must be > 0;";
  for (const auto& [id, c] : cameras)
    if (auto s = c.check(); !s) bad += fmt::format(" camera '{}': {};", id, s.error().message);
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "OverlayOptions:{}", bad);
  return ok_status();
}

cv::Mat draw_overlay(const cv::Mat& image, const SensorId& camera, const MultiFrame& tick,
                     const BlackboardView& view, const OverlayOptions& options, cv::Size out_size) {
  cv::Mat canvas(out_size, CV_8UC3, cv::Scalar::all(0));
  if (out_size.empty()) return canvas;
  Style st;
  st.font = std::max(0.35, 0.5 * out_size.width / 960.0);
  st.thick = std::max(2, static_cast<int>(std::lround(2.0 * out_size.width / 960.0)));
  st.thin = std::max(1, st.thick / 2);

  // The picture, scaled to fit and centred.
  Mapping map;
  cv::Size shown = image.size();
  if (!image.empty()) {
    map.scale = std::min(static_cast<double>(out_size.width) / image.cols,
                         static_cast<double>(out_size.height) / image.rows);
    const cv::Size sz(std::max(1, static_cast<int>(std::lround(image.cols * map.scale))),
                      std::max(1, static_cast<int>(std::lround(image.rows * map.scale))));
    const cv::Rect roi((out_size.width - sz.width) / 2, (out_size.height - sz.height) / 2,
                       std::min(sz.width, out_size.width), std::min(sz.height, out_size.height));
    map.offset = {static_cast<double>(roi.x), static_cast<double>(roi.y)};
    cv::Mat bgr;
    if (image.type() == CV_8UC3)
      bgr = image;
    else if (image.type() == CV_8UC1)
      cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
    else if (image.type() == CV_8UC4)
      cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
    if (!bgr.empty()) {
      cv::Mat dst = canvas(roi);
      // Bilinear: 5x cheaper than INTER_AREA at 0.75x, good enough for a review video.
      cv::resize(bgr, dst, roi.size(), 0, 0, cv::INTER_LINEAR);
    } else {
      label(canvas, "unsupported image type", {10, out_size.height / 2}, {255, 255, 255}, {0, 0, 0},
            st);
    }
  }
  const Timestamp t = tick.stamp;
  const auto model_it = options.cameras.find(camera);
  const CameraModel* model = model_it == options.cameras.end() ? nullptr : &model_it->second;
  if (options.blur_faces && !image.empty()) {
    // In the shown picture's pixels, moved to the canvas; before anything is drawn on it.
    std::vector<cv::Rect> regions = face_regions_px(camera, t, view, model, shown);
    const cv::Rect picture(
        cv::Point(static_cast<int>(map.offset.x), static_cast<int>(map.offset.y)),
        cv::Size(static_cast<int>(std::lround(shown.width * map.scale)),
                 static_cast<int>(std::lround(shown.height * map.scale))));
    for (cv::Rect& r : regions) {
      const cv::Point tl = map(cv::Point2d(r.x, r.y)), br = map(cv::Point2d(r.br().x, r.br().y));
      r = cv::Rect(tl, br) & picture;
    }
    blur_regions(canvas, regions);
  }

  std::shared_ptr<const SelectedCamera> sel_keep;
  const SelectedCamera* sel = this_tick(view, keys::kSelectedCamera, t, sel_keep);

  // Face boxes with scores.
  std::shared_ptr<const FaceDetections> det_keep;
  if (const FaceDetections* det = this_tick(view, keys::kFaceDetections, t, det_keep)) {
    const auto cam = det->cameras.find(camera);
    if (cam != det->cameras.end()) {
      const double k = rescale(cam->second.image_size, shown);
      for (size_t i = 0; i < cam->second.faces.size(); ++i) {
        const DetectedFace& f = cam->second.faces[i];
        const bool selected = sel != nullptr && sel->camera == camera && sel->face_index == i;
        const cv::Point tl = map(cv::Point2d(f.box_px.x, f.box_px.y) * k);
        const cv::Point br = map(cv::Point2d(f.box_px.br().x, f.box_px.br().y) * k);
        const cv::Scalar& c =
            selected ? overlay_colors::kSelectedFaceBox : overlay_colors::kFaceBox;
        cv::rectangle(canvas, tl, br, c, selected ? st.thick + 1 : st.thick);
        label(canvas, fmt::format("{:.2f}", f.score), {tl.x, tl.y - 6}, {0, 0, 0}, c, st);
      }
    }
  }

  // Landmarks of this camera.
  std::shared_ptr<const FaceLandmarks> lm_keep;
  if (const FaceLandmarks* lm = this_tick(view, keys::kFaceLandmarks, t, lm_keep);
      lm != nullptr && lm->camera == camera) {
    const double k = rescale(lm->image_size, shown);
    for (const cv::Point2d& p : lm->points_px)
      if (std::isfinite(p.x) && std::isfinite(p.y))
        cv::circle(canvas, map(p * k), std::max(1, st.thin), overlay_colors::kLandmark, cv::FILLED,
                   cv::LINE_AA);
  }

  // Head axes (world, through this camera's model).
  std::shared_ptr<const HeadPose> head_keep;
  if (const HeadPose* head = this_tick(view, keys::kHeadPose, t, head_keep)) {
    const cv::Vec3d o = head->position_world_m;
    const double L = options.head_axis_length_m;
    const cv::Scalar axis_colour[3] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}};
    for (int a = 0; a < 3; ++a) {
      cv::Vec3d e(0, 0, 0);
      e[a] = L;
      draw_segment(canvas, map, model, shown, o, o + head->world_from_head * e, axis_colour[a],
                   st.thick);
    }
  }

  // Eye centres of this camera.
  std::shared_ptr<const EyeCenters> eyes_keep;
  if (const EyeCenters* eyes = this_tick(view, keys::kEyeCenters, t, eyes_keep);
      eyes != nullptr && eyes->camera == camera) {
    for (const EyeCenter* e : {&eyes->right, &eyes->left})
      if (e->found)
        cv::circle(canvas, map(e->center_px), std::max(3, st.thick + 1), overlay_colors::kEyeCenter,
                   st.thin, cv::LINE_AA);
  }

  // Gaze rays.
  std::shared_ptr<const EyeGaze> gaze_keep;
  if (const EyeGaze* gaze = this_tick(view, keys::kEyeGaze, t, gaze_keep)) {
    for (const GazeRay* r : {&gaze->right, &gaze->left, &gaze->both}) {
      if (!r->valid) continue;
      draw_segment(canvas, map, model, shown, r->origin_world_m,
                   r->origin_world_m + r->direction_world * options.gaze_length_m,
                   overlay_colors::kGaze, r == &gaze->both ? st.thick : st.thin);
    }
  }

  // The child's skeleton (world joints, through this camera's model).
  std::shared_ptr<const BodyState> body_keep;
  if (const BodyState* body =
          options.skeleton ? this_tick(view, keys::kChildBody, t, body_keep) : nullptr) {
    for (const auto& [a, b] : kSkeletonBones) {
      const JointObservation &ja = body->body.joint(a), &jb = body->body.joint(b);
      if (ja.valid() && jb.valid())
        draw_segment(canvas, map, model, shown, ja.position_m, jb.position_m,
                     overlay_colors::kSkeleton, st.thin);
    }
  }

  const int line = static_cast<int>(std::lround(28 * st.font / 0.5));
  // Selected camera: a frame around the picture.
  if (sel != nullptr && sel->camera == camera && !image.empty())
    cv::rectangle(
        canvas,
        cv::Rect(cv::Point(static_cast<int>(map.offset.x), static_cast<int>(map.offset.y)),
                 cv::Size(static_cast<int>(std::lround(shown.width * map.scale)),
                          static_cast<int>(std::lround(shown.height * map.scale)))),
        overlay_colors::kSelectedFaceBox, st.thick);

  // Sound direction, gesture (left, above the mutual-gaze box) and the last utterance (subtitle).
  int row = out_size.height - line / 2 - line;
  std::shared_ptr<const SoundDirection> sound_keep;
  if (const SoundDirection* sd =
          options.sound_direction
              ? recent(view, keys::kSoundDirection, t, Duration::from_seconds(0.5), sound_keep)
              : nullptr) {
    label(canvas, fmt::format("sound az {:+.0f} deg", sd->azimuth_deg), {8, row}, {255, 255, 255},
          {90, 60, 20}, st);
    row -= line;
  }
  std::shared_ptr<const ActionState> action_keep;
  if (const ActionState* action =
          options.gesture ? this_tick(view, keys::kChildAction, t, action_keep) : nullptr;
      action != nullptr && action->ready && action->label != "none") {
    double score = 0;
    for (const auto& [name, p] : action->scores)
      if (name == action->label) score = p;
    label(canvas, fmt::format("gesture {} {:.2f}", action->label, score), {8, row}, {0, 0, 0},
          overlay_colors::kSkeleton, st);
  }
  std::shared_ptr<const RecognizedSpeech> speech_keep;
  if (const RecognizedSpeech* speech =
          options.subtitles ? recent(view, keys::kRecognizedSpeech, t,
                                     Duration::from_seconds(options.subtitle_s), speech_keep)
                            : nullptr) {
    std::shared_ptr<const SpeakerIdentity> speaker_keep;
    const SpeakerIdentity* speaker = recent(
        view, keys::kSpeakerIdentity, t, Duration::from_seconds(options.subtitle_s), speaker_keep);
    std::string text = "\"" + speech->text + "\"";
    if (speaker != nullptr) text += " - " + speaker->speaker_id;
    int baseline = 0;
    const int w =
        cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, st.font, st.thin, &baseline).width;
    label(canvas, text, {(out_size.width - w) / 2, out_size.height - 2 * line - line / 2},
          {255, 255, 255}, {0, 0, 0}, st);
  }

  // Legend (bottom right).
  if (options.legend) {
    const std::pair<const char*, cv::Scalar> items[] = {
        {"face", overlay_colors::kFaceBox},
        {"selected face", overlay_colors::kSelectedFaceBox},
        {"landmarks", overlay_colors::kLandmark},
        {"eye centres", overlay_colors::kEyeCenter},
        {"gaze", overlay_colors::kGaze},
        {"head x/y/z", {0, 0, 255}},
        {"skeleton", overlay_colors::kSkeleton}};
    const double small = st.font * 0.8;
    const int step = static_cast<int>(std::lround(line * 0.8));
    int y = out_size.height - static_cast<int>(std::size(items)) * step - line / 2;
    for (const auto& [name, colour] : items) {
      int baseline = 0;
      const cv::Size sz = cv::getTextSize(name, cv::FONT_HERSHEY_SIMPLEX, small, 1, &baseline);
      const int x = out_size.width - sz.width - step - 8;
      cv::rectangle(canvas, {x - step, y - sz.height}, {x - 4, y}, colour, cv::FILLED);
      cv::putText(canvas, name, {x, y}, cv::FONT_HERSHEY_SIMPLEX, small, {255, 255, 255}, 1,
                  cv::LINE_AA);
      y += step;
    }
  }

  // Header: shown camera, selection, time.
  label(canvas, fmt::format("{} (DREAM {})", camera, dream::camera_id(camera)), {8, line},
        {255, 255, 255}, {40, 40, 40}, st);
  const std::string sel_text = sel == nullptr ? std::string("selected: none")
                                              : fmt::format("selected: {} (DREAM {})", sel->camera,
                                                            dream::camera_id(sel->camera));
  label(canvas, sel_text, {8, 2 * line},
        sel != nullptr && sel->camera == camera ? cv::Scalar(0, 0, 0) : cv::Scalar(255, 255, 255),
        sel != nullptr && sel->camera == camera ? overlay_colors::kSelectedFaceBox
                                                : cv::Scalar(40, 40, 40),
        st);
  label(canvas, fmt::format("t {:.2f} s  #{}", t.is_set() ? t.seconds() : 0.0, tick.tick),
        {out_size.width, line}, {255, 255, 255}, {40, 40, 40}, st);

  // Mutual gaze indicator.
  std::shared_ptr<const MutualGaze> mg_keep;
  const MutualGaze* mg = this_tick(view, keys::kMutualGaze, t, mg_keep);
  if (mg != nullptr && mg->mutual)
    label(canvas, fmt::format("MUTUAL {:.1f} s", mg->held_s), {8, out_size.height - line / 2},
          {255, 255, 255}, overlay_colors::kMutual, st);
  else
    label(canvas, mg != nullptr ? "no mutual gaze" : "no gaze", {8, out_size.height - line / 2},
          {230, 230, 230}, overlay_colors::kNoMutual, st);
  return canvas;
}

struct OverlayWriter::Impl {
  OverlayOptions options;
  fs::path final_path, partial_path;
  bool open = false;
  cv::VideoWriter writer;
  cv::Size size;
  cv::Mat last;
  int64_t frames = 0;
  int64_t pending = 0;  // ticks before the first picture
  std::optional<SensorId> shown;
  std::string codec;
  std::vector<SensorId> tiles;              // mosaic: the cameras, in order
  std::map<SensorId, cv::Mat> last_images;  // mosaic: each camera's last frame

  // Starts the encoder for pictures of `picture_size`' aspect: the configured fourcc, else mp4v.
  Status start(cv::Size picture_size) {
    const int h =
        2 * std::max(1, static_cast<int>(std::lround(options.width_px * picture_size.height /
                                                     (2.0 * std::max(1, picture_size.width)))));
    size = cv::Size(options.width_px - options.width_px % 2, h);
    std::vector<std::string> tries{options.fourcc};
    if (options.fourcc != "mp4v") tries.emplace_back("mp4v");
    for (const std::string& f : tries) {
      if (writer.open(partial_path.string(), cv::CAP_FFMPEG,
                      cv::VideoWriter::fourcc(f[0], f[1], f[2], f[3]), options.fps, size, true)) {
        if (f != options.fourcc)
          log::warn("{}: no '{}' encoder in OpenCV's FFmpeg, written as '{}'", final_path.string(),
                    options.fourcc, f);
        codec = f;
        return ok_status();
      }
    }
    std::error_code ec;
    fs::remove(partial_path, ec);
    return make_error(ErrorCode::kUnsupported,
                      "{}: cannot encode '{}' video with OpenCV's FFmpeg backend",
                      final_path.string(), options.fourcc);
  }

  // Mosaic: every camera's last picture in a grid of tiles, each with its own overlay.
  cv::Mat draw_mosaic(const MultiFrame& tick, const BlackboardView& view) const {
    const int n = static_cast<int>(tiles.size());
    const int cols = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
    const int rows = (n + cols - 1) / cols;
    cv::Mat canvas(size, CV_8UC3, cv::Scalar::all(0));
    const cv::Size tile(size.width / cols, size.height / rows);
    OverlayOptions o = options;
    o.legend = false;
    for (int i = 0; i < n; ++i) {
      const auto it = last_images.find(tiles[static_cast<size_t>(i)]);
      if (it == last_images.end()) continue;
      o.legend = i == n - 1;
      draw_overlay(it->second, it->first, tick, view, o, tile)
          .copyTo(canvas(cv::Rect((i % cols) * tile.width, (i / cols) * tile.height, tile.width,
                                  tile.height)));
    }
    return canvas;
  }

  void write(const cv::Mat& picture) {
    writer.write(picture);
    ++frames;
  }
};

OverlayWriter::OverlayWriter() : impl_(std::make_unique<Impl>()) {}
OverlayWriter::~OverlayWriter() { abandon(); }

Status OverlayWriter::open(const fs::path& path, const OverlayOptions& options) {
  abandon();
  if (auto s = options.check(); !s) return s;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (auto s = ensure_writable_dir(dir); !s) return s;
  Impl& m = *impl_;
  m.options = options;
  m.size = {};
  m.last.release();
  m.frames = 0;
  m.pending = 0;
  m.shown.reset();
  m.codec.clear();
  m.tiles.clear();
  m.last_images.clear();
  m.final_path = path;
  m.partial_path = dir / (path.stem().string() + ".partial" + path.extension().string());
  std::error_code ec;
  fs::remove(path, ec);  // never leave an older complete file behind
  fs::remove(m.partial_path, ec);
  m.open = true;
  return ok_status();
}

Status OverlayWriter::add(const MultiFrame& tick, const BlackboardView& view) {
  Impl& m = *impl_;
  if (!m.open) return make_error(ErrorCode::kFailedPrecondition, "overlay: add() before open()");

  // Which camera to show.
  SensorId camera;
  if (m.options.camera != "selected") {
    camera = m.options.camera;
  } else {
    const auto sel = view.get(keys::kSelectedCamera);
    if (sel && sel->stamp == tick.stamp && sel->present()) {
      camera = sel->value->camera;
    } else if (m.shown) {
      camera = *m.shown;
    } else if (color_image(tick, "camera_middle") != nullptr) {
      camera = "camera_middle";
    } else {
      for (const auto& [id, f] : tick.frames)
        if (color_image(tick, id) != nullptr) {
          camera = id;
          break;
        }
    }
  }
  const cv::Mat* image = camera.empty() ? nullptr : color_image(tick, camera);
  if (image == nullptr) {  // repeat the last picture (or wait for the first)
    if (m.last.empty())
      ++m.pending;
    else
      m.write(m.last);
    return ok_status();
  }

  if (m.options.mosaic) {
    if (m.tiles.empty())
      for (const auto& [id, f] : tick.frames)
        if (color_image(tick, id) != nullptr) m.tiles.push_back(id);
    for (const SensorId& id : m.tiles)
      if (const cv::Mat* img = color_image(tick, id)) m.last_images[id] = *img;
    if (!m.writer.isOpened()) {
      const int n = static_cast<int>(m.tiles.size());
      const int cols = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
      const int rows = (n + cols - 1) / cols;
      if (auto s = m.start({image->cols * cols, image->rows * rows}); !s) return s;
    }
    m.last = m.draw_mosaic(tick, view);
    for (; m.pending > 0; --m.pending) m.write(m.last);
    m.write(m.last);
    return ok_status();
  }
  if (!m.writer.isOpened())
    if (auto s = m.start(image->size()); !s) return s;
  m.shown = camera;
  m.last = draw_overlay(*image, camera, tick, view, m.options, m.size);
  for (; m.pending > 0; --m.pending) m.write(m.last);
  m.write(m.last);
  return ok_status();
}

Status OverlayWriter::commit() {
  Impl& m = *impl_;
  if (!m.open) return make_error(ErrorCode::kFailedPrecondition, "overlay: not open");
  if (!m.writer.isOpened()) {
    const fs::path p = m.final_path;
    abandon();
    return make_error(ErrorCode::kNotFound, "{}: no frame of the shown camera in any tick",
                      p.string());
  }
  m.writer.release();
  std::error_code ec;
  const auto bytes = fs::file_size(m.partial_path, ec);
  if (ec || bytes == 0) {
    const fs::path p = m.final_path;
    abandon();
    return make_error(ErrorCode::kIoError, "{}: the encoder wrote nothing", p.string());
  }
  fs::rename(m.partial_path, m.final_path, ec);
  if (ec) {
    const fs::path p = m.final_path;
    abandon();
    return make_error(ErrorCode::kIoError, "{}: cannot rename: {}", p.string(), ec.message());
  }
  m.open = false;
  return ok_status();
}

void OverlayWriter::abandon() {
  Impl& m = *impl_;
  if (m.writer.isOpened()) m.writer.release();
  if (m.open) {
    std::error_code ec;
    fs::remove(m.partial_path, ec);
  }
  m.open = false;
}

bool OverlayWriter::is_open() const { return impl_->open; }
int64_t OverlayWriter::frames_written() const { return impl_->frames; }
cv::Size OverlayWriter::frame_size() const { return impl_->size; }
std::string OverlayWriter::codec() const { return impl_->codec; }
const fs::path& OverlayWriter::path() const { return impl_->final_path; }

}  // namespace dreamsense::exporters
