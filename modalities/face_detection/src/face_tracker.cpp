#include "dreamsense/face_detection/face_tracker.hpp"

#include "dreamsense/perception/face_detection.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::face_detection {
namespace {

// Keeps the better of overlapping detections; result best score first.
std::vector<DetectedFace> merge(std::vector<DetectedFace> faces, double merge_iou) {
  std::stable_sort(faces.begin(), faces.end(),
                   [](const DetectedFace& a, const DetectedFace& b) { return a.score > b.score; });
  std::vector<DetectedFace> kept;
  for (const DetectedFace& f : faces) {
    bool dup = false;
    for (const DetectedFace& k : kept) dup = dup || box_iou(f.box_px, k.box_px) > merge_iou;
    if (!dup) kept.push_back(f);
  }
  return kept;
}

}  // namespace

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
}

std::vector<DetectedFace> FaceTracker::guided_faces(const std::vector<FaceGuide>& guides) const {
  std::vector<DetectedFace> faces;
  for (const Track& t : tracked_) {
    // The guide of this face: the one made from the box this tracker returned for it.
    const auto g = std::find_if(guides.begin(), guides.end(), [&](const FaceGuide& c) {
      return box_iou(c.tracked_box, t.box) > 0.999;
    });
    if (g == guides.end() || !(box_iou(g->box, t.box) >= options_.guide_min_iou)) return {};
    faces.push_back(DetectedFace{g->box, t.score, t.view, t.frontalness});
  }
  return faces;
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

  std::vector<DetectedFace> faces;
  if (!full && !tracked_.empty() && guided_in_a_row_ + 1 < options_.cascade_interval) {
    faces = guided_faces(guides);
    out.guided = !faces.empty();
  }
  guided_in_a_row_ = out.guided ? guided_in_a_row_ + 1 : 0;
  if (!full && !tracked_.empty() && !out.guided) {
    // Around each tracked face: the narrow size range first, the wide one if that finds nothing.
    for (const Track& track : tracked_) {
      const cv::Rect2d& t = track.box;
      const double size = std::max(t.width, t.height);
      const double m = options_.roi_margin * size;
      const cv::Rect region_px =
          cv::Rect(cv::Rect2d(t.x - m, t.y - m, t.width + 2 * m, t.height + 2 * m)) &
          cv::Rect(0, 0, image.cols, image.rows);
      if (region_px.empty()) continue;
      std::vector<DetectedFace> found;
      if (options_.roi_narrow_first) {
        found = detector_.detect(image,
                                 SearchRegion{region_px, options_.roi_narrow_min_scale * size,
                                              options_.roi_narrow_max_scale * size},
                                 false);
        // A box near the range's edge means the face may be beyond it (the windows stop there
        // and pull the box towards the last size): let the wide range decide.
        const bool settled = std::all_of(found.begin(), found.end(), [&](const DetectedFace& f) {
          const double change = std::max(f.box_px.width, f.box_px.height) / size;
          return std::abs(std::log(change)) <= std::log1p(options_.roi_narrow_max_change);
        });
        if (!settled) found.clear();
      }
      if (found.empty())
        found = detector_.detect(
            image,
            SearchRegion{region_px, options_.roi_min_scale * size, options_.roi_max_scale * size},
            false);
      faces.insert(faces.end(), found.begin(), found.end());
    }
    if (faces.empty() && options_.full_search_on_miss) full = true;
  }
  if (full) {
    faces = detector_.detect(image, std::nullopt, false);
    frames_since_full_ = 0;
  }
  out.faces = merge(std::move(faces), options_.merge_iou);
  out.full_search = full;
  // Frontalness: carried over from the same face in the previous frame while young enough.
  std::vector<Track> next;
  const bool estimate = detector_.options().estimate_frontalness;
  for (size_t i = 0; i < out.faces.size(); ++i) {
    DetectedFace& f = out.faces[i];
    Track t{f.box_px, f.frontalness, 0, f.score, f.view};
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
