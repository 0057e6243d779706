#pragma once
// `dreamsense enroll objects`: labelled views of toys from
//  - crops: DIR/<label>/*.png|jpg (one toy per image, some table around it, or tight), or
//  - recordings: sessions whose top camera shows the toys, with boxes from a CSV file
//    ("frame,label,x,y,w,h" per line, frame = index of the camera's frame from 0, or the stamp in
//    ns when `--boxes-by-stamp`) or from the session's truth.jsonl `object` records.
// In recordings the table-top detector runs as in the analysis and its blob matching a box
// (IoU >= 0.5) is the view, so the gallery sees the toys as the analysis will; without a match
// the box itself (mask by colour) is used.
// Labels map to ids through `classes`: the DREAM toys (car 0, cup 1, flower 2, plane 3) are
// known; a new label gets the next free id unless `classes` names it.

#include "dreamsense/core/status.hpp"
#include "dreamsense/objects/identification.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::eval {

struct ObjectEnrolmentOptions {
  std::optional<std::filesystem::path> crops;   // DIR/<label>/*.png|jpg
  std::vector<std::filesystem::path> sessions;  // recordings
  std::optional<std::filesystem::path> boxes;   // CSV for the (single) session; else truth.jsonl
  bool boxes_by_stamp = false;                  // CSV first column is stamp_ns, not frame index
  std::string camera = "top.color";
  int frame_step = 10;                        // every n-th frame of a recording
  std::vector<objects::ObjectClass> classes;  // extra / overriding classes (id, label, size)
  std::optional<std::filesystem::path> base;  // add to this gallery instead of a new one
  objects::GalleryOptions gallery;
  Status check() const;
};

struct ObjectEnrolmentResult {
  objects::ObjectGallery gallery;
  std::vector<std::pair<std::string, int>> views_per_label;
};

Result<ObjectEnrolmentResult> enrol_objects(const ObjectEnrolmentOptions& options);

// "label=id" or "label=id:LxWxH" (metres), e.g. "ball=4:0.06x0.06x0.06".
Result<objects::ObjectClass> parse_object_class(const std::string& text);

}  // namespace dreamsense::eval
