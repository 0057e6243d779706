#include "dreamsense/batch/process_pool.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>

#include "test_util.hpp"

namespace dreamsense::batch {
namespace {
namespace fs = std::filesystem;
using test::read_text;
using test::TempDir;

ChildCommand sh(const std::string& script, const fs::path& log) {
  return {{"/bin/sh", "-c", script}, log};
}

TEST(FailureReason, LastErrorLineWins) {
  EXPECT_EQ(failure_reason("[info] starting\nerror: first\nwarning\nerror: /s/session.yaml: "
                           "line 3: bad key\n[info] bye\n",
                           1, 0),
            "/s/session.yaml: line 3: bad key");
  EXPECT_EQ(failure_reason("[error] decoder broke\nsomething else\n", 1, 0),
            "[error] decoder broke");
  EXPECT_EQ(failure_reason("terminate called after throwing an instance of 'x'\n", 0, SIGABRT)
                .rfind("killed by signal SIGABRT", 0),
            0u);
}

TEST(FailureReason, FallsBackToLastLineThenExitCode) {
  EXPECT_EQ(failure_reason("one\ntwo\n\n", 2, 0), "two");
  EXPECT_EQ(failure_reason("The following argument was not expected: --bogus\nRun with --help "
                           "for more information.\n",
                           106, 0),
            "The following argument was not expected: --bogus");
  EXPECT_EQ(failure_reason("", 3, 0), "exit code 3");
  EXPECT_EQ(failure_reason("", -1, SIGSEGV).rfind("killed by signal SIGSEGV", 0), 0u);
  EXPECT_EQ(failure_reason("progress 10%\rprogress 50%\rerror: late\n", 1, 0), "late");
}

TEST(ProcessPool, OutcomesAndLogsOfEachChild) {
  TempDir t;
  std::vector<ChildCommand> cmds = {
      sh("echo out; echo 'some noise' >&2; exit 0", t / "ok.log"),
      sh("echo 'error: /x/session.yaml: malformed' >&2; exit 1", t / "fail.log"),
      sh("echo 'about to crash' >&2; kill -SEGV $$", t / "crash.log"),
      {{(t / "no-such-program").string()}, t / "exec.log"},
  };
  std::vector<ChildOutcome> got(cmds.size());
  std::vector<int> finished(cmds.size(), 0);
  PoolOptions o;
  o.workers = 2;
  run_pool(cmds, o, nullptr, [&](size_t i, const ChildOutcome& c) {
    got[i] = c;
    ++finished[i];
  });
  for (int n : finished) EXPECT_EQ(n, 1);
  EXPECT_TRUE(got[0].ok);
  EXPECT_EQ(got[0].exit_code, 0);
  EXPECT_EQ(read_text(t / "ok.log"), "out\nsome noise\n");
  EXPECT_FALSE(got[1].ok);
  EXPECT_EQ(got[1].exit_code, 1);
  EXPECT_EQ(got[1].reason, "/x/session.yaml: malformed");
  EXPECT_FALSE(got[2].ok);
  EXPECT_EQ(got[2].term_signal, SIGSEGV);
  EXPECT_NE(got[2].reason.find("SIGSEGV"), std::string::npos) << got[2].reason;
  EXPECT_NE(got[2].reason.find("about to crash"), std::string::npos) << got[2].reason;
  EXPECT_FALSE(got[3].ok);
  EXPECT_EQ(got[3].exit_code, 127);
  EXPECT_NE(got[3].reason.find("cannot execute"), std::string::npos) << got[3].reason;
}

TEST(ProcessPool, NeverMoreThanWorkersAtATimeAndUsesThemAll) {
  TempDir t;
  std::vector<ChildCommand> cmds;
  for (int i = 0; i < 6; ++i) cmds.push_back(sh("sleep 0.2", t / ("j" + std::to_string(i))));
  int running = 0, most = 0;
  std::vector<size_t> order;
  PoolOptions o;
  o.workers = 2;
  run_pool(
      cmds, o,
      [&](size_t i) {
        order.push_back(i);
        most = std::max(most, ++running);
      },
      [&](size_t, const ChildOutcome& c) {
        EXPECT_TRUE(c.ok);
        --running;
      });
  EXPECT_EQ(most, 2);
  EXPECT_EQ(order, (std::vector<size_t>{0, 1, 2, 3, 4, 5}));
}

TEST(ProcessPool, StopTerminatesRunningAndStartsNoMore) {
  TempDir t;
  std::vector<ChildCommand> cmds;
  for (int i = 0; i < 4; ++i) cmds.push_back(sh("sleep 30", t / ("j" + std::to_string(i))));
  bool stop = false;
  std::vector<ChildOutcome> got(cmds.size());
  PoolOptions o;
  o.workers = 2;
  o.stop_requested = [&] { return stop; };
  const auto start = std::chrono::steady_clock::now();
  run_pool(
      cmds, o, [&](size_t i) { stop = stop || i == 1; },
      [&](size_t i, const ChildOutcome& c) { got[i] = c; });
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(s, 20.0);  // not the children's 30 s: they were terminated
  for (int i : {0, 1}) {
    EXPECT_TRUE(got[i].started);
    EXPECT_TRUE(got[i].interrupted);
    EXPECT_EQ(got[i].term_signal, SIGTERM);
    EXPECT_EQ(got[i].reason, "interrupted");
  }
  for (int i : {2, 3}) EXPECT_FALSE(got[i].started);
}

TEST(ProcessPool, StubbornChildIsKilledAfterTheGracePeriod) {
  TempDir t;
  // Ignores SIGTERM; the marker file says it is running with its trap in place.
  const fs::path ready = t / "ready";
  ChildOutcome got;
  PoolOptions o;
  o.kill_grace_s = 0.3;
  o.stop_requested = [&] { return fs::exists(ready); };
  run_pool(
      {sh("trap '' TERM; touch " + ready.string() + "; while :; do sleep 0.05; done", t / "log")},
      o, nullptr, [&](size_t, const ChildOutcome& c) { got = c; });
  EXPECT_TRUE(got.interrupted);
  EXPECT_EQ(got.term_signal, SIGKILL);
}

TEST(RunCaptured, StdoutAndStderrApart) {
  auto r = run_captured({"/bin/sh", "-c", "echo 42; echo oops >&2; exit 5"});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->out, "42\n");
  EXPECT_EQ(r->err, "oops\n");
  EXPECT_EQ(r->exit_code, 5);
  auto missing = run_captured({"dreamsense-no-such-program-xyz"});
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("dreamsense-no-such-program-xyz"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::batch
