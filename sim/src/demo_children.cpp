#include "dreamsense/sim/demo_children.hpp"

#include "dreamsense/sim/face_renderer.hpp"

namespace dreamsense::sim {

const std::vector<DemoChild>& demo_children() {
  // Crops and masks of the new portraits follow the original child's, scaled by the landmark
  // face width w (jaw 0 to 16): crop from (cx - 0.92 w, eye_y - 1.01 w), 1.84 w x 2.12 w; mask
  // centre (cx, eye_y - 0.05 w), semi-axes 0.81 w x 0.93 w; face_width_px 1.03 w. Where the
  // photo ends sooner, crop and mask stop at its border.
  static const std::vector<DemoChild> children = [] {
    const std::filesystem::path data(DREAMSENSE_DEMO_DATA_DIR);
    std::vector<DemoChild> c(4);
    c[0].name = "astronaut";
    c[0].subject = "demo_child";
    c[0].expression = "happy";  // the NASA portrait smiles
    c[0].in_shipped_gallery = true;
    c[0].portrait = "/usr/lib/python3/dist-packages/skimage/data/astronaut.png";
    c[0].package = "python3-skimage";
    c[0].licence = "public domain (NASA portrait of Eileen Collins)";
    c[0].landmarks = default_portrait_landmarks_path();
    c[0].crop_px = {140, 8, 170, 196};
    c[0].mask_centre_px = {225.0, 97.0};
    c[0].mask_axes_px = {75.0, 86.0};
    c[0].face_width_px = 95.0;
    c[0].face_width_m = 0.15;
    c[0].eye_height_offset_m = 0;

    c[1].name = "grace_hopper";
    c[1].subject = "demo_child_grace_hopper";
    c[1].expression = "neutral";  // the portrait does not smile (looked at in a rendered frame)
    c[1].portrait = "/usr/share/matplotlib/mpl-data/sample_data/grace_hopper.jpg";
    c[1].package = "python-matplotlib-data";
    c[1].licence = "public domain (US Navy portrait of Grace M. Hopper, a US government work)";
    c[1].landmarks = data / "grace_hopper_landmarks.yaml";
    c[1].crop_px = {101, 4, 346, 398};
    c[1].mask_centre_px = {275.0, 185.1};
    c[1].mask_axes_px = {152.5, 174.8};
    c[1].face_width_px = 193.1;
    c[1].face_width_m = 0.135;        // a smaller face
    c[1].eye_height_offset_m = 0.04;  // a smaller child: eyes 4 cm lower

    c[2].name = "tom_cruise";
    c[2].subject = "demo_child_tom_cruise";
    c[2].expression = "happy";  // a broad smile
    c[2].portrait = "/usr/share/doc/libdlib19.1/examples/faces/Tom_Cruise_avp_2014_4.jpg";
    c[2].package = "libdlib19.1";
    c[2].licence =
        "Debian's copyright file lists dlib's examples/* as Creative-Commons-Public-Domain; the "
        "photograph appears to be Gage Skidmore's (Wikimedia Commons, CC BY-SA)";
    c[2].landmarks = data / "tom_cruise_landmarks.yaml";
    c[2].crop_px = {0, 0, 565, 800};
    c[2].mask_centre_px = {296.0, 368.1};
    c[2].mask_axes_px = {268.0, 367.0};  // the photo's borders (0.81 w x 0.93 w would not fit)
    c[2].face_width_px = 406.7;
    c[2].face_width_m = 0.16;          // a larger, wider face
    c[2].eye_height_offset_m = -0.04;  // a taller child: eyes 4 cm higher

    // The held-out child: no seed shows it (demo_child_for_seed), only `demo --child 3` (only
    // the rotated face search was chosen while looking at it, sim/README.md). Darker skin,
    // narrowed smiling eyes, the head tilted 13 degrees in the photo. Its tile of the collage ends
    // at x 1774 below y 370; the mask stays inside it (at y 370 the ellipse is 155 px wide on each
    // side).
    c[3].name = "bald_guys_21";
    c[3].subject = "demo_child_bald_guys_21";
    c[3].expression = "happy";  // a broad smile
    c[3].portrait = "/usr/share/doc/libdlib19.1/examples/faces/bald_guys.jpg";
    c[3].package = "libdlib19.1";
    c[3].licence =
        "Debian's copyright file lists dlib's examples/* as Creative-Commons-Public-Domain; the "
        "collage's photographs are of unknown origin";
    c[3].landmarks = data / "bald_guys_21_landmarks.yaml";
    c[3].crop_px = {1345, 0, 515, 504};  // the photo's top cuts the formula's crop
    c[3].mask_centre_px = {1602.5, 179.7};
    c[3].mask_axes_px = {226.8, 260.4};
    c[3].face_width_px = 288.4;
    c[3].face_width_m = 0.145;
    c[3].eye_height_offset_m = 0.02;  // eyes 2 cm lower
    return c;
  }();
  return children;
}

// Odd seeds (the default demo, seed 1, and the tests' seed 3) show the original child, whose
// calibration ships; even seeds alternate between children 1 and 2. Child 3 is held out.
int demo_child_for_seed(uint64_t seed) {
  if (seed % 2 == 1) return 0;
  return 1 + static_cast<int>((seed / 2 + 1) % 2);
}

}  // namespace dreamsense::sim
