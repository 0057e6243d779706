#pragma once
// The eye region a locator searches: geometry of one eye from its six dlib contour landmarks,
// the search window for centre candidates and the iris-radius prior. Method and numbers:
// modalities/eye_centers/README.md.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <span>

namespace dreamsense::eye_centers {

// Geometry of one eye from the six contour points of the iBUG 300-W mark-up, in image order:
// p0 = the image-left corner, p1 p2 = upper lid (left to right), p3 = the image-right corner,
// p4 p5 = lower lid (right to left). Both eyes of the 68-point mark-up are in this order
// (36-41: 36 outer corner ... ; 42-47: 42 inner corner ...).
struct EyeRegion {
  std::array<cv::Point2d, 6> contour_px;
  cv::Point2d center_px;  // centroid of the six points
  double angle_rad = 0;   // direction of p0 -> p3 (0 = horizontal; positive turns towards +y)
  double width_px = 0;    // |p3 - p0|, corner to corner
  double opening_px = 0;  // lid to lid: (|p1 - p5| + |p2 - p4|) / 2
  double opening_ratio() const { return width_px > 0 ? opening_px / width_px : 0; }
  bool finite() const;
};

// Requires exactly six points (always-on check: a programmer error otherwise).
EyeRegion eye_region_from_contour(std::span<const cv::Point2d> contour_px);

// What every locator does with an EyeRegion. Lengths marked "x width" are fractions of the eye's
// corner-to-corner width, so the same options work at any image resolution.
struct EyeRegionOptions {
  // The eye is resampled into a patch whose x axis is the corner line (head roll removed) and
  // whose scale puts the eye width in [min_work_width_px, max_work_width_px]: small eyes are
  // upsampled (finer radius sampling), large ones downsampled (bounded cost).
  double min_work_width_px = 24;
  double max_work_width_px = 48;
  // Rejections (found = false, not errors): the eye is narrower than this in the image ...
  double min_eye_width_px = 8;
  // ... or closed: lid-to-lid distance below min_opening_px or below min_opening_ratio x width
  // (an open eye is about 0.25-0.35 x width in the 68-point mark-up, a closed one below 0.15).
  double min_opening_px = 2.0;
  double min_opening_ratio = 0.12;
  // ... or the patch has no contrast (grey-level standard deviation, 0-255 scale).
  double min_contrast = 2.0;
  // Candidate centres: between the corners but at least corner_inset x width away from them,
  // and from vertical_slack x width above the upper lid to as far below the lower lid.
  double corner_inset = 0.12;
  double vertical_slack = 0.10;
  // Iris radius prior (x width): the human iris is ~12 mm wide in a ~28-30 mm eye (corner to
  // corner), radius ~0.2. Below ~0.16 the limbus search can lock onto the pupil edge.
  double min_iris_radius = 0.16;
  double max_iris_radius = 0.32;
  Status check() const;
};

}  // namespace dreamsense::eye_centers
