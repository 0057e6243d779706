#pragma once
// Readers for skeleton action datasets, into dataset-independent labelled sequences
// (dreamsense/actions/skeleton_sequence.hpp: core's joint order, optical frame x right, y down,
// z forward). Malformed files give one-line errors naming the file and line.
//
// UTKinect-Action3D (Xia et al. 2012): DIR/joints_sSS_eEE.txt, one frame per line: a depth
//   frame id then 20 joints x (x y z) in metres, Kinect SDK v1 joint order and camera axes
//   (x to the sensor's left, y up, z forward); DIR/actionLabel.txt: blocks "sSS_eEE" followed by
//   "label: first last" (depth frame ids; "NaN NaN" = segment missing, skipped). When
//   actionLabel_modified.txt (Vemulapalli et al.'s corrected labels) is present it is used
//   unless a label file is named. Frames with a repeated id are dropped (the first is kept);
//   stamps = frame id / 30 s. NaN/inf coordinates mark that joint missing.
// MSR Action3D (Li et al. 2010): DIR/aXX_sYY_eZZ_skeleton3D.txt, 20 lines "x y z c" per frame
//   (joint order: shoulders L/R, neck, spine, hips L/R, hip centre, elbows, wrists, hands, knees,
//   ankles, feet, head; y up, x to the sensor's left), 15 frames/s. `c` is not a Kinect
//   tracking state (it is 0 on plausible joints such as the neck), so every finite joint counts
//   as tracked and
//   an all-zero joint or frame is missing. A sequence with no usable frame is skipped.

#include "dreamsense/actions/skeleton_sequence.hpp"
#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::eval::actions {

using dreamsense::actions::LabelledSequence;

struct ActionDataset {
  std::string name;                     // "utkinect", "msr-action3d"
  std::vector<std::string> labels;      // all classes, dataset order
  std::vector<LabelledSequence> items;  // segments / sequences with subject ids ("s01")
  int skipped = 0;                      // segments missing from the labels or with no frames
  std::string note;                     // what was read (label file, skipped items)
};

struct UtkinectOptions {
  std::filesystem::path label_file;  // empty: actionLabel_modified.txt if present, else
                                     // actionLabel.txt (both in DIR)
  double frame_rate_hz = 30;         // depth frame ids -> stamps
};
Result<ActionDataset> read_utkinect(const std::filesystem::path& dir,
                                    const UtkinectOptions& options = {});

// One UTKinect joints file, all frames (stamps from the frame ids).
Result<std::vector<std::pair<int, dreamsense::actions::SkeletonFrame>>> read_utkinect_joints(
    const std::filesystem::path& file, double frame_rate_hz = 30);

struct MsrAction3dOptions {
  double frame_rate_hz = 15;
};
Result<ActionDataset> read_msr_action3d(const std::filesystem::path& dir,
                                        const MsrAction3dOptions& options = {});
Result<dreamsense::actions::SkeletonSequence> read_msr_skeleton(const std::filesystem::path& file,
                                                                double frame_rate_hz = 15);

// By dataset name ("utkinect", "msr-action3d"); unknown names are an error listing the known ones.
Result<ActionDataset> read_action_dataset(const std::string& name,
                                          const std::filesystem::path& dir);

}  // namespace dreamsense::eval::actions
