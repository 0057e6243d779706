// `dreamsense batch --slurm` against a real single-node Slurm cluster that the test starts on
// 127.0.0.1 (munged, slurmctld and slurmd from Debian's munge and slurm-wlm, with a minimal
// slurm.conf in a temporary folder), then `batch collect`. Skipped, with the reason, when the
// packages are not installed or the daemons cannot start (e.g. without the privileges slurmd
// needs).

#include "dreamsense/batch/batch.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "test_util.hpp"

namespace dreamsense::batch {
namespace {
namespace fs = std::filesystem;
using test::read_table;
using test::read_text;
using test::TempDir;
using test::write_text;

fs::path demo(int seed) {
  static const fs::path dir = [] {
    const fs::path d = DREAMSENSE_BATCH_DEMO_DIR;
    auto r = run_captured(
        {"sh", DREAMSENSE_SOURCE_DIR "/batch/test/make_demos.sh", DREAMSENSE_EXE, d.string(), "3"});
    EXPECT_TRUE(r && r->exit_code == 0) << (r ? r->err : r.error().message);
    return d;
  }();
  return dir / ("seed" + std::to_string(seed));
}

// A program in PATH or the sbin folders (daemons live in /usr/sbin).
fs::path find_program(const std::string& name) {
  std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  path += ":/usr/sbin:/sbin:/usr/local/sbin";
  size_t start = 0;
  while (start <= path.size()) {
    const size_t end = std::min(path.find(':', start), path.size());
    const fs::path p = fs::path(path.substr(start, end - start)) / name;
    if (!p.parent_path().empty() && ::access(p.c_str(), X_OK) == 0) return p;
    start = end + 1;
  }
  return {};
}

int free_port() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  int port = 0;
  if (::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  ::close(s);
  return port;
}

// The daemons, as children that die with the test; stopped (TERM, then KILL) on destruction.
class Daemons {
 public:
  ~Daemons() {
    for (pid_t p : pids_) ::kill(p, SIGTERM);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    for (pid_t p : pids_) {
      int status = 0;
      while (::waitpid(p, &status, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() > deadline) {
          ::kill(p, SIGKILL);
          ::waitpid(p, &status, 0);
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  }
  void start(const std::vector<std::string>& argv, const fs::path& log) {
    std::vector<char*> a;
    std::vector<std::string> copy = argv;
    for (auto& s : copy) a.push_back(s.data());
    a.push_back(nullptr);
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (::getppid() != parent) ::_exit(1);
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, STDOUT_FILENO);
      ::dup2(fd, STDERR_FILENO);
      ::execv(a[0], a.data());
      ::_exit(127);
    }
    if (pid > 0) pids_.push_back(pid);
  }
  // A daemon that has already exited (it could not start).
  bool any_exited() {
    for (pid_t p : pids_) {
      int status = 0;
      if (::waitpid(p, &status, WNOHANG) == p) return true;
    }
    return false;
  }

 private:
  std::vector<pid_t> pids_;
};

std::string tail(const fs::path& p, size_t n = 600) {
  const std::string s = read_text(p);
  return s.size() > n ? s.substr(s.size() - n) : s;
}

CapturedRun run(const std::vector<std::string>& argv) {
  auto r = run_captured(argv);
  if (!r) throw std::runtime_error(r.error().message);
  return *r;
}

TEST(BatchSlurm, JobArrayOnALocalClusterThenCollect) {
  std::map<std::string, fs::path> prog;
  for (const char* name :
       {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "scontrol"}) {
    prog[name] = find_program(name);
    if (prog[name].empty())
      GTEST_SKIP() << name << " is not installed (Debian packages slurm-wlm and munge; "
                   << "tools/setup.sh installs them)";
  }
  TempDir t;
  const fs::path d = t.path();
  ::chmod(d.c_str(), 0755);
  fs::create_directories(d / "munge");
  ::chmod((d / "munge").c_str(), 0700);
  fs::create_directories(d / "state");
  fs::create_directories(d / "spool");
  {
    // A fresh munge key for this cluster only.
    std::ifstream rnd("/dev/urandom", std::ios::binary);
    std::string key(1024, '\0');
    rnd.read(key.data(), static_cast<std::streamsize>(key.size()));
    write_text(d / "munge" / "munge.key", key);
    ::chmod((d / "munge" / "munge.key").c_str(), 0600);
  }
  const passwd* pw = ::getpwuid(::geteuid());
  const std::string user = pw ? pw->pw_name : "root";
  const int ctld_port = free_port(), slurmd_port = free_port();
  ASSERT_GT(ctld_port, 0);
  const fs::path socket = d / "munge" / "munge.sock";
  const fs::path conf = d / "slurm.conf";
  write_text(conf, fmt::format(R"(# single-node test cluster (dreamsense batch_slurm_test)
ClusterName=dstest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort={ctld}
SlurmdPort={slurmd}
AuthType=auth/munge
AuthInfo=socket={sock}
CredType=cred/munge
SlurmUser={user}
SlurmdUser={user}
StateSaveLocation={dir}/state
SlurmdSpoolDir={dir}/spool
SlurmctldPidFile={dir}/slurmctld.pid
SlurmdPidFile={dir}/slurmd.pid
SlurmctldLogFile={dir}/slurmctld.log
SlurmdLogFile={dir}/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName=dsnode NodeAddr=127.0.0.1 NodeHostname=localhost CPUs=2 RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=dsnode Default=YES MaxTime=INFINITE State=UP
)",
                               fmt::arg("ctld", ctld_port), fmt::arg("slurmd", slurmd_port),
                               fmt::arg("sock", socket.string()), fmt::arg("user", user),
                               fmt::arg("dir", d.string())));
  write_text(d / "cgroup.conf", "CgroupPlugin=autodetect\nIgnoreSystemd=yes\n");
  ::setenv("SLURM_CONF", conf.c_str(), 1);  // for sinfo/sbatch here and in dreamsense batch

