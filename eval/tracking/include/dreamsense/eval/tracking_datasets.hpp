#pragma once
// Single-object tracking sequences (cli.md `--dataset otb|mil DIR`):
//  - otb: DIR/img/NNNN.jpg (any numbered .jpg/.png) + DIR/groundtruth_rect.txt, one box per
//    line "x y w h" with 1-based pixel coordinates (Wu, Lim & Yang, CVPR 2013); commas, tabs and
//    spaces all occur as separators. A sequence with several targets has
//    groundtruth_rect.1.txt, ... instead: the first is used. When the file has fewer lines than
//    there are images, line 1 belongs to the first image unless the sequence is one of the few
//    OTB sequences known to start later (David 300, Tiger1 6, BlurCar1 247, BlurCar3 3,
//    BlurCar4 18) or `start_frame` says otherwise.
//  - mil: DIR/imgs/imgNNNNN.png + NAME_gt.txt (one "x,y,w,h" per frame, 0-based, 0,0,0,0 on
//    unlabelled frames) + NAME_frames.txt ("first,last" frame numbers) (Babenko, Yang &
//    Belongie, CVPR 2009).
// A box with zero width or height marks an unlabelled frame. Boxes are returned 0-based.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::eval {

struct TrackingSequence {
  std::string name;
  std::filesystem::path dir;
  std::vector<std::filesystem::path> frames;     // image files in frame order
  std::vector<std::optional<cv::Rect2d>> truth;  // one per frame; nullopt = unlabelled
  std::vector<std::string> warnings;             // count mismatches etc. (one line each)
  size_t labelled() const;
};

// One ground-truth line: four numbers separated by commas, tabs and/or spaces. `origin` is
// subtracted from x and y (1 for OTB). nullopt for an unlabelled box (w or h == 0). Error
// (kCorruptData) "FILE:LINE: ..." for anything else (wrong count, not a number, negative size).
Result<std::optional<cv::Rect2d>> parse_box_line(std::string_view line, const std::string& file,
                                                 int line_number, double origin);
// All boxes of a ground-truth file (blank trailing lines ignored).
Result<std::vector<std::optional<cv::Rect2d>>> read_box_file(const std::filesystem::path& file,
                                                             double origin);

// start_frame: the frame number of the first ground-truth line (0 = automatic, see above).
Result<TrackingSequence> read_otb_sequence(const std::filesystem::path& dir, int start_frame = 0);
Result<TrackingSequence> read_mil_sequence(const std::filesystem::path& dir);
// `dataset` "otb" or "mil": DIR itself when it is a sequence, otherwise each sub-folder that is
// one (sorted by name). Error when none is found.
Result<std::vector<TrackingSequence>> read_tracking_dataset(std::string_view dataset,
                                                            const std::filesystem::path& dir,
                                                            int start_frame = 0);

}  // namespace dreamsense::eval
