#pragma once
// `dreamsense eval eyes`: the BioID eye-centre protocol (Jesorsky et al. 2001), JSON of
// spec/cli.md (task "eyes").
//
// Per image: Haar face detection (opencv-data haarcascade_frontalface_alt2, the best-scoring
// face), dlib 68 landmarks on it, eye regions from contours 36-41 and 42-47, then each method's
// eye centres. Error e = max(d_left, d_right) / |L - R| with L, R the true centres of the .eye
// file; no face, no landmarks or an eye the method does not find (found = false) is a failure
// (e = inf). Metrics: acc_e005, acc_e010, acc_e025 = fraction of ALL images with e <= 0.05,
// 0.10, 0.25; median_e over all images (inf counts as larger than any); face_detection_rate;
// found_rate (both eyes found, among faces with landmarks). Timing: ms_per_face_median =
// detection + landmarks + both eyes; ms_per_eye_median = one eye's locator call.
//
// Methods: "improved_integro_differential" (CLI "improved"), "daugman", "timm_barth", and the
// reference "landmark_centroid" (centroid of the six contour points, no image search) that
// `all` adds. The first method is the default, whose metrics are also at the top level;
// every method's metrics and timing are under metrics.<method> and timing.<method>.

#include "dreamsense/core/status.hpp"
#include "dreamsense/eye_centers/eye_center_locator.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "synthetic_eyes.hpp"

namespace dreamsense::eye_centers {

inline constexpr const char* kLandmarkCentroid = "landmark_centroid";

struct EyeEvalOptions {
  std::string dataset = "bioid";  // name in the JSON: "bioid" or "synthetic-eyes"
  std::filesystem::path dir;      // BioID layout
  // When set, this synthetic set is written into `dir` first (dataset "synthetic-eyes").
  std::optional<SyntheticEyeSetOptions> generate;
  // Method names as above (CLI aliases "improved" and "all" accepted); first = default.
  std::vector<std::string> methods{"improved_integro_differential"};
  EyeCenterLocatorOptions locator;  // its `method` is ignored (each method runs in turn)
  std::filesystem::path face_cascade =
      "/usr/share/opencv4/haarcascades/haarcascade_frontalface_alt2.xml";
  std::filesystem::path landmark_model = "/usr/share/dlib/shape_predictor_68_face_landmarks.dat";
  double min_face_px = 40;  // BioID faces are 90-150 px wide
  Status check() const;
};

// Expands "all" and "improved"; unknown names are errors.
Result<std::vector<std::string>> expand_eye_methods(const std::vector<std::string>& names);

Result<nlohmann::json> run_eye_eval(const EyeEvalOptions& options,
                                    const std::function<void(double)>& progress = {});

}  // namespace dreamsense::eye_centers
