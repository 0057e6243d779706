#pragma once
// A synthetic, BioID-layout eye-centre set made by the project from a real face, so CI can run
// `eval eyes` without BioID (whose licence forbids redistribution).
//
// Each image: the astronaut portrait of Debian's python3-skimage (public-domain NASA photo of
// Eileen Collins), converted to grey, randomly scaled (inter-ocular distance), rotated (roll) and
// placed on a procedural background (gradient, blurred rectangles), with both eyes repainted: the
// eye opening (an almond between the corners, lids as hand-measured on the portrait) gets a
// sclera, and a textured iris with pupil, limbal ring and glint at a known gaze offset (the same
// for both eyes), clipped by the lids (the upper one randomly lowered) and rendered with 4x4
// supersampling; then side lighting, brightness, contrast, Gaussian blur and noise. The truth is
// the painted iris centre. Everything is drawn from one seed per image (mt19937_64 raw outputs, so
// identical on every platform).

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>

#include "bioid.hpp"

namespace dreamsense::eye_centers {

struct SyntheticEyeSetOptions {
  int count = 200;
  uint64_t seed = 1;
  std::filesystem::path portrait = "/usr/lib/python3/dist-packages/skimage/data/astronaut.png";
  // Iris centres in the portrait (pixel centres at integers; sim/face_renderer.hpp).
  cv::Point2d portrait_right_eye_px{203.0, 101.0};  // the subject's right eye (image left)
  cv::Point2d portrait_left_eye_px{246.0, 102.0};   // the subject's left eye (image right)
  cv::Size image_size{384, 286};                    // BioID's
  double min_interocular_px = 38, max_interocular_px = 68;
  double max_roll_deg = 8;
  // Gaze: iris offset from its rest position, uniform in +-max x eye width (same for both eyes).
  double max_gaze_x = 0.15, max_gaze_y = 0.05;
  // Upper lid lowered to this fraction of the portrait's (uniform in [min_lid_droop, 1.05]).
  double min_lid_droop = 0.7;
  // Side lighting: grey *= 1 + a * (distance along the eye line / inter-ocular), |a| <= this.
  double max_side_light = 0.3;
  double min_blur_sigma = 0.3, max_blur_sigma = 1.4;
  double min_noise_sd = 1, max_noise_sd = 7;
  double min_gain = 0.75, max_gain = 1.2, max_offset = 20;  // grey' = gain * grey + offset
  Status check() const;
};

struct SyntheticEyeImage {
  std::string id;  // "BioID_NNNN"
  cv::Mat grey;    // CV_8UC1, image_size
  BioIdEyes eyes;  // painted iris centres
  double iris_radius_px = 0;
};

class SyntheticEyeRenderer {
 public:
  // Loads the portrait (kNotFound naming python3-skimage when absent).
  static Result<SyntheticEyeRenderer> create(const SyntheticEyeSetOptions& options);
  // Image `index` of the set (depends only on options and index).
  SyntheticEyeImage render(int index) const;
  const SyntheticEyeSetOptions& options() const { return options_; }

 private:
  SyntheticEyeRenderer(SyntheticEyeSetOptions o, cv::Mat portrait, cv::Mat mask)
      : options_(std::move(o)), portrait_(std::move(portrait)), mask_(std::move(mask)) {}
  SyntheticEyeSetOptions options_;
  cv::Mat portrait_;  // CV_32F grey
  cv::Mat mask_;      // CV_32F head-and-shoulders alpha, portrait pixels
};

// Writes options.count images as BioID_NNNN.pgm + BioID_NNNN.eye into `dir` (created; existing
// BioID_* files are overwritten, others left alone).
Status write_synthetic_eye_set(const SyntheticEyeSetOptions& options,
                               const std::filesystem::path& dir,
                               const std::function<void(double)>& progress = {});

}  // namespace dreamsense::eye_centers
