#pragma once
// The smoothing factor of a One Euro filter step (Casiez, Roussel & Vogel, CHI 2012): a first-order
// low-pass with cut-off `cutoff_hz` moves a fraction alpha = 1 / (1 + tau / dt), tau = 1 / (2 pi
// f_c), of the way to a new sample `dt_s` seconds after the last one. Used by the head-pose and
// gaze filters.

#include <numbers>

namespace dreamsense {

inline double one_euro_alpha(double cutoff_hz, double dt_s) {
  const double tau = 1.0 / (2 * std::numbers::pi * cutoff_hz);
  return 1.0 / (1.0 + tau / dt_s);
}

}  // namespace dreamsense
