#pragma once
// `eval landmarks` (spec/cli.md task "landmarks"): face detection + 68 landmarks on real faces in
// the 300-W layout (NAME.jpg + NAME.pts), run as the pipeline runs them, per detector chain, and
// the landmarker alone from the annotated box. Method and numbers: modalities/face_landmarks/
// README.md ("Real faces").

#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/report.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::eval::landmarks {

// ---- 300-W annotations -------------------------------------------------------------------------

// Reads a 300-W .pts file: either the iBUG layout (`version: 1`, `n_points: 68`, `{`, 68 lines
// `x y`, `}`) or bare `x y` lines. Errors (one line naming the file and line): missing or
// unreadable file, a non-number, a line without two values, a point count other than
// `expected_points` (or than the header's n_points), a missing `}`. iBUG coordinates are 1-based
// (Matlab); they are returned as read.
Result<std::vector<cv::Point2d>> read_pts(const std::filesystem::path& file,
                                          int expected_points = 68);

struct LandmarkItem {
  std::string name;             // file stem, e.g. "111076519_1"
  std::filesystem::path image;  // NAME.jpg (or .png/.jpeg)
  std::filesystem::path pts;    // NAME.pts
};

// The items of a 300-W folder, sorted by name. An image without its .pts (or a .pts without its
// image) is an error naming the file; an empty folder or a missing one too.
Result<std::vector<LandmarkItem>> list_300w(const std::filesystem::path& dir);

// ---- metrics -----------------------------------------------------------------------------------

// The "box of the annotated points" of the detection rule is points_extent
// (perception/face_landmarks.hpp).
// Distance of the outer eye corners, points 37 and 46 (1-based; indices 36 and 45): the 300-W
// normaliser. Needs 68 points.
double outer_corner_distance(const std::vector<cv::Point2d>& truth);
// Mean point-to-point error over the 68 points / outer_corner_distance(truth).
double nme_outer_corners(const std::vector<cv::Point2d>& predicted,
                         const std::vector<cv::Point2d>& truth);
// Eye-contour centroids (points 37-42 and 43-48, 1-based) of prediction vs truth: the mean of the
// two eyes' centroid distances / outer_corner_distance(truth).
double eye_center_error(const std::vector<cv::Point2d>& predicted,
                        const std::vector<cv::Point2d>& truth);
// Index of the box with the highest IoU with `truth_box` when that IoU >= min_iou, else -1.
int match_detection(const std::vector<cv::Rect2d>& boxes, const cv::Rect2d& truth_box,
                    double min_iou = 0.5);

// ---- the protocol ------------------------------------------------------------------------------

using Progress = std::function<void(double)>;

