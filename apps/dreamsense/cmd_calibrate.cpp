// `dreamsense calibrate ...` and `dreamsense eval calibration` (issue 3; being written).

#include "commands.hpp"

namespace dreamsense::app {

void add_calibrate(CLI::App&, const GlobalFlags&, int&) {}
void add_eval_calibration(CLI::App&, const GlobalFlags&, int&) {}

}  // namespace dreamsense::app
