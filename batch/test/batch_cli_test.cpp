// `dreamsense batch` as a user runs it, on short demo sessions (ctest fixture batch_demos):
// a batch with bad inputs among good ones, and a batch killed midway then resumed.

#include "dreamsense/batch/batch.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <fcntl.h>
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

// The demo sessions seed1..seed3 (made by the fixture, or here when run by hand).
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

CapturedRun dreamsense(std::vector<std::string> args) {
  args.insert(args.begin(), DREAMSENSE_EXE);
  auto r = run_captured(args);
  if (!r) throw std::runtime_error(r.error().message);
  return *r;
}

std::map<std::string, std::string> row_of(const std::vector<std::map<std::string, std::string>>& t,
                                          const fs::path& input) {
  for (const auto& r : t)
    if (r.at("input") == input.string()) return r;
  ADD_FAILURE() << "no row for " << input;
  return {};
}

TEST(BatchCli, SomeInputsFailTheOthersFinish) {
  TempDir t;
  // Bad inputs: a session whose session.yaml is malformed; a folder with a video no decoder can
  // read, an empty video and a text file; a duplicate.
  write_text(t / "broken" / "session.yaml", "streams: [\n  - {id: cam\n");
  write_text(t / "videos" / "garbage.mp4", std::string(4096, '\x5a'));
  write_text(t / "videos" / "empty.avi", "");
  write_text(t / "videos" / "notes.txt", "not a video\n");
  const fs::path out = t / "out";
  const auto r = dreamsense({"batch", demo(1).string(), (t / "broken").string(), demo(2).string(),
                             (t / "videos").string(), demo(3).string(), demo(1).string() + "/",
                             "--out", out.string(), "--jobs", "2"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  // Every failure listed on stderr with its reason.
  EXPECT_NE(r.err.find("failed: " + (t / "broken").string() + ": " +
                       (t / "broken" / "session.yaml").string()),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("failed: " + (t / "videos" / "garbage.mp4").string() + ": "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("failed: " + (t / "videos" / "empty.avi").string() + ": empty file"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("failed: " + demo(2).string()), std::string::npos) << r.err;

  const auto table = read_table(out / "batch.csv");
  ASSERT_EQ(table.size(), 8u);  // 3 demos, broken, 3 folder entries, the duplicate
  for (int seed : {1, 2, 3}) {
    const auto row = row_of(table, fs::canonical(demo(seed)));
    EXPECT_EQ(row.at("status"), "ok") << row.at("reason");
    EXPECT_EQ(row.at("ticks"), "75");  // 3 s at 25 Hz: the analysis' own figure
    EXPECT_EQ(row.at("media_seconds"), "3.0");
    EXPECT_GT(std::stod(row.at("seconds")), 0.0);
    const fs::path dir = out / row.at("output");
    EXPECT_TRUE(fs::exists(dir / "summary.json"));
    EXPECT_TRUE(fs::exists(dir / "report.html"));
    EXPECT_TRUE(fs::exists(dir / kDoneFile));
    EXPECT_NE(read_text(out / (row.at("output") + ".log")).find("batch: ok after"),
              std::string::npos);
  }
  const auto broken = row_of(table, fs::canonical(t / "broken"));
  EXPECT_EQ(broken.at("status"), "failed");
  EXPECT_NE(broken.at("reason").find("session.yaml"), std::string::npos) << broken.at("reason");
  const auto garbage = row_of(table, fs::canonical(t / "videos" / "garbage.mp4"));
  EXPECT_EQ(garbage.at("status"), "failed");
  EXPECT_NE(garbage.at("reason").find("garbage.mp4"), std::string::npos) << garbage.at("reason");
  EXPECT_EQ(row_of(table, fs::canonical(t / "videos" / "empty.avi")).at("status"), "failed");
  const auto notes = row_of(table, fs::canonical(t / "videos" / "notes.txt"));
  EXPECT_EQ(notes.at("status"), "skipped");
  EXPECT_NE(notes.at("reason").find(".txt"), std::string::npos);
  size_t duplicates = 0;
  for (const auto& row : table) duplicates += row.at("reason").rfind("duplicate of", 0) == 0;
  EXPECT_EQ(duplicates, 1u);

  // collect rebuilds the same table from the folders.
  const std::string before = read_text(out / "batch.csv");
  fs::remove(out / "batch.csv");
  const auto c = dreamsense({"batch", "collect", out.string()});
  EXPECT_EQ(c.exit_code, 1) << c.err;  // some failed
  EXPECT_EQ(read_text(out / "batch.csv"), before);

  // --out that is a file: one line, exit 1, nothing run.
  write_text(t / "file", "x");
  const auto f = dreamsense({"batch", demo(1).string(), "--out", (t / "file").string()});
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_EQ(f.err, "error: " + (t / "file").string() + ": --out exists and is not a folder\n");
}

// Starts `dreamsense batch ARGS` in the background, stderr to `err`.
pid_t start(const std::vector<std::string>& args, const fs::path& err) {
  std::vector<std::string> argv = {DREAMSENSE_EXE, "batch"};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> a;
  for (auto& s : argv) a.push_back(s.data());
  a.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, STDERR_FILENO);
    ::execv(a[0], a.data());
    ::_exit(127);
  }
  return pid;
}

// Processes whose command line mentions `text` (other than this test).
std::vector<pid_t> processes_mentioning(const std::string& text) {
  std::vector<pid_t> found;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = read_text(e.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find(text) != std::string::npos && std::stoi(name) != ::getpid())
      found.push_back(std::stoi(name));
  }
  return found;
}

TEST(BatchCli, KilledMidwayTheRerunRedoesOnlyTheUnfinished) {
  TempDir t;
  const fs::path out = t / "out";
  const std::vector<std::string> args = {
      demo(1).string(), demo(2).string(), demo(3).string(), "--out", out.string(), "--jobs", "1"};
  const pid_t pid = start(args, t / "first.err");
  ASSERT_GT(pid, 0);
  // Wait for the first finished analysis, then SIGKILL the batch (no chance to clean up).
  fs::path finished;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (finished.empty() && std::chrono::steady_clock::now() < deadline) {
    std::error_code ec;
    for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec))
      if (fs::exists(it->path() / kDoneFile)) finished = it->path();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_FALSE(finished.empty()) << read_text(t / "first.err");
  // Its analyses die with it (no orphan keeps writing into the batch folder).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_TRUE(processes_mentioning(out.string()).empty());

  const auto done_time = fs::last_write_time(finished / kDoneFile);
  const auto summary_time = fs::last_write_time(finished / "summary.json");
  size_t unfinished = 0;
  for (const auto& e : fs::directory_iterator(out))
    if (e.is_directory() && !fs::exists(e.path() / kDoneFile)) ++unfinished;
  EXPECT_LE(unfinished, 1u);  // jobs 1: at most the one running when killed

  // The same command again (not a terminal: one line per event on stderr).
  const pid_t again = start(args, t / "second.err");
  ::waitpid(again, &status, 0);
  const std::string err = read_text(t / "second.err");
  ASSERT_TRUE(WIFEXITED(status)) << err;
  EXPECT_EQ(WEXITSTATUS(status), 0) << err;
  EXPECT_NE(err.find("kept " + finished.filename().string() + " (finished earlier)"),
            std::string::npos)
      << err;
  if (unfinished == 1) EXPECT_NE(err.find("redoing a partial analysis"), std::string::npos) << err;
  size_t analysed = 0;
  for (size_t p = err.find("\nok "); p != std::string::npos; p = err.find("\nok ", p + 1))
    ++analysed;
  analysed += err.rfind("ok ", 0) == 0;
  EXPECT_EQ(analysed, 2u) << err;  // only the two unfinished ones
  EXPECT_EQ(fs::last_write_time(finished / kDoneFile), done_time);
  EXPECT_EQ(fs::last_write_time(finished / "summary.json"), summary_time);
  const auto table = read_table(out / "batch.csv");
  ASSERT_EQ(table.size(), 3u);
  for (const auto& row : table) EXPECT_EQ(row.at("status"), "ok") << row.at("input");
  EXPECT_NE(err.find("batch: 3 ok (1 finished earlier), 0 failed"), std::string::npos) << err;
}

TEST(BatchCli, HelpAndUsageErrors) {
  const auto help = dreamsense({"batch", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--jobs"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("batch collect DIR"), std::string::npos);
  const auto no_out = dreamsense({"batch", demo(1).string()});
  EXPECT_NE(no_out.exit_code, 0);
  EXPECT_NE((no_out.out + no_out.err).find("--out"), std::string::npos);
  TempDir t;
  const auto not_batch = dreamsense({"batch", "collect", t.path().string()});
  EXPECT_EQ(not_batch.exit_code, 1);
  EXPECT_NE(not_batch.err.find("batch.json"), std::string::npos) << not_batch.err;
}

}  // namespace
}  // namespace dreamsense::batch
