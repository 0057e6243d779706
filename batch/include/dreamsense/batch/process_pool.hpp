#pragma once
// A pool of N worker slots running child processes (fork + exec), each in its own process group
// with stdout and stderr captured to a log file and stdin from /dev/null. A child that crashes or
// exits non-zero is a failure whose reason is the last error line of its log; the others go on.
// When stop is requested (SIGINT/SIGTERM, see StopSignals) no more children are started and the
// running ones are terminated (SIGTERM, then SIGKILL after a grace period). Children also die
// with the pool's process (PR_SET_PDEATHSIG), so a killed batch leaves no orphan analyses.

#include "dreamsense/core/status.hpp"

#include <atomic>
#include <csignal>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::batch {

struct ChildCommand {
  std::vector<std::string> argv;  // argv[0]: the executable's path
  std::filesystem::path log;      // truncated, then receives the child's stdout and stderr
};

struct ChildOutcome {
  bool started = false;      // false: stop was requested before it could start
  bool ok = false;           // exited with status 0
  bool interrupted = false;  // terminated by the pool because stop was requested
  int exit_code = -1;        // when it exited
  int term_signal = 0;       // when a signal ended it
  double seconds = 0;        // wall time
  std::string reason;        // failures: one line (see failure_reason)
};

// The reason of a failed child, one line: the last line of its output that starts with "error:"
// (or contains "[error]"/"[critical]", or "terminate called"), else its last non-empty line (not
// CLI11's "Run with --help ..." hint); prefixed for a signal with "killed by signal SIGxxx";
// "exit code N" when it wrote nothing.
std::string failure_reason(std::string_view output, int exit_code, int term_signal);

// The last `max_bytes` of a file ("" when it cannot be read).
std::string read_tail(const std::filesystem::path& path, size_t max_bytes = 64 * 1024);

struct PoolOptions {
  int workers = 1;
  double kill_grace_s = 3.0;             // SIGTERM -> SIGKILL
  double poll_s = 0.02;                  // how often children are polled
  std::function<bool()> stop_requested;  // polled; true: stop (may be empty)
};

// Runs every command, at most options.workers at a time, in order. on_start(i) is called just
// before command i starts, on_finish(i, outcome) when it has ended (or will not start), both from
// the calling thread; every command gets exactly one on_finish.
void run_pool(const std::vector<ChildCommand>& commands, const PoolOptions& options,
              const std::function<void(size_t)>& on_start,
              const std::function<void(size_t, const ChildOutcome&)>& on_finish);

// Installs SIGINT/SIGTERM handlers that only set a flag (restored on destruction).
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  bool requested() const;
  int signal() const;  // the signal received (0: none)

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

struct CapturedRun {
  int exit_code = -1;
  int term_signal = 0;
  std::string out, err;  // the child's stdout and stderr
};

// Runs a short command to its end (no shell; argv[0] is looked up in PATH) with its stdout and
// stderr captured. An error only when it cannot be started (the message names the program).
Result<CapturedRun> run_captured(const std::vector<std::string>& argv);

}  // namespace dreamsense::batch
