#include "dreamsense/face_detection/face_tracker.hpp"

#include "dreamsense/perception/face_detection.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::face_detection {
namespace {

// A face of this frame and the in-plane angle it was found (or placed) at.
struct Found {
  DetectedFace face;
  double roll_deg = 0;
};

std::vector<Found> at_roll(const std::vector<DetectedFace>& faces, double roll_deg) {
  std::vector<Found> out;
  for (const DetectedFace& f : faces) out.push_back({f, roll_deg});
  return out;
}

// Keeps the better of overlapping detections; result best score first.
std::vector<Found> merge(std::vector<Found> faces, double merge_iou) {
  std::stable_sort(faces.begin(), faces.end(),
                   [](const Found& a, const Found& b) { return a.face.score > b.face.score; });
  std::vector<Found> kept;
  for (const Found& f : faces) {
    bool dup = false;
    for (const Found& k : kept) dup = dup || box_iou(f.face.box_px, k.face.box_px) > merge_iou;
    if (!dup) kept.push_back(f);
  }
  return kept;
}

}  // namespace

cv::Rect2d grown_by(const cv::Rect2d& box, double margin) {
  const double m = margin * std::max(box.width, box.height);
  return {box.x - m, box.y - m, box.width + 2 * m, box.height + 2 * m};
}

std::vector<DetectedFace> detect_rolled(FaceDetector& detector, const cv::Mat& image,
                                        const cv::Rect& region, double roll_deg, double min_face_px,
                                        double max_face_px) {
  if (roll_deg == 0)
    return detector.detect(image, SearchRegion{region, min_face_px, max_face_px}, false);
  if (region.empty() || image.empty()) return {};
  // The region's centre stays the canvas centre; the image turns by roll_deg about it (OpenCV:
  // positive = counter-clockwise on screen, which makes a face rolled by +roll_deg upright).
  const cv::Point2f centre(static_cast<float>(region.x + region.width / 2.0),
                           static_cast<float>(region.y + region.height / 2.0));
  cv::Mat M = cv::getRotationMatrix2D(centre, roll_deg, 1.0);
  const double shift_x = region.width / 2.0 - centre.x, shift_y = region.height / 2.0 - centre.y;
  M.at<double>(0, 2) += shift_x;
  M.at<double>(1, 2) += shift_y;
  cv::Mat canvas;
  cv::warpAffine(image, canvas, M, region.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  std::vector<DetectedFace> faces = detector.detect(
      canvas, SearchRegion{cv::Rect(0, 0, canvas.cols, canvas.rows), min_face_px, max_face_px},
      false);
  cv::Mat back;
  cv::invertAffineTransform(M, back);
  for (DetectedFace& f : faces) {
    const cv::Point2d c(f.box_px.x + f.box_px.width / 2, f.box_px.y + f.box_px.height / 2);
    const cv::Point2d p(
        back.at<double>(0, 0) * c.x + back.at<double>(0, 1) * c.y + back.at<double>(0, 2),
        back.at<double>(1, 0) * c.x + back.at<double>(1, 1) * c.y + back.at<double>(1, 2));
    f.box_px.x = p.x - f.box_px.width / 2;
    f.box_px.y = p.y - f.box_px.height / 2;
  }
  // Keep faces whose centre lies in the image (the replicated border holds no real face).
  std::erase_if(faces, [&](const DetectedFace& f) {
    const double cx = f.box_px.x + f.box_px.width / 2, cy = f.box_px.y + f.box_px.height / 2;
    return cx < 0 || cy < 0 || cx >= image.cols || cy >= image.rows;
  });
  return faces;
}

Status FaceTrackerOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (full_search_interval < 1)
    add(fmt::format("full_search_interval {} < 1", full_search_interval));
  if (full_search_phase < 0) add(fmt::format("full_search_phase {} < 0", full_search_phase));
  if (frontalness_interval < 1)
    add(fmt::format("frontalness_interval {} < 1", frontalness_interval));
  if (lost_search_interval < 1)
    add(fmt::format("lost_search_interval {} < 1", lost_search_interval));
  if (!(roi_margin >= 0)) add(fmt::format("roi_margin {} < 0", roi_margin));
  if (!(roi_min_scale > 0 && roi_min_scale <= 1 && roi_max_scale >= 1))
    add(fmt::format("roi scales [{}, {}] must satisfy 0 < min <= 1 <= max", roi_min_scale,
                    roi_max_scale));
  if (roi_narrow_first && !(roi_narrow_max_change > 0))
    add(fmt::format("roi_narrow_max_change {} <= 0", roi_narrow_max_change));
  if (roi_narrow_first &&
      !(roi_narrow_min_scale > 0 && roi_narrow_min_scale <= 1 && roi_narrow_max_scale >= 1))
    add(fmt::format("roi narrow scales [{}, {}] must satisfy 0 < min <= 1 <= max",
                    roi_narrow_min_scale, roi_narrow_max_scale));
  if (!(turned_away_yaw_deg >= 0 && turned_away_yaw_deg <= 180))
    add(fmt::format("turned_away_yaw_deg {} not in [0, 180]", turned_away_yaw_deg));
  if (turned_away_search_interval < 1)
    add(fmt::format("turned_away_search_interval {} < 1", turned_away_search_interval));
  if (!(merge_iou >= 0 && merge_iou < 1)) add(fmt::format("merge_iou {} not in [0, 1)", merge_iou));
  if (cascade_interval < 1) add(fmt::format("cascade_interval {} < 1", cascade_interval));
  if (!(guide_min_iou > 0 && guide_min_iou <= 1))
    add(fmt::format("guide_min_iou {} not in (0, 1]", guide_min_iou));
  if (!(roll_min_deg >= 0 && roll_min_deg <= 90))
    add(fmt::format("roll_min_deg {} not in [0, 90]", roll_min_deg));
  if (!(roll_step_deg >= 0 && roll_step_deg <= 90))
    add(fmt::format("roll_step_deg {} not in [0, 90]", roll_step_deg));
  if (!(lost_roll_deg >= 0 && lost_roll_deg <= 90))
    add(fmt::format("lost_roll_deg {} not in [0, 90]", lost_roll_deg));
  if (lost_roll_search_interval < 1)
    add(fmt::format("lost_roll_search_interval {} < 1", lost_roll_search_interval));
  if (!(lost_roll_max_yaw_deg >= 0 && lost_roll_max_yaw_deg <= 180))
    add(fmt::format("lost_roll_max_yaw_deg {} not in [0, 180]", lost_roll_max_yaw_deg));
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "FaceTrackerOptions: " + bad);
  return ok_status();
}

