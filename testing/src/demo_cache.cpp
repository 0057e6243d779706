#include "dreamsense/testing/demo_cache.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/file.h>
#include <system_error>
#include <unistd.h>

namespace dreamsense::testing {
namespace {

namespace fs = std::filesystem;

// Holds an exclusive flock on a file for its lifetime.
class FileLock {
 public:
  explicit FileLock(const fs::path& file) : fd_(::open(file.c_str(), O_CREAT | O_RDWR, 0644)) {
    if (fd_ >= 0 && ::flock(fd_, LOCK_EX) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);  // closing releases the lock
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  bool locked() const { return fd_ >= 0; }

 private:
  int fd_;
};

}  // namespace

Result<fs::path> cached_demo_session(const std::string& name, sim::DemoOptions options) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return make_error(ErrorCode::kIoError, "/proc/self/exe: {}", ec.message());
  const fs::path root = fs::path(DREAMSENSE_BINARY_DIR) / "test-data" / exe.filename();
  fs::create_directories(root, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", root.string(), ec.message());
  const FileLock lock(root / (name + ".lock"));
  if (!lock.locked())
    return make_error(ErrorCode::kIoError, "{}: cannot lock: {}", (root / name).string(),
                      std::strerror(errno));
  const fs::path dir = root / name, done = root / (name + ".done");
  // `.done` is written after a complete generation; its time says which executable made it.
  std::error_code done_ec, exe_ec;
  const auto made = fs::last_write_time(done, done_ec);
  const auto linked = fs::last_write_time(exe, exe_ec);
  if (!done_ec && !exe_ec && made >= linked) return dir;
  fs::remove(done, ec);
  fs::remove_all(dir, ec);
  options.out_dir = dir;
  options.overwrite = true;
  auto generated = sim::generate_demo_session(options);
  if (!generated) return tl::unexpected(generated.error());
  if (FILE* f = std::fopen(done.c_str(), "w"); f != nullptr) std::fclose(f);
  return dir;
}

}  // namespace dreamsense::testing
