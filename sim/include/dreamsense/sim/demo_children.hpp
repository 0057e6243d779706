#pragma once
// The demo's children (issue 15): different faces (portraits shipped by Debian packages), face
// proportions and heights, so that accuracy is measured across children and not on one face.
// `dreamsense demo` chooses the child from the seed (demo_child_for_seed); DemoOptions::child
// (library default 0, the original child) pins it. Child 0 is the child of every session made
// before there were several, and the only one with a calibration folder (data/subjects/
// demo_child); the others are analysed as new children (self-calibration, issue 15).

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::sim {

struct DemoChild {
  std::string name;     // truth / metadata: which child
  std::string subject;  // session metadata `subject` (calibration folder name)
  std::filesystem::path portrait;
  std::string package;              // Debian package that ships the portrait
  std::string licence;              // of the portrait (sim/README.md, "Children")
  std::filesystem::path landmarks;  // 68 landmarks of the portrait (data/demo)
  // Texture crop and feathered elliptic alpha mask (MeshFaceOptions); cheek-to-cheek width at eye
  // level in portrait pixels, and the physical width the face is given.
  cv::Rect crop_px;
  cv::Point2d mask_centre_px;
  cv::Size2d mask_axes_px;
  double face_width_px = 0;
  double face_width_m = 0.15;
  // The child's eye height at rest relative to the original child's (world y points down, so
  // negative = taller).
  double eye_height_offset_m = 0;
  // Truth for faces (issue 12): the portrait's expression (the renderer does not animate it), and
  // whether the shipped face gallery (data/subjects/demo_child/face_gallery.yaml) enrols this
  // child; a child it does not enrol must be answered as unknown (-1).
  std::string expression = "happy";
  bool in_shipped_gallery = false;
};

// Child 0 = the original demo child (astronaut.png); the others in a fixed order. Child 3 is
// held out: no seed shows it (`demo --child 3`), so settings are not chosen on it by accident.
inline constexpr int kHeldOutDemoChild = 3;
const std::vector<DemoChild>& demo_children();
// The child a seed shows: 0 for odd seeds, 1 and 2 alternately for even seeds (2, 6, 10, ...
// child 1; 4, 8, 12, ... child 2); never the held-out child.
int demo_child_for_seed(uint64_t seed);

}  // namespace dreamsense::sim
