#pragma once
// Toys on the table in the top camera's colour image: the table region, a background model of
// it, and the blobs that differ from it.
//
// DREAM's detector (original-dream.md §3.6) differenced the frame against a stored photograph of
// the empty table (threshold 50) inside a fixed ROI and grouped the pixels into blobs. Here the
// table and its background are learnt from the session itself, so nothing has to be
// photographed beforehand and toys may already lie on the table:
//  1. Table region (initialise): the dominant colour of the image centre is the table's; the
//     largest connected region of that colour (closed, convex hull) is the table. When the table
//     polygon is known from the calibration (table corners projected into the image) it is used
//     instead.
//  2. Background: the table image with every pixel that is not table-coloured filled in from its
//     table-coloured neighbourhood (normalised box convolution); afterwards a running average
//     updated only at pixels that are background in this frame and outside the boxes the caller
//     marks as occupied (tracked toys), so a toy that stands still is never learnt away.
//  3. Detection (every frame, at 1/downscale resolution): pixels whose colour differs from the
//     background by more than `foreground_threshold` (sum of absolute BGR differences), opened
//     and closed, grouped into connected components; components of implausible size are
//     dropped; a component that reaches the table's border is flagged `touches_edge`: an arm or
//     hand entering from the child's side (or a toy pushed to the edge), which the caller does
//     not take for a toy unless identification is sure.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace dreamsense::objects {

struct TableTopDetectorOptions {
  int downscale = 2;                   // work at 1/downscale resolution (1, 2 or 4)
  double foreground_threshold = 60;    // sum of |dB| + |dG| + |dR| above which a pixel is not table
  double table_colour_tolerance = 60;  // same measure, table segmentation at initialise()
  double background_rate = 0.05;       // running-average rate of background pixels per frame
  double min_area_px = 150;            // blob area limits, full-resolution pixels
  double max_area_px = 40000;
  int edge_margin_px = 6;         // full-resolution px: a blob this close to the table border
                                  // touches the edge
  int open_px = 3, close_px = 5;  // morphology kernels (working resolution)
  Status check() const;
};

struct ObjectCandidate {
  cv::Rect box;               // full-resolution pixels
  cv::RotatedRect footprint;  // minimum-area rectangle of the blob (full resolution)
  cv::Point2d centroid;       // of the blob pixels (full resolution)
  double area_px = 0;         // full-resolution pixels
  bool touches_edge = false;
  cv::Mat mask;  // CV_8U, box.size(): 255 on the blob
};

class TableTopDetector {
 public:
  explicit TableTopDetector(TableTopDetectorOptions options = {});
  // Learns the table region and the background from one BGR frame (toys may lie on the table).
  // `table_polygon`: the table's outline in the image when the calibration knows it (>= 3
  // points); empty: found from colour. Error when no table-coloured region is found.
  Status initialise(const cv::Mat& bgr, const std::vector<cv::Point2f>& table_polygon = {});
  bool initialised() const { return !background_.empty(); }
  // Candidates in this frame (initialises on the first call). `occupied`: boxes (full
  // resolution) where the background must not learn (current tracks).
  Result<std::vector<ObjectCandidate>> detect(const cv::Mat& bgr,
                                              const std::vector<cv::Rect>& occupied = {});
  // Full-resolution table mask (255 = table), empty before initialise().
  cv::Mat table_mask() const;
  cv::Size frame_size() const { return frame_size_; }
  void reset();

 private:
  cv::Mat shrink(const cv::Mat& bgr) const;

  TableTopDetectorOptions o_;
  cv::Size frame_size_;
  cv::Mat table_;       // working resolution, 255 = table
  cv::Mat inner_;       // table minus the border band
  cv::Mat background_;  // working resolution, CV_32FC3
  cv::Mat small_, diff_, fg_, labels_, stats_, centroids_, learn_;
};

}  // namespace dreamsense::objects
