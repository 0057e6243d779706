#pragma once
// Which toy is it (F19 identifyObject): the DREAM ids 0 car, 1 cup, 2 flower, 3 plane and any toy
// a user enrols (`dreamsense enroll objects`).
//
// Two identifiers over the same views (a crop of the top camera around a blob):
//  - `hog_svm`, the seed's (original-dream.md §3.6): the crop resized to 32x32 grey, HOG with
//    16-px blocks, 8-px stride, 8-px cells, 9 bins (324-D), C-SVC with an RBF kernel, gamma 0.09,
//    C 10. It has no rejection: every blob gets one of the trained ids.
//  - `gallery`, ours: a colour histogram of the blob's own pixels (hue x saturation, plus value
//    for unsaturated pixels; square-rooted, i.e. the Hellinger embedding) and fHOG of the crop
//    rotated so that the blob's long axis is horizontal (both 0 and 180 degree versions are
//    enrolled), compared by nearest neighbour with every enrolled exemplar; the nearest class
//    wins when its distance is below the gallery's rejection threshold, otherwise the view is
//    `unknown` (id -1): hands, arms and toys nobody enrolled. Few-shot by design: a handful of
//    crops per toy is enough, and adding a toy never retrains the others.
//
// Both live in one versioned gallery file (OpenCV YAML, format "dreamsense.object_gallery",
// version 1): the classes (id, label, physical size), the exemplar features, the rejection
// threshold, and the baseline SVM trained on the same views.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::objects {

inline constexpr int kUnknownObject = -1;

// A crop around one object: the BGR pixels, the object's mask in it and its footprint (minimum-
// area rectangle of the mask, crop coordinates).
struct ObjectView {
  cv::Mat crop;  // CV_8UC3
  cv::Mat mask;  // CV_8U, same size, 255 = object
  cv::RotatedRect footprint;
};

// The view of `box` in `frame`; `mask` (box-sized) when the detector has one, otherwise the
// object is separated from the surrounding table by colour (the crop's border colour).
// `footprint` (frame coordinates) when the detector has it, otherwise it is computed from the mask.
Result<ObjectView> make_view(const cv::Mat& frame_bgr, const cv::Rect& box,
                             const cv::Mat& mask = {},
                             const std::optional<cv::RotatedRect>& footprint = std::nullopt);

struct ObjectClass {
  int id = kUnknownObject;
  std::string label;
  // Physical size (m): length (long side of the top face), width, height. Used for 3-D positions
  // (the top face's height above the table) and the grip rule.
  cv::Vec3d size_m{0.10, 0.075, 0.03};
};

// The gallery of the demo's four toys shipped in modalities/objects/models (MODEL_CARD.md).
std::filesystem::path default_gallery_path();

// The DREAM toys (ids 0-3) with the demo's 10 x 7.5 x 3 cm boxes.
std::vector<ObjectClass> dream_toy_classes();

struct Identification {
  int id = kUnknownObject;
  std::string label = "unknown";
  double score = 0;     // gallery: 1 - distance / threshold (> 0 accepted); hog_svm: 1
  double distance = 0;  // gallery: nearest-neighbour distance
};

struct LabelledView {
  int id = kUnknownObject;
  ObjectView view;
};

// Our descriptor (colour + rotation-normalised fHOG); two rows: the view and its 180-degree turn.
cv::Mat gallery_features(const ObjectView& view);
// The seed's 324-D HOG of a view.
cv::Mat dream_hog_features(const ObjectView& view);

struct GalleryOptions {
  double hog_weight = 0.5;  // distance = colour distance + hog_weight * HOG distance
  // Rejection threshold = this x the 95th percentile of the enrolment views' leave-one-view-out
  // nearest distances within their class (set at enrolment, stored in the file).
  double rejection_factor = 1.6;
  int max_exemplars_per_class = 40;  // evenly thinned when more views are given
  bool train_baseline = true;        // also train the seed's HOG + RBF-SVM on the same views
  Status check() const;
};

class ObjectGallery {
 public:
  static constexpr int kFormatVersion = 1;
  static constexpr const char* kFormatName = "dreamsense.object_gallery";

  // Enrols labelled views: every id in `views` must be in `classes`. Error when a class has no
  // view or a view is empty.
  static Result<ObjectGallery> enrol(const std::vector<ObjectClass>& classes,
                                     const std::vector<LabelledView>& views,
                                     const GalleryOptions& options = {});
  // Adds the views of further classes (or more views of known ones) to this gallery; the
  // threshold is recomputed, the baseline SVM retrained.
  Status add(const std::vector<ObjectClass>& classes, const std::vector<LabelledView>& views);

  // The same gallery without one class (threshold and baseline recomputed): to measure how an
  // object nobody enrolled is treated.
  Result<ObjectGallery> without(int id) const;

  Identification identify(const ObjectView& view) const;           // ours, with rejection
  Identification identify_baseline(const ObjectView& view) const;  // the seed's HOG + SVM
  bool has_baseline() const;

  const std::vector<ObjectClass>& classes() const { return classes_; }
  const ObjectClass* find(int id) const;
  double threshold() const { return threshold_; }
  void set_threshold(double t) { threshold_ = t; }
  const GalleryOptions& options() const { return options_; }
  int exemplars() const { return features_.rows; }

  Status save(const std::filesystem::path& path) const;  // atomic
  static Result<ObjectGallery> load(const std::filesystem::path& path);

 private:
  void nearest(const cv::Mat& f, int& id, double& d, int skip_view = -1) const;
  Status append(const std::vector<LabelledView>& views);
  Status finish();  // threshold and baseline from the stored features

  GalleryOptions options_;
  std::vector<ObjectClass> classes_;
  cv::Mat features_;                // one row per exemplar (CV_32F): colour | fHOG
  std::vector<int> feature_ids_;    // class id per row
  std::vector<int> feature_views_;  // enrolment view per row (two rows per view)
  cv::Mat baseline_samples_;        // the seed's HOG per view (CV_32F), kept to retrain
  std::vector<int> baseline_ids_;
  double threshold_ = 0;
  cv::Ptr<cv::ml::SVM> svm_;
};

}  // namespace dreamsense::objects
