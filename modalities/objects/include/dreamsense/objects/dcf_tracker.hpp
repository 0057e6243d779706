#pragma once
// The project's tracker, named `dreamsense` in make_tracker: a discriminative correlation filter
// on fHOG with a colour model, scale search and failure detection. Each part is published:
//  - translation: multi-channel linear correlation filter learnt in the Fourier domain with a
//    running numerator/denominator (Danelljan, Hager, Khan & Felsberg, "Accurate Scale
//    Estimation for Robust Visual Tracking" (DSST), BMVC 2014, eq. 3-5) on fHOG cells (fhog.hpp)
//    with a Hann window; search window = target * (1 + padding) (Henriques et al., "High-Speed
//    Tracking with Kernelized Correlation Filters", TPAMI 2015, padding 1.5), resampled to a
//    fixed template area so the cost does not depend on the target's size;
//  - colour: per-pixel foreground/background colour-histogram likelihood averaged over the
//    target box, merged with the filter response as (1 - a) * cf + a * colour (Bertinetto,
//    Valmadre, Golodetz, Miksik & Torr, "Staple: Complementary Learners for Real-Time Tracking",
//    CVPR 2016; a = 0.3, 32 bins per channel, learning rates 0.01 / 0.04, lambda 1e-3, output
//    sigma 1/16 as there);
//  - scale: a separate 1-D filter over 33 scales, step 1.02 (DSST §3.2, learning rate 0.025,
//    scale model area <= 32x16 as in Staple);
//  - failure detection: the peak value and the average peak-to-correlation energy (APCE) of the
//    merged response; the models are updated only while both stay above 0.7 and 0.45 of their
//    running means (Wang, Liu & Huang, "Large Margin Object Tracking with Circulant Feature
//    Maps" (LMCF), CVPR 2017), so an occluder is not learnt; after `lost_after` frames in a row
//    below them the target is reported lost and re-detected by evaluating the filter on a 3x3
//    grid of windows around the last position until a confident peak reappears.
// The DREAM seed had no tracker at all (original-dream.md §3.10).

#include "dreamsense/objects/tracker.hpp"

#include <vector>

namespace dreamsense::objects {

struct DcfTrackerOptions {
  int cell_size = 4;                      // fHOG cell (px of the resampled window)
  double padding = 1.5;                   // window = target * (1 + padding) (KCF)
  double template_side = 112;             // the window is resampled to about this^2 px
  double output_sigma_factor = 1.0 / 16;  // Gaussian label sigma = sqrt(w h) * this (Staple)
  double lambda = 1e-3;                   // ridge regularisation (Staple)
  double learning_rate = 0.01;            // filter (Staple learning_rate_cf)
  int colour_bins = 32;                   // per channel (Staple n_bins)
  double colour_learning_rate = 0.04;     // (Staple learning_rate_pwp)
  double inner_padding = 0.2;             // foreground = target shrunk by this x mean side (Staple)
  double merge_factor = 0.3;              // weight of the colour response (Staple)
  int scales = 33;                        // DSST
  double scale_step = 1.02;               // DSST
  double scale_sigma_factor = 0.25;       // DSST
  double scale_learning_rate = 0.025;     // DSST
  double scale_model_max_area = 512;  // px of the resampled target for the scale filter (Staple)
  double peak_ratio = 0.7;            // LMCF beta1: update only if peak >= this x running mean
  double apce_ratio = 0.45;           // LMCF beta2: ... and APCE >= this x running mean
  double baseline_rate = 0.1;         // running average of peak/APCE over confident frames
  double baseline_low_rate = 0.02;    // ... and over low frames (a lasting change is learnt)
  int lost_after = 10;                // frames below both ratios before the target is "lost"
  bool redetect = true;               // search a 3x3 grid of windows while lost
  Status check() const;
};

class DcfTracker : public Tracker {
 public:
  explicit DcfTracker(DcfTrackerOptions options = {});
  ~DcfTracker() override;
  std::string_view name() const override { return "dreamsense"; }
  Status init(const cv::Mat& frame, const cv::Rect2d& box) override;
  Result<TrackerUpdate> update(const cv::Mat& frame) override;

  struct State;  // implementation detail (dcf_tracker.cpp)

 private:
  DcfTrackerOptions o_;
  std::unique_ptr<State> s_;
};

}  // namespace dreamsense::objects
