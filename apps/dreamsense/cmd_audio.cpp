// `dreamsense eval doa` (issue 5; being written).

#include "commands.hpp"

namespace dreamsense::app {

void add_eval_doa(CLI::App&, const GlobalFlags&, int&) {}

}  // namespace dreamsense::app
