#include "dreamsense/batch/process_pool.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <poll.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace dreamsense::batch {
namespace {

volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void ds_batch_on_stop_signal(int s) { g_stop_signal = s; }

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(b, e - b + 1));
}

bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

std::string signal_name(int s) {
  switch (s) {
    case SIGSEGV:
      return "SIGSEGV";
    case SIGABRT:
      return "SIGABRT";
    case SIGKILL:
      return "SIGKILL";
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    case SIGBUS:
      return "SIGBUS";
    case SIGFPE:
      return "SIGFPE";
    case SIGILL:
      return "SIGILL";
    case SIGPIPE:
      return "SIGPIPE";
    default:
      return fmt::format("{}", s);
  }
}

// Decimal digits of a non-negative int into buf (async-signal-safe); returns the length.
size_t format_int(int v, char* buf) {
  char tmp[16];
  size_t n = 0;
  do {
    tmp[n++] = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v > 0 && n < sizeof tmp);
  for (size_t i = 0; i < n; ++i) buf[i] = tmp[n - 1 - i];
  return n;
}

struct Running {
  size_t index;
  pid_t pid;
  std::chrono::steady_clock::time_point start;
  bool terminated = false;  // SIGTERM sent by the pool
};

}  // namespace

std::string failure_reason(std::string_view output, int exit_code, int term_signal) {
  std::vector<std::string> lines;
  size_t pos = 0;
  while (pos <= output.size()) {
    size_t end = output.find('\n', pos);
    if (end == std::string_view::npos) end = output.size();
    std::string_view line = output.substr(pos, end - pos);
    if (auto cr = line.rfind('\r'); cr != std::string_view::npos && cr + 1 < line.size())
      line = line.substr(cr + 1);  // a progress bar's carriage returns: keep the last part
    if (auto t = trim(line); !t.empty()) lines.push_back(std::move(t));
    pos = end + 1;
  }
  std::string found;
  for (auto it = lines.rbegin(); it != lines.rend() && found.empty(); ++it) {
    if (starts_with(*it, "error:"))
      found = trim(std::string_view(*it).substr(6));
    else if (it->find("[error]") != std::string::npos ||
             it->find("[critical]") != std::string::npos || starts_with(*it, "terminate called"))
      found = *it;
  }
  // Else the last line, but not CLI11's closing hint after a usage error.
  while (found.empty() && !lines.empty()) {
    if (starts_with(lines.back(), "Run with --help")) {
      lines.pop_back();
      continue;
    }
    found = lines.back();
  }
  if (found.size() > 400) found = found.substr(0, 397) + "...";
  if (term_signal != 0) {
    std::string r = "killed by signal " + signal_name(term_signal);
    const char* desc = ::strsignal(term_signal);
    if (desc) r += fmt::format(" ({})", desc);
    return found.empty() ? r : r + ": " + found;
  }
  if (!found.empty()) return found;
  return fmt::format("exit code {}", exit_code);
}

std::string read_tail(const std::filesystem::path& path, size_t max_bytes) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return {};
  const std::streamoff size = in.tellg();
  const std::streamoff from = size > static_cast<std::streamoff>(max_bytes)
                                  ? size - static_cast<std::streamoff>(max_bytes)
                                  : 0;
  in.seekg(from);
  std::string text(static_cast<size_t>(size - from), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<size_t>(in.gcount()));
  return text;
}

