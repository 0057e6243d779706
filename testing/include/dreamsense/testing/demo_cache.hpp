#pragma once
// A demo session generated once per test executable and build folder, shared by all its tests.
// ctest runs every TEST in a process of its own, so a session generated "once per binary" in
// memory was generated again by each test: ~1 s each in the release build, ~20 s under ASan
// (issue 18: CI's sanitizer stage).

#include "dreamsense/core/status.hpp"
#include "dreamsense/sim/demo_session.hpp"

#include <filesystem>
#include <string>

namespace dreamsense::testing {

// The session of `options` (its out_dir and overwrite are ignored) in
// <build>/test-data/<this executable>/<name>. It is generated when missing or older than the
// executable (a relink, e.g. after a change to the simulator, regenerates it); a file lock makes
// tests running in parallel wait for one generation. `name` must differ for different options.
Result<std::filesystem::path> cached_demo_session(const std::string& name,
                                                  sim::DemoOptions options);

}  // namespace dreamsense::testing