struct LandmarksEvalOptions {
  std::string dataset = "300w";
  std::filesystem::path dir;
  // Detector chains, measured on the same images; the first one is reported at the top level.
  //  haar     - the pipeline's face detector (Haar alt2, FaceDetectorOptions defaults) and the
  //             dlib landmarker with its box re-derivation (the pipeline's chain, baseline);
  //  hog      - dlib's HOG detector (faces down to hog_min_face_px), dlib landmarker;
  //  hog_haar - hog, and a wider Haar search (wide_haar_*) when HOG finds no face in the image;
  //  union    - hog and the wider Haar search both, Haar boxes overlapping no HOG box (IoU <
  //             0.3) added;
  //  tiny / union_tiny - face-api's tiny face detector alone / added to union (see below);
  //  a "+tta" suffix: the landmarker with test-time augmentation (tta_box_scales, tta_mirror).
  //  "+cnn": face-api's 68-point CNN (npm @vladmandic/face-api, MIT) instead of dlib, from the
  //  detector box; "+mean": the per-point mean of dlib+tta and the CNN (spread = half their
  //  distance); "+cnn_dlib": dlib+tta started from the box of the CNN's points; "+switch":
  //  dlib+tta when the pipeline landmarker's spread_confidence (its two box passes) is >=
  //  switch_min_confidence (the analyser's "confident" threshold), else the CNN (spread = the
  //  CNN's mean distance from dlib's points); "+cnn_switch": as +switch, except that on the boxes
  //  of face-api's detectors (tiny, ssd) both dlib fits start from the box of the CNN's points
  //  (dlib's box convention derived through the CNN; the CNN's own points from the detector box);
  //  "+plain_switch": the pipeline's rule (FaceLandmarksAnalyzerOptions::cnn_fallback): the
  //  pipeline landmarker's own fit when confident, else the CNN.
  std::vector<std::string> detectors{"ssd_paired+switch",
                                     "ssd_paired+cnn_switch",
                                     "union_ssd+switch",
                                     "ssd_hybrid+switch",
                                     "ssd_hybrid+cnn_switch",
                                     "ssd_hybrid",
                                     "ssd_union+cnn_switch",
                                     "ssd_union+switch",
                                     "union_tiny_ssd+switch",
                                     "union_ssd+cnn_switch",
                                     "union_ssd",
                                     "ssd+cnn_switch",
                                     "ssd+switch",
                                     "ssd+cnn",
                                     "ssd",
                                     "union_tiny+switch",
                                     "union_tiny+tta",
                                     "union_tiny",
                                     "tiny",
                                     "union+switch",
                                     "union+tta",
                                     "union+cnn",
                                     "union+mean",
                                     "union+cnn_dlib",
                                     "union",
                                     "hog_haar",
                                     "hog",
                                     "haar"};
  std::vector<double> tta_box_scales{0.9, 1.1};
  bool tta_mirror = true;
  double min_iou = 0.5;       // detection rule (box of the fitted points vs annotated points)
  double failure_nme = 0.08;  // failure_rate_08
  // HogFaceDetectorOptions::min_face_px and max_work_side_px: smaller faces than the library's
  // defaults (40, 1600), at about twice the time (an 800 px image is searched at 2133 px).
  double hog_min_face_px = 30;
  int hog_max_work_side_px = 2800;
  // The Haar search of hog_haar and union (the haar chain keeps the pipeline's defaults).
  double wide_haar_min_face_px = 40;
  bool wide_haar_profile = true;
  int landmark_refit_passes = 1;  // DlibLandmarkerOptions::refit_passes (all chains)
  // DlibLandmarkerOptions::quantized_leaves (all chains; the pipeline's default; false = dlib's
  // float leaves).
  bool landmark_quantized_leaves = true;
  // iBUG .pts coordinates are 1-based (Matlab): subtract 1 to compare with 0-based pixels.
  bool one_based_annotations = true;
  // from_box_cnn (the CNN from the annotated box) also when no chain uses the CNN.
  bool with_cnn = false;
  double switch_min_confidence = 0.5;
  // "tiny": face-api's tiny face detector (vision::FaceApiTinyFaceDetector) at about the image's
  // resolution (longest side rounded up to 32, at most tiny_max_input_px), the package's default
  // score threshold; "union_tiny": union, and tiny boxes overlapping no union box (IoU < 0.3);
  // "tiny_union": the same detectors, tiny's box kept where boxes overlap (added after seeing
  // that union_tiny's merge dropped tiny boxes that matched better; README "Real faces").
  int tiny_max_input_px = 1024;
  double tiny_min_score = 0.5;
  // "ssd": face-api's SSD MobileNet v1 detector (vision::FaceApiSsdDetector; fixed 512 px input)
  // with the package's default minimum confidence; "union_ssd": union, and SSD boxes overlapping
  // no union box (IoU < 0.3); "union_tiny_ssd": union_tiny, and SSD boxes overlapping none;
  // "ssd_union": the boxes of union_ssd, SSD's kept where boxes overlap (SSD's boxes match the
  // annotated points' box best of all detectors: README "Real faces"); "ssd_hybrid": the boxes
  // of ssd_union, but the landmarker starts from the union box that overlaps an SSD box most
  // (IoU >= 0.3: dlib's own detector's box convention), from the SSD box where none does;
  // "ssd_paired": ssd_hybrid, but face-api's CNN (+cnn, +switch, ...) always starts from the SSD
  // box: each landmarker from the box in its own convention (the CNN's is the points' extent,
  // which the SSD's boxes match; a HOG/Haar box can put it on the wrong region: README).
  double ssd_min_score = 0.5;
  // Also run the SSD on 2 x 2 overlapping tiles (each ssd_tile_fraction of the image's width and
  // height) when the image's longest side exceeds 1.5 x its 512 px input: a face smaller than the
  // smallest anchor at the whole image's scale (~51 px of 512, i.e. ~100 px of a 1024 px photo)
  // is then seen about 2.4 x larger. Tile boxes cut by an inner tile border, and tile boxes
  // larger than half a tile (the whole-image pass sees those), are dropped; the rest are merged
  // with the whole-image boxes by the package's greedy suppression (IoU > 0.5, higher score kept).
  // On by default since 2026-11-29 (AFW: SSD alone 0.941 -> 0.994 of the faces found; README
  // "Real faces").
  bool ssd_tiles = true;
  double ssd_tile_fraction = 0.6;
  std::filesystem::path face_api_model_dir;  // empty = the npm package's model folder
  std::filesystem::path landmark_model = "/usr/share/dlib/shape_predictor_68_face_landmarks.dat";
  size_t stride = 1;     // every stride-th item (by name), a subset for quick runs and tests
  size_t max_items = 0;  // 0 = all
  Status check() const;
};

Result<EvalReport> run_landmarks_eval(const LandmarksEvalOptions& options,
                                      const Progress& progress = {});

}  // namespace dreamsense::eval::landmarks