void run_pool(const std::vector<ChildCommand>& commands, const PoolOptions& options,
              const std::function<void(size_t)>& on_start,
              const std::function<void(size_t, const ChildOutcome&)>& on_finish) {
  using Clock = std::chrono::steady_clock;
  const size_t workers = static_cast<size_t>(std::max(1, options.workers));
  const auto stop = [&] { return options.stop_requested && options.stop_requested(); };
  std::vector<Running> running;
  size_t next = 0;
  bool stopping = false;
  Clock::time_point kill_at{};
  const pid_t parent = ::getpid();

  auto finish = [&](size_t i, ChildOutcome o) {
    if (on_finish) on_finish(i, o);
  };
  auto launch = [&](size_t i) {
    const auto& c = commands[i];
    if (on_start) on_start(i);
    ChildOutcome failed;
    failed.started = true;
    if (c.argv.empty()) {
      failed.reason = "empty command";
      return finish(i, failed);
    }
    const int log_fd = ::open(c.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (log_fd < 0) {
      failed.reason = fmt::format("{}: cannot write: {}", c.log.string(), std::strerror(errno));
      return finish(i, failed);
    }
    const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    std::vector<char*> argv;
    for (const auto& a : c.argv) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const std::string exec_failed = "error: cannot execute " + c.argv[0] + ": errno ";
    const auto start = Clock::now();
    const pid_t pid = ::fork();
    if (pid == 0) {
      // Child: only async-signal-safe calls until exec.
      ::setpgid(0, 0);
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (::getppid() != parent) ::_exit(127);  // the pool died before prctl took effect
      ::signal(SIGINT, SIG_DFL);
      ::signal(SIGTERM, SIG_DFL);
      ::signal(SIGPIPE, SIG_DFL);
      sigset_t none;
      sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);
      ::dup2(log_fd, STDOUT_FILENO);
      ::dup2(log_fd, STDERR_FILENO);
      ::execv(argv[0], argv.data());
      const int e = errno;
      char num[16];
      const size_t n = format_int(e, num);
      [[maybe_unused]] auto w1 = ::write(STDERR_FILENO, exec_failed.data(), exec_failed.size());
      [[maybe_unused]] auto w2 = ::write(STDERR_FILENO, num, n);
      [[maybe_unused]] auto w3 = ::write(STDERR_FILENO, "\n", 1);
      ::_exit(127);
    }
    const int fork_errno = errno;
    ::close(log_fd);
    if (null_fd >= 0) ::close(null_fd);
    if (pid < 0) {
      failed.reason = fmt::format("cannot start a process: {}", std::strerror(fork_errno));
      return finish(i, failed);
    }
    ::setpgid(pid, pid);  // also here, so that killpg works even before the child ran
    running.push_back({i, pid, start});
  };

  while (next < commands.size() || !running.empty()) {
    if (!stopping && stop()) {
      stopping = true;
      for (auto& r : running) {
        ::kill(-r.pid, SIGTERM);
        r.terminated = true;
      }
      kill_at = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(options.kill_grace_s));
      for (; next < commands.size(); ++next) finish(next, ChildOutcome{});  // never started
    }
    while (!stopping && running.size() < workers && next < commands.size()) launch(next++);
    if (stopping && Clock::now() >= kill_at)
      for (const auto& r : running) ::kill(-r.pid, SIGKILL);

    bool reaped = false;
    for (auto it = running.begin(); it != running.end();) {
      int status = 0;
      const pid_t got = ::waitpid(it->pid, &status, WNOHANG);
      if (got == 0 || (got < 0 && errno == EINTR)) {
        ++it;
        continue;
      }
      ChildOutcome o;
      o.started = true;
      o.seconds = std::chrono::duration<double>(Clock::now() - it->start).count();
      if (got < 0) {
        o.reason = fmt::format("lost the child process: {}", std::strerror(errno));
      } else if (WIFEXITED(status)) {
        o.exit_code = WEXITSTATUS(status);
        o.ok = o.exit_code == 0;
      } else if (WIFSIGNALED(status)) {
        o.term_signal = WTERMSIG(status);
      }
      // Kill whatever the child left in its process group.
      ::kill(-it->pid, SIGKILL);
      o.interrupted = it->terminated && !o.ok;
      if (!o.ok && o.reason.empty())
        o.reason = o.interrupted ? "interrupted"
                                 : failure_reason(read_tail(commands[it->index].log), o.exit_code,
                                                  o.term_signal);
      const size_t index = it->index;
      it = running.erase(it);
      reaped = true;
      finish(index, o);
    }
    if (!reaped && !running.empty())
      std::this_thread::sleep_for(std::chrono::duration<double>(options.poll_s));
  }
}

Result<CapturedRun> run_captured(const std::vector<std::string>& argv) {
  if (argv.empty()) return make_error(ErrorCode::kInvalidArgument, "run_captured: empty command");
  int out_pipe[2], err_pipe[2];
  if (::pipe2(out_pipe, O_CLOEXEC) != 0)
    return make_error(ErrorCode::kIoError, "cannot make a pipe: {}", std::strerror(errno));
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) {
    ::close(out_pipe[0]);
    ::close(out_pipe[1]);
    return make_error(ErrorCode::kIoError, "cannot make a pipe: {}", std::strerror(errno));
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  if (rc != 0) {
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    return make_error(ErrorCode::kNotFound, "cannot run {}: {}", argv[0], std::strerror(rc));
  }
  CapturedRun run;
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&run.out, &run.err};
  int open_fds = 2;
  char buf[4096];
  while (open_fds > 0) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t n = ::read(fds[k].fd, buf, sizeof buf);
      if (n > 0) {
        sinks[k]->append(buf, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        ::close(fds[k].fd);
        fds[k].fd = -1;
        --open_fds;
      }
    }
  }
  for (auto& f : fds)
    if (f.fd >= 0) ::close(f.fd);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) run.term_signal = WTERMSIG(status);
  return run;
}

StopSignals::StopSignals() {
  g_stop_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = ds_batch_on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking call returns and the loop notices
  ::sigaction(SIGINT, &sa, &old_int_);
  ::sigaction(SIGTERM, &sa, &old_term_);
}

StopSignals::~StopSignals() {
  ::sigaction(SIGINT, &old_int_, nullptr);
  ::sigaction(SIGTERM, &old_term_, nullptr);
}

bool StopSignals::requested() const { return g_stop_signal != 0; }
int StopSignals::signal() const { return g_stop_signal; }

}  // namespace dreamsense::batch
