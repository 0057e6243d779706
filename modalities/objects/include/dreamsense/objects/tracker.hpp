#pragma once
// One interface for every single-object tracker: the project's own (`ct`, compressive tracking as
// published; `dreamsense`, the improved correlation-filter tracker) and OpenCV's baselines (`kcf`,
// `csrt`, `mil`, `mosse`, `medianflow`), so that `eval tracking` and the table-top pipeline run
// them through the same calls.
//
// Boxes are in pixels of the frame, 0-based, (x, y) = top-left corner, floating point.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::objects {

struct TrackerUpdate {
  cv::Rect2d box;         // the estimate in this frame (the last one when `found` is false)
  bool found = true;      // false: the tracker itself reports the target lost in this frame
  double confidence = 1;  // tracker-specific, larger = surer; 0..1 for ct and dreamsense
};

class Tracker {
 public:
  virtual ~Tracker() = default;
  virtual std::string_view name() const = 0;
  // `frame`: 8-bit BGR (CV_8UC3) or grey (CV_8UC1). Error (kInvalidArgument) for an empty frame,
  // an empty or non-finite box, or a box mostly outside the frame (check_init_box).
  virtual Status init(const cv::Mat& frame, const cv::Rect2d& box) = 0;
  // Error for an empty frame, a frame of another size/type than init's, or a call before init.
  virtual Result<TrackerUpdate> update(const cv::Mat& frame) = 0;
};

// Names make_tracker accepts, the project's first: ct, dreamsense, kcf, csrt, mil, mosse,
// medianflow.
const std::vector<std::string>& tracker_names();
// Error (kInvalidArgument) naming the known trackers for an unknown name.
Result<std::unique_ptr<Tracker>> make_tracker(std::string_view name);

// The checks every init() applies: a non-empty 8-bit 1- or 3-channel frame; a finite box with
// width and height >= 2 px; at least half of its area inside the frame.
Status check_init_box(const cv::Mat& frame, const cv::Rect2d& box);
// The checks every update() applies (same size and type as the frame given to init).
Status check_update_frame(const cv::Mat& frame, const cv::Size& init_size, int init_type);

// Intersection over union of two boxes (0 when either is empty).
double iou(const cv::Rect2d& a, const cv::Rect2d& b);
inline cv::Point2d box_centre(const cv::Rect2d& b) {
  return {b.x + 0.5 * b.width, b.y + 0.5 * b.height};
}

}  // namespace dreamsense::objects
