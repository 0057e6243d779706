#pragma once
// Eye-centre (iris/pupil centre) localisation in one eye region: the improved integro-
// differential operator of DREAM D4.2 and two baselines (Daugman's original operator, Timm &
// Barth's means of gradients). Method, papers and measured numbers:
// modalities/eye_centers/README.md.
//
// Every locator takes a grey (CV_8UC1) or BGR (CV_8UC3) image and the six contour landmarks of
// one eye (EyeRegion order), and returns an EyeLocation in image pixels. A closed, too small or
// featureless eye is found = false with a rejection reason (absence, not an error); an empty image
// or an unsupported pixel type is an error. All functions are const and thread-safe.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/eye_centers/eye_region.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <span>
#include <string_view>

namespace dreamsense::eye_centers {

enum class EyeCenterMethod {
  kImprovedIntegroDifferential,  // D4.2 eq. (2): horizontal cones, precomputed ring tables
  kDaugman,                      // Daugman's integro-differential operator, full circles
  kTimmBarth,                    // Timm & Barth 2011, means of gradients
};
// "improved_integro_differential", "daugman", "timm_barth".
std::string_view to_string(EyeCenterMethod method);
// Accepts the names above and "improved" for the first.
std::optional<EyeCenterMethod> eye_center_method_from_string(std::string_view name);

// Why a locator found no centre.
enum class EyeRejection {
  kNone,        // found
  kTooSmall,    // eye narrower than EyeRegionOptions::min_eye_width_px
  kClosed,      // lids closer than min_opening_px / min_opening_ratio
  kNoContrast,  // patch standard deviation below min_contrast (blank, saturated, occluded)
  kNoEdge,      // the method's peak response is below its threshold
};
std::string_view to_string(EyeRejection rejection);

struct EyeLocation {
  bool found = false;
  // The eye centre, image pixels, sub-pixel (valid when found): the pupil centre when the
  // improved operator resolved the pupil (pupil_found), else the iris (limbus) centre.
  cv::Point2d center_px;
  cv::Point2d iris_center_px;  // limbus centre (integro-differential methods; T&B: = center_px)
  double radius_px = 0;        // iris radius at the peak (integro-differential methods), else 0
  bool pupil_found = false;    // improved operator's pupil stage accepted a pupil
  double pupil_radius_px = 0;  // valid when pupil_found
  double pupil_score = 0;      // the pupil stage's peak step (grey levels), 0 if it did not run
  double confidence = 0;       // [0, 1], see each method's options
  double score = 0;            // the raw peak: limbus step in grey levels, or T&B's objective
  EyeRejection rejection = EyeRejection::kNone;
  EyeCenter to_eye_center() const {
    return {found, center_px, found ? confidence : 0.0, found && pupil_found};
  }
};

// D4.2 eq. (2). For a candidate centre (x0, y0) the normalised contour sums (ring means) L_k at
// radii k*dr are taken over two opposing cones of +-cone_half_angle_deg around the eye's
// horizontal (eyelids ignored); D_n = |sum_k (G(n-k) - G(n-k-1)) L_k| is their derivative-of-
// Gaussian over radius (convolution and differentiation interchanged: one 1-D filter of the ring
// means); the centre and radius maximise D_n. Speed: the ring kernels are precomputed once per
// call as integer pixel offsets with bilinear ring weights, so a candidate costs one weighted sum
// over the cone pixels (about pi * r_max^2 / 2 taps) plus the short 1-D filter; no trigonometry
// and no interpolation per candidate.
// Second stage of the improved operator: the pupil boundary inside the found limbus, by the same
// ring-table operator (dark inside) on radii min_radius_ratio..max_radius_ratio x the limbus
// radius, around centres within max_offset_ratio x the limbus radius of the limbus centre. The
// pupil centre replaces the limbus centre when its step is at least min_step grey levels and at
// least min_step_ratio x the limbus step (a pupil that is not darker than its iris, e.g. a dark
// iris at low resolution, keeps the limbus centre).
struct PupilOptions {
  bool enabled = true;
  double min_radius_ratio = 0.2, max_radius_ratio = 0.6;  // human pupil: ~0.2-0.7 x iris radius
  double min_radius_px = 1.0;                             // patch pixels
  double max_offset_ratio = 0.4;
  // The stage resamples the limbus neighbourhood 1-4x finer so that the limbus radius is about
  // this many pixels; sigma_px and the radius step then apply to that grid.
  double target_iris_radius_px = 12;
  double cone_half_angle_deg = 45;  // the lids cut full circles around a small pupil too
  double sigma_px = 1.0;            // Gaussian over radius, fine-grid pixels
  double min_step = 8;
  double min_step_ratio = 0.25;
  // Grey levels above this percentile of the iris disc are clipped to it (100: off): glints
  // (corneal reflections, often on the pupil border) and the sclera stop pulling the pupil's
  // ring means, while the pupil edge (darker than most of the iris) is kept.
  double clip_percentile = 50;
  Status check() const;
};

struct ImprovedIntegroDifferentialOptions {
  double radius_step_px = 0.5;  // dr, in patch pixels
  double sigma_px = 1.0;        // Gaussian over radius, in patch pixels
  double cone_half_angle_deg = 45;
  double arc_step_px = 0.5;  // dtheta = arc_step_px / radius (free: samples merge into the tables)
  // Eq. (2) takes |D_n|. When true (default), only dark-inside edges count (an iris is darker
  // than the sclera), which ignores bright-inside rings such as a glint or a skin gap.
  bool dark_inside_only = true;
  // found = false when the best limbus step is below min_step grey levels; confidence =
  // clamp(step / full_confidence_step, 0, 1).
  double min_step = 6;
  double full_confidence_step = 60;
  // An open eye shows its iris: found = false (kNoEdge) also when the limbus step is below
  // min_step_of_range x the grey-level spread (95th - 5th percentile) of the eye's window. A
  // closed eye (lid skin and lash line, landmarks that did not follow the blink) has no such step.
  double min_step_of_range = 0.15;
  // Candidate search, both stages: every coarse_step-th centre, then all centres around the best
  // of them (1 = exhaustive).
  int coarse_step = 2;
  PupilOptions pupil;
  Status check() const;
};

// Daugman's operator, J. Daugman, "High confidence visual recognition of persons by a test of
// statistical independence", IEEE TPAMI 15(11), 1993: max over (r, x0, y0) of
// |G_sigma(r) * d/dr of the full-circle contour mean| by brute force: for each candidate and
// radius, bilinear samples around the whole circle (about one per pixel of arc), then the
// derivative and the Gaussian over radius. The baseline eq. (2) improves on.
struct DaugmanOptions {
  double radius_step_px = 0.5;
  double sigma_px = 1.0;
  double arc_step_px = 0.5;       // samples along each circle (at least 8 per circle)
  bool dark_inside_only = false;  // the original takes |.|
  double min_step = 6;
  double full_confidence_step = 60;
  Status check() const;
};

// F. Timm, E. Barth, "Accurate eye centre localisation by means of gradients", VISAPP 2011:
// c* = argmax_c w_c / N * sum_i max(0, d_i . g_i)^2, d_i the unit displacement from c to pixel i,
// g_i the unit gradient at i; only gradients with magnitude above mean + gradient_threshold_sd *
// s.d. of the patch's magnitudes count; w_c = 255 - (Gaussian-smoothed grey level at c), the
// "dark centre" prior.
struct TimmBarthOptions {
  // 1.0 is about what the reference implementation's dynamic threshold (50 * s.d. / sqrt(pixels)
  // + mean) gives on its 50-pixel-wide eye patches.
  double gradient_threshold_sd = 1.0;
  double weight_blur_sigma_px = 1.0;  // smoothing for w_c, patch pixels
  bool use_weight = true;
  // confidence = clamp(objective / full_confidence_objective, 0, 1) with the unweighted mean
  // squared cosine at the peak (1 = every strong gradient points radially away from c).
  double full_confidence_objective = 0.4;
  double min_objective = 0.02;  // found = false below this
  Status check() const;
};

Result<EyeLocation> locate_improved_integro_differential(
    const cv::Mat& image, std::span<const cv::Point2d> eye_contour_px,
    const EyeRegionOptions& region = {}, const ImprovedIntegroDifferentialOptions& options = {});
Result<EyeLocation> locate_daugman(const cv::Mat& image,
                                   std::span<const cv::Point2d> eye_contour_px,
                                   const EyeRegionOptions& region = {},
                                   const DaugmanOptions& options = {});
Result<EyeLocation> locate_timm_barth(const cv::Mat& image,
                                      std::span<const cv::Point2d> eye_contour_px,
                                      const EyeRegionOptions& region = {},
                                      const TimmBarthOptions& options = {});

// The iris's size in millimetres: the horizontal visible iris diameter (HVID) is 11.7 +- 0.5 mm
// in adults (Ruefer, Schroeder & Erb, Cornea 24(3):259-261, 2005) and reaches it in the first
// years of life, so unlike the eye's width it hardly differs between children. Given the eye's
// depth, it fixes the limbus radius in pixels far more tightly than the width-relative prior of
// EyeRegionOptions (0.16-0.32 x width: a factor 2, within which a narrow-eyed face's limbus
// search locks onto an inner ring).
struct IrisSizePrior {
  double diameter_mm = 11.7;
  // The limbus radius is searched in [min_ratio, max_ratio] x the expected radius (intersected
  // with the width-relative prior). Below 1: an iris seen obliquely is narrower across (the
  // horizontal cones measure that width), and the found circle sits inside the dark limbal ring.
  double min_ratio = 0.85;
  double max_ratio = 1.1;
  // true: an eye whose pupil is not found at that size (hidden under a lid, or the size is
  // wrong) is searched again with the width-relative prior alone, and that result is kept when
  // it finds the eye. false: the sized search's result stands.
  bool fall_back_without_pupil = true;
  Status check() const;
};

// `region` with its iris-radius range narrowed to [min_ratio, max_ratio] x expected_radius_px
// (as fractions of the width of the eye `contour`, six points in EyeRegion order), intersected
// with the region's own range; unchanged when they do not overlap (an implausible expectation,
// e.g. from a wrong depth) or the expectation is not a positive number.
EyeRegionOptions with_expected_iris_radius(const EyeRegionOptions& region,
                                           std::span<const cv::Point2d> contour,
                                           double expected_radius_px, const IrisSizePrior& prior);

// The image scale (pixels per millimetre) at a world point seen by `camera`: its focal length
// over the point's depth; nullopt for a point less than 5 cm in front of the camera.
std::optional<double> pixels_per_mm_at(const CameraModel& camera, const cv::Vec3d& point_world_m);

struct EyeCenterLocatorOptions {
  EyeCenterMethod method = EyeCenterMethod::kImprovedIntegroDifferential;
  EyeRegionOptions region;
  IrisSizePrior iris_size;  // used when locate() is given the eye's depth
  ImprovedIntegroDifferentialOptions improved;
  DaugmanOptions daugman;
  TimmBarthOptions timm_barth;
  Status check() const;
};

// One configured method, for both eyes of a face.
class EyeCenterLocator {
 public:
  static Result<EyeCenterLocator> create(const EyeCenterLocatorOptions& options = {});

  // One eye; `eye_contour_px` = six points in EyeRegion order (requires exactly six).
  // `pixels_per_mm`: the image scale at the eye (focal length / depth), when known: the limbus
  // is then searched at the size options().iris_size gives it (with_expected_iris_radius).
  Result<EyeLocation> locate(const cv::Mat& image, std::span<const cv::Point2d> eye_contour_px,
                             std::optional<double> pixels_per_mm = std::nullopt) const;
  // Both eyes of 68-point landmarks fitted on `image` (requires kFaceLandmarkCount points):
  // right = subject's right eye (36-41), left = 42-47; camera, stamp, sequence and method filled.
  Result<EyeCenters> locate_both(const cv::Mat& image, const FaceLandmarks& landmarks,
                                 std::optional<double> pixels_per_mm = std::nullopt) const;

  const EyeCenterLocatorOptions& options() const { return options_; }

 private:
  explicit EyeCenterLocator(const EyeCenterLocatorOptions& o) : options_(o) {}
  Result<EyeLocation> locate_in(const cv::Mat& image, std::span<const cv::Point2d> contour,
                                const EyeRegionOptions& region) const;
  EyeCenterLocatorOptions options_;
};

}  // namespace dreamsense::eye_centers
