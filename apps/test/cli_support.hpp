#pragma once
// What the command-line tests share: run the built `dreamsense` (DREAMSENSE_EXE, a compile
// definition of each test target) with -q and its stderr captured, and read files back.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace dreamsense::cli_support {

struct RunResult {
  int exit_code = -1;
  std::string err;  // stderr
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// `dreamsense -q ARGS` (without -q when !quiet: the info lines too), stderr captured (stdout
// goes to the test's own).
inline RunResult run(const std::string& args, bool quiet = true) {
  const std::filesystem::path err_file =
      std::filesystem::temp_directory_path() / ("ds_cli_err_" + std::to_string(::getpid()));
  const std::string cmd =
      std::string(DREAMSENSE_EXE) + (quiet ? " -q " : " ") + args + " 2> " + err_file.string();
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(err_file);
  std::filesystem::remove(err_file);
  return r;
}

inline std::vector<nlohmann::json> read_jsonl(const std::filesystem::path& p) {
  std::vector<nlohmann::json> out;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) out.push_back(nlohmann::json::parse(line));
  return out;
}

// The 4-second demo (seed 3) that the ctest fixture `cli_demo_fixture` makes once for all the
// command-line tests (DREAMSENSE_CLI_DEMO_DIR); a test binary run by hand makes its own under
// `root`, which is cleared first. `analysed`: the fixture's analysis is needed too.
inline std::filesystem::path fixture_demo(const std::filesystem::path& root, bool analysed = true) {
  std::filesystem::remove_all(root);
  std::filesystem::create_directories(root);
  const std::filesystem::path shared = DREAMSENSE_CLI_DEMO_DIR;
  if (std::filesystem::exists(shared / (analysed ? "summary.json" : "session.yaml"))) return shared;
  const std::filesystem::path out = root / "demo";
  RunResult r = run("demo --out " + out.string() + " --seed 3 --duration 4" +
                    (analysed ? "" : " --no-analyze"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return out;
}

}  // namespace dreamsense::cli_support