std::optional<BoxOnExtent> box_on_extent(const cv::Rect2d& box, const cv::Rect2d& extent) {
  if (!(extent.width > 0 && extent.height > 0)) return std::nullopt;
  return BoxOnExtent{(box.x + box.width / 2 - (extent.x + extent.width / 2)) / extent.width,
                     (box.y + box.height / 2 - (extent.y + extent.height / 2)) / extent.height,
                     box.width / extent.width, box.height / extent.height};
}

cv::Rect2d place_box(const BoxOnExtent& r, const cv::Rect2d& extent) {
  const double w = r.sx * extent.width, h = r.sy * extent.height;
  const double cx = extent.x + extent.width / 2 + r.dx * extent.width;
  const double cy = extent.y + extent.height / 2 + r.dy * extent.height;
  return {cx - w / 2, cy - h / 2, w, h};
}

FaceTracker::FaceTracker(FaceDetector detector, FaceTrackerOptions options)
    : detector_(std::move(detector)), options_(options) {
  DS_CHECK(options_.check().has_value());
}

void FaceTracker::reset() {
  tracked_.clear();
  frames_since_full_ = 0;
  guided_in_a_row_ = 0;
  lost_full_searches_ = 0;
}

std::vector<std::pair<DetectedFace, double>> FaceTracker::guided_faces(
    const std::vector<FaceGuide>& guides) const {
  std::vector<std::pair<DetectedFace, double>> faces;
  for (const Track& t : tracked_) {
    // The guide of this face: the one made from the box this tracker returned for it.
    const auto g = std::find_if(guides.begin(), guides.end(), [&](const FaceGuide& c) {
      return box_iou(c.tracked_box, t.box) > 0.999;
    });
    if (g == guides.end() || !(box_iou(g->box, t.box) >= options_.guide_min_iou)) return {};
    faces.emplace_back(DetectedFace{g->box, t.score, t.view, t.frontalness}, g->roll_deg);
  }
  return faces;
}

std::vector<DetectedFace> FaceTracker::search_region(const cv::Mat& image, const Track& track,
                                                     double roll_deg) {
  const double size = std::max(track.box.width, track.box.height);
  const cv::Rect2d grown = grown_by(track.box, options_.roi_margin);
  // Upright: the region clipped to the image. Rotated: the same region about the face's centre
  // (detect_rolled samples outside the image as its replicated border).
  const cv::Rect region_px =
      roll_deg == 0 ? cv::Rect(grown) & cv::Rect(0, 0, image.cols, image.rows) : cv::Rect(grown);
  if (region_px.empty()) return {};
  std::vector<DetectedFace> found;
  if (options_.roi_narrow_first) {
    found =
        detect_rolled(detector_, image, region_px, roll_deg, options_.roi_narrow_min_scale * size,
                      options_.roi_narrow_max_scale * size);
    // A box near the range's edge means the face may be beyond it (the windows stop there
    // and pull the box towards the last size): let the wide range decide.
    const bool settled = std::all_of(found.begin(), found.end(), [&](const DetectedFace& f) {
      const double change = std::max(f.box_px.width, f.box_px.height) / size;
      return std::abs(std::log(change)) <= std::log1p(options_.roi_narrow_max_change);
    });
    if (!settled) found.clear();
  }
  if (found.empty())
    found = detect_rolled(detector_, image, region_px, roll_deg, options_.roi_min_scale * size,
                          options_.roi_max_scale * size);
  return found;
}

