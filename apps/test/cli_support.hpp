#pragma once
// What the command-line tests share: run the built `dreamsense` (DREAMSENSE_EXE, a compile
// definition of each test target) with -q and its stderr captured, and read files back.

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

// `dreamsense -q ARGS`, stderr captured (stdout goes to the test's own).
inline RunResult run(const std::string& args) {
  const std::filesystem::path err_file =
      std::filesystem::temp_directory_path() / ("ds_cli_err_" + std::to_string(::getpid()));
  const std::string cmd = std::string(DREAMSENSE_EXE) + " -q " + args + " 2> " + err_file.string();
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

}  // namespace dreamsense::cli_support
