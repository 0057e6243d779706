// Small POSIX file helpers shared by the session reader, writer and manifest code (private to the
// sources library).
#pragma once

#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace dreamsense::sources::detail {

inline std::string errno_text(int err) { return std::strerror(err); }

// fsync of a directory, so that a rename or a new file in it survives a power cut. Best effort:
// a directory that cannot be opened is left alone (the files themselves were synced).
inline void sync_dir(const std::filesystem::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace dreamsense::sources::detail
