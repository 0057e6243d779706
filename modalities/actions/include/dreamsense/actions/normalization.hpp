#pragma once
// Body-frame normalisation of a window of skeleton frames: translation, scale and facing
// direction removed, missing joints filled. What is assumed (README.md "Normalisation"):
// - the sensor's up direction is known (`BodyFrameOptions::up`; the project's optical frame has
//   up = -y; dataset readers convert their layouts to that frame);
// - coordinates are right-handed; left/right joint labels are the body's own (Kinect labels them
//   so); a mirrored source mirrors the facing axis consistently, so models must be trained and
//   used on the same handedness;
// - the body is upright enough that the shoulder and hip lines give its facing direction;
// - body size: the median torso length (shoulder centre to hip centre) plus the median shoulder
//   width is the unit of length, so a child and an adult doing the same movement give the same
//   features as long as their proportions are similar.
// Missing joints (confidence below min_confidence, or a non-finite position) are interpolated
// in time from the same joint's observations in the window, held at the window's ends, and a
// joint never observed in the window takes its nearest observed neighbour's position along the
// skeleton tree. A window without any usable torso joint is `usable == false` (no_data).

#include "dreamsense/actions/skeleton_sequence.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace dreamsense::actions {

struct BodyFrameOptions {
  // Up in sensor coordinates (normalised internally). Optical frame: (0, -1, 0).
  cv::Vec3d up{0, -1, 0};
  // Rotate about `up` so that the body's left-right axis is the x axis (the window's mean
  // shoulder and hip lines). Off: only translation and scale.
  bool normalize_facing = true;
  // Divide by the body's size (see above). Off: metres.
  bool normalize_scale = true;
  // Rebuild every frame from the hip centre outwards with each bone's direction kept and its
  // length set to a reference skeleton's (in body units): removes the remaining differences of
  // proportions between people (a child's arms vs an adult's) and bone-length jitter of the
  // tracker. Needs normalize_scale.
  bool normalize_bones = true;
  // Joints below this confidence are missing. 0.5 (Kinect "inferred") is kept by default.
  float min_confidence = 0.25f;
  // Unit length when the window shows no torso length or shoulder width (metres).
  double default_body_size_m = 0.60;
  Status check() const;
};

struct NormalizedWindow {
  int frames = 0;
  std::vector<double> t_s;  // seconds since the window's first frame, strictly increasing
  // frames x kJointCount, row-major: positions[f * kJointCount + j]. Body frame: x = the body's
  // left, y = up, z = forward (towards where the body faces); origin = the window's mean hip
  // centre; unit = body size (or metres when normalize_scale is off).
  std::vector<cv::Vec3f> positions;
  std::vector<uint8_t> observed;  // same layout: 1 = measured, 0 = filled in
  double body_size_m = 0;         // the unit of length used
  double observed_fraction = 0;   // of the frames x joints
  bool facing_known = false;      // false: the sensor's x axis was taken as the body's left
  bool usable = false;            // false: nothing to classify (no torso joint in the window)
  const cv::Vec3f& at(int frame, int joint) const {
    return positions[static_cast<size_t>(frame) * kJointCount + static_cast<size_t>(joint)];
  }
};

NormalizedWindow normalize_window(std::span<const SkeletonFrame> frames,
                                  const BodyFrameOptions& options);

// The mirror image of a normalised window: the body's left and right swapped (x -> -x and the
// left/right joints exchanged). Training augmentation: a wave of the left hand teaches the right.
void mirror_left_right(NormalizedWindow& window);

// Linear resampling of the window's positions at n instants evenly spaced over its duration
// (n x kJointCount, row-major). A window of one frame repeats it.
std::vector<cv::Vec3f> resample_positions(const NormalizedWindow& window, int n);

}  // namespace dreamsense::actions
