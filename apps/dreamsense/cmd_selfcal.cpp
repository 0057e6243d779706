// Self-calibration before an analysis (issue 15): `--subject auto`, and the default when the
// session's subject has no calibration folder. The library self_calibration/ decides when it
// runs, builds the face model from the session and points the analysis at its files; this maps
// the flags to its mode.

#include "commands.hpp"

namespace dreamsense::app {

SelfCalibrationMode self_calibration_mode(const SubjectFlags& flags) {
  if (flags.subject == "auto") return SelfCalibrationMode::kAlways;
  if (flags.subject == "none") return SelfCalibrationMode::kNever;
  return SelfCalibrationMode::kWhenNoSubject;
}

}  // namespace dreamsense::app