  Daemons daemons;
  daemons.start({prog["munged"].string(), "-F", "-f", "--socket=" + socket.string(),
                 "--key-file=" + (d / "munge" / "munge.key").string(),
                 "--pid-file=" + (d / "munge" / "munged.pid").string(),
                 "--seed-file=" + (d / "munge" / "munged.seed").string(),
                 "--log-file=" + (d / "munge" / "munged.log").string()},
                d / "munged.out");
  const auto wait_for = [](const std::function<bool()>& ok, std::chrono::seconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline) {
      if (ok()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return false;
  };
  if (!wait_for([&] { return fs::exists(socket); }, std::chrono::seconds(10)))
    GTEST_SKIP() << "munged could not start here: " << tail(d / "munged.out")
                 << tail(d / "munge" / "munged.log");
  daemons.start({prog["slurmctld"].string(), "-D", "-f", conf.string()}, d / "slurmctld.out");
  daemons.start({prog["slurmd"].string(), "-D", "-N", "dsnode", "-f", conf.string()},
                d / "slurmd.out");
  const auto node_state = [&] {
    auto r = run_captured({prog["sinfo"].string(), "-h", "-N", "-o", "%t"});
    return r && r->exit_code == 0 ? r->out : std::string();
  };
  if (!wait_for([&] { return node_state().rfind("idle", 0) == 0 || daemons.any_exited(); },
                std::chrono::seconds(40)) ||
      node_state().rfind("idle", 0) != 0)
    GTEST_SKIP() << "the Slurm daemons could not start here (node state \"" << node_state()
                 << "\"): slurmctld: " << tail(d / "slurmctld.out") << tail(d / "slurmctld.log")
                 << " slurmd: " << tail(d / "slurmd.out") << tail(d / "slurmd.log");

  // Submit two demo sessions as a job array, at most 2 tasks at a time.
  const fs::path out = d / "out";
  const auto sub = run({DREAMSENSE_EXE, "batch", demo(1).string(), demo(2).string(), "--out",
                        out.string(), "--slurm", "--jobs", "2"});
  ASSERT_EQ(sub.exit_code, 0) << sub.err;
  std::string job = sub.out;
  while (!job.empty() && job.back() == '\n') job.pop_back();
  ASSERT_FALSE(job.empty());
  ASSERT_EQ(job.find_first_not_of("0123456789"), std::string::npos) << job;
  EXPECT_NE(sub.err.find("batch collect " + out.string()), std::string::npos) << sub.err;
  const std::string script = read_text(out / "slurm" / "batch.sbatch");
  EXPECT_NE(script.find("#SBATCH --array=0-1%2"), std::string::npos) << script;
  EXPECT_EQ(read_text(out / "slurm" / "inputs.txt"),
            fs::canonical(demo(1)).string() + "\n" + fs::canonical(demo(2)).string() + "\n");

  // Wait for the array and the collect job.
  const bool ended = wait_for(
      [&] {
        auto q = run_captured({prog["squeue"].string(), "-h", "-u", user, "-o", "%i"});
        return q && q->exit_code == 0 && q->out.empty();
      },
      std::chrono::seconds(600));
  ASSERT_TRUE(ended) << "the jobs did not end; slurmd: " << tail(d / "slurmd.log");
  for (int i : {0, 1})
    EXPECT_TRUE(fs::exists(out / "slurm" / fmt::format("task-{}_{}.out", job, i)))
        << "array task " << i << " did not run; slurmd: " << tail(d / "slurmd.log");

  // The collect job wrote batch.csv; `batch collect` writes the same.
  ASSERT_TRUE(fs::exists(out / "batch.csv")) << "collect job: " << [&] {
    std::string s;
    for (const auto& e : fs::directory_iterator(out / "slurm"))
      s += e.path().filename().string() + ": " + tail(e.path(), 300) + "\n";
    return s;
  }();
  const std::string by_job = read_text(out / "batch.csv");
  const auto c = run({DREAMSENSE_EXE, "batch", "collect", out.string()});
  EXPECT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(read_text(out / "batch.csv"), by_job);
  const auto table = read_table(out / "batch.csv");
  ASSERT_EQ(table.size(), 2u);
  for (const auto& row : table) {
    EXPECT_EQ(row.at("status"), "ok") << row.at("input") << ": " << row.at("reason") << "\n"
                                      << tail(out / (row.at("output") + ".log"));
    EXPECT_EQ(row.at("ticks"), "75");
    EXPECT_TRUE(fs::exists(out / row.at("output") / kDoneFile));
  }

  // Submitting again: everything is finished, nothing is submitted.
  const auto again = run({DREAMSENSE_EXE, "batch", demo(1).string(), demo(2).string(), "--out",
                          out.string(), "--slurm"});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(again.out.empty()) << again.out;
  EXPECT_NE(again.err.find("nothing left to analyse (2 finished)"), std::string::npos) << again.err;
}

}  // namespace
}  // namespace dreamsense::batch
