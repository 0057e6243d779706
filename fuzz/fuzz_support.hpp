#pragma once
// Shared by the libFuzzer harnesses (fuzz/README.md): a private scratch folder for parsers whose
// API takes a path (removed when the fuzzer exits) and quiet logging (a parser's warning per
// input would flood the fuzzer's output and slow it down).

#include "dreamsense/core/log.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>
#include <unistd.h>

namespace dreamsense::fuzz {

class ScratchDir {
 public:
  ScratchDir()
      : dir_(std::filesystem::temp_directory_path() /
             ("dreamsense-fuzz-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(dir_);
    log::set_level(log::Level::kOff);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return dir_; }

  // Writes `bytes` to <scratch>/<name> (replacing it) and returns the path.
  std::filesystem::path write(const std::string& name, std::string_view bytes) const {
    const std::filesystem::path p = dir_ / name;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return p;
  }

 private:
  std::filesystem::path dir_;
};

inline const ScratchDir& scratch() {
  static const ScratchDir dir;
  return dir;
}

inline std::string_view as_text(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

}  // namespace dreamsense::fuzz
