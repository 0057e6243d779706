#pragma once
// Window descriptors for action classification (README.md "Method").
// - kRelativePositions (the seed's method, D4.2 §Human Action Analysis): pairwise differences
//   p_i - p_j of the normalised joints (all pairs i < j), at `rjp_frames` instants evenly spaced
//   over the window, concatenated.
// - kPyramid (ours): the window resampled at `samples` instants evenly spaced over its duration
//   (linear time normalisation: rate invariance within the window); per joint coordinate, the
//   means of the position and of its velocity over the cells of a temporal pyramid (1, 2, 4, ...
//   cells), plus the magnitudes of the lowest Fourier coefficients of the whole window (Wang et
//   al. 2012's Fourier temporal pyramid, level 0); optionally (`distances`) the Euclidean
//   distances between every pair of the descriptor's joints, their mean and standard deviation
//   over the same pyramid cells (rotation-invariant: a wrong facing estimate leaves them alone).

#include "dreamsense/actions/normalization.hpp"
#include "dreamsense/core/status.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::actions {

enum class FeatureMethod { kRelativePositions, kPyramid };
std::string_view to_string(FeatureMethod m);  // "relative_positions", "pyramid"
Result<FeatureMethod> feature_method_from_string(std::string_view s);

// Which joints enter the descriptor. kUpperBody: the ten DREAM joints plus spine and hip centre
// (for a seated child whose legs are hidden under the table and only "inferred").
enum class JointSet { kAll, kUpperBody };
std::string_view to_string(JointSet s);  // "all", "upper_body"
Result<JointSet> joint_set_from_string(std::string_view s);
std::vector<int> joint_indices(JointSet s);

struct FeatureOptions {
  FeatureMethod method = FeatureMethod::kPyramid;
  JointSet joints = JointSet::kUpperBody;
  int samples = 32;    // resampled instants per window (pyramid), >= 4
  int rjp_frames = 4;  // instants per window (relative positions), >= 1
  // relative positions: means over rjp_frames equal cells of the window resampled at `samples`
  // instants, instead of single instants.
  bool rjp_average = false;
  int pyramid_levels = 2;  // 1 + 2 + 4 cells, 1..5
  bool velocities = true;  // pyramid: also the velocity means
  int fourier = 4;         // pyramid: Fourier magnitudes 1..fourier per coordinate (0 = none)
  // pyramid: joints relative to the same frame's hip centre (the pose), with the hip centre's
  // own path relative to the window origin (the body's displacement) kept separately, so that
  // walking a metre does not drown the arms' posture. Off: all joints relative to the origin.
  bool pose_relative = true;
  // pyramid: also the pairwise joint distances (mean and standard deviation per pyramid cell):
  // hand to hand, hand to head, ... Off in the linear-SVM method, on in the LDA one (README.md).
  bool distances = false;
  Status check() const;
};

int feature_dimension(const FeatureOptions& o);

// The descriptor of a normalised window (empty if the window is not usable).
std::vector<float> extract_features(const NormalizedWindow& window, const FeatureOptions& o);

}  // namespace dreamsense::actions
