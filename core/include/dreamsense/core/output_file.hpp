#pragma once
// An output file that is only presented as complete when it is: it is written as
// "<name>.partial" and renamed to <name> by commit(). A run that fails leaves no file under the
// final name (the destructor removes an uncommitted partial file).

#include "dreamsense/core/status.hpp"

#include <cstdio>
#include <filesystem>
#include <string_view>

namespace dreamsense {

class OutputFile {
 public:
  OutputFile() = default;
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  Status open(const std::filesystem::path& final_path);
  Status write(std::string_view text);
  Status commit();  // flush, close, rename
  void abandon();   // close and delete the partial file
  bool is_open() const { return file_ != nullptr; }
  const std::filesystem::path& path() const { return final_; }

 private:
  std::FILE* file_ = nullptr;
  std::filesystem::path final_, partial_;
};

// Checks that `dir` exists (creating it) and that a file can be created in it.
Status ensure_writable_dir(const std::filesystem::path& dir);

}  // namespace dreamsense