TrackedFrameFaces FaceTracker::process(const cv::Mat& image, const KnownFrontalness& known,
                                       std::optional<double> head_yaw_deg,
                                       const std::vector<FaceGuide>& guides) {
  TrackedFrameFaces out;
  const int64_t index = frame_index_++;
  if (image.size() != last_size_) tracked_.clear();  // a new geometry: old boxes mean nothing
  last_size_ = image.size();
  ++frames_since_full_;
  bool full = false;
  if (tracked_.empty()) {
    const bool turned_away = head_yaw_deg && std::abs(*head_yaw_deg) > options_.turned_away_yaw_deg;
    const int interval =
        turned_away ? std::max(options_.lost_search_interval, options_.turned_away_search_interval)
                    : options_.lost_search_interval;
    full = index == 0 || frames_since_full_ >= interval;
  } else {
    full = (index + options_.full_search_phase) % options_.full_search_interval == 0;
  }

  std::vector<Found> faces;
  if (!full && !tracked_.empty() && guided_in_a_row_ + 1 < options_.cascade_interval) {
    for (auto& [face, roll] : guided_faces(guides)) faces.push_back({face, roll});
    out.guided = !faces.empty();
  }
  guided_in_a_row_ = out.guided ? guided_in_a_row_ + 1 : 0;
  if (!full && !tracked_.empty() && !out.guided) {
    // Around each tracked face: upright, or rotated upright when it is rolled; then, if that
    // finds nothing and rotated searches are on, rolled a step further either way.
    for (const Track& track : tracked_) {
      const double roll = std::abs(track.roll_deg) >= options_.roll_min_deg ? track.roll_deg : 0;
      std::vector<DetectedFace> found = search_region(image, track, roll);
      double found_roll = roll;
      if (found.empty() && options_.roll_step_deg > 0)
        for (const double step : {-options_.roll_step_deg, options_.roll_step_deg}) {
          found = search_region(image, track, track.roll_deg + step);
          found_roll = track.roll_deg + step;
          if (!found.empty()) break;
        }
      for (const Found& f : at_roll(found, found_roll)) faces.push_back(f);
    }
    if (faces.empty() && options_.full_search_on_miss) full = true;
  }
  if (full) {
    faces = at_roll(detector_.detect(image, std::nullopt, false), 0);
    frames_since_full_ = 0;
    // Rotated full searches while lost: in the first lost frame, then every
    // lost_roll_search_interval frames; not while the head is known to face away from this
    // camera (the frontal cascade would not find it rotated either).
    const bool facing = !head_yaw_deg || std::abs(*head_yaw_deg) <= options_.lost_roll_max_yaw_deg;
    bool rotated = false;
    if (!faces.empty() || !tracked_.empty())
      lost_full_searches_ = 0;
    else
      rotated = options_.lost_roll_deg > 0 && facing &&
                lost_full_searches_++ % options_.lost_roll_search_interval == 0;
    if (rotated) {
      // Nothing upright and nothing tracked: a face may be rolled beyond the cascade's reach.
      const cv::Rect whole(0, 0, image.cols, image.rows);
      for (const double roll : {-options_.lost_roll_deg, options_.lost_roll_deg}) {
        for (const Found& f : at_roll(detect_rolled(detector_, image, whole, roll), roll))
          faces.push_back(f);
      }
    }
  }
  const std::vector<Found> kept = merge(std::move(faces), options_.merge_iou);
  for (const Found& f : kept) out.faces.push_back(f.face);
  out.full_search = full;
  // Frontalness: carried over from the same face in the previous frame while young enough.
  std::vector<Track> next;
  const bool estimate = detector_.options().estimate_frontalness;
  for (size_t i = 0; i < out.faces.size(); ++i) {
    DetectedFace& f = out.faces[i];
    Track t{f.box_px, f.frontalness, 0, f.score, f.view, kept[i].roll_deg};
    const std::optional<float> given =
        known && f.view == FaceView::kFrontal ? known(out.faces, i) : std::nullopt;
    if (given) {
      // No proxy this frame; the age makes the next frame without a known value re-estimate it.
      f.frontalness = *given;
      t.frontalness = *given;
      t.frontalness_age = options_.frontalness_interval;
    } else if (estimate && f.view == FaceView::kFrontal) {
      const Track* prev = nullptr;
      for (const Track& p : tracked_)
        if (box_iou(p.box, f.box_px) > options_.merge_iou &&
            (prev == nullptr || box_iou(p.box, f.box_px) > box_iou(prev->box, f.box_px)))
          prev = &p;
      if (prev != nullptr && prev->frontalness_age + 1 < options_.frontalness_interval) {
        t.frontalness = prev->frontalness;
        t.frontalness_age = prev->frontalness_age + 1;
      } else {
        t.frontalness = detector_.frontalness(image, f.box_px);
        // A new face starts at an age given by the phase, so cameras re-estimate in turn.
        t.frontalness_age =
            prev == nullptr ? options_.full_search_phase % options_.frontalness_interval : 0;
      }
      f.frontalness = t.frontalness;
    }
    next.push_back(t);
  }
  tracked_ = std::move(next);
  return out;
}

}  // namespace dreamsense::face_detection
