// run_batch, collect_batch, run_task and the Slurm submission against a stand-in for the
// dreamsense executable (a shell script with analyze's contract: outputs into --out,
// summary.json last, "error: ..." and a non-zero exit on bad input).

#include "dreamsense/batch/batch.hpp"

#include "dreamsense/batch/slurm.hpp"

#include <gtest/gtest.h>

#include <set>
#include <sys/stat.h>

#include "test_util.hpp"

namespace dreamsense::batch {
namespace {
namespace fs = std::filesystem;
using test::make_session;
using test::read_text;
using test::TempDir;
using test::write_text;

// The stand-in: a session whose session.yaml contains "bad" fails; one with a file "slow" takes
// 30 s; each run appends its input to runs.txt.
fs::path write_fake_dreamsense(const TempDir& t) {
  const fs::path exe = t / "fake-dreamsense";
  write_text(
      exe,
      "#!/bin/sh\n"
      "[ \"$1\" = analyze ] || { echo \"error: unexpected verb $1\" >&2; exit 2; }\n"
      "in=\"$2\"; out=\"$4\"; shift 5\n"
      "echo \"$in\" >> '" +
          (t / "runs.txt").string() +
          "'\n"
          "mkdir -p \"$out\" && echo partial > \"$out/primitives.jsonl\"\n"
          "echo '[info] analysing' >&2\n"
          "if grep -q bad \"$in/session.yaml\"; then\n"
          "  echo \"error: $in/session.yaml: line 1: malformed\" >&2; exit 1; fi\n"
          "[ -f \"$in/slow\" ] && sleep 30\n"
          "printf '{\"ticks\": %s, \"session\": \"%s\", \"extra\": \"%s\"}\\n' "
          "\"$(cat \"$in/ticks\")\" \"$(basename \"$in\")\" \"$*\" > \"$out/summary.json\"\n");
  ::chmod(exe.c_str(), 0755);
  return exe;
}

std::vector<std::string> runs(const TempDir& t) {
  std::vector<std::string> v;
  std::istringstream in(read_text(t / "runs.txt"));
  for (std::string line; std::getline(in, line);) v.push_back(line);
  return v;
}

void make_demo(const fs::path& dir, int ticks, bool bad = false) {
  write_text(dir / "session.yaml", bad ? "bad: [\n" : "version: 1\n");
  write_text(dir / "ticks", std::to_string(ticks));
}

struct Fixture {
  TempDir t;
  fs::path exe = write_fake_dreamsense(t);
  BatchOptions options() const {
    BatchOptions o;
    o.out_dir = t / "out";
    o.jobs = 2;
    o.executable = exe;
    o.kill_grace_s = 0.5;
    return o;
  }
  const TableRow& row(const BatchReport& r, const std::string& input_end) const {
    for (const auto& row : r.rows)
      if (row.input.size() >= input_end.size() &&
          row.input.compare(row.input.size() - input_end.size(), input_end.size(), input_end) == 0)
        return row;
    throw std::runtime_error("no row for " + input_end);
  }
};

TEST(Batch, AnalysesRunOneThreadEachUnlessTheFlagsSayOtherwise) {
  using Argv = std::vector<std::string>;
  EXPECT_EQ(
      analyze_command("ds", "in", "out", {"--disable", "speech"}),
      (Argv{"ds", "analyze", "in", "--out", "out", "-q", "--threads", "1", "--disable", "speech"}));
  EXPECT_EQ(analyze_command("ds", "in", "out", {"--threads", "3"}),
            (Argv{"ds", "analyze", "in", "--out", "out", "-q", "--threads", "3"}));
  EXPECT_EQ(analyze_command("ds", "in", "out", {"--threads=2"}),
            (Argv{"ds", "analyze", "in", "--out", "out", "-q", "--threads=2"}));
}

TEST(Batch, RunsEveryInputOneFailureDoesNotStopTheOthers) {
  Fixture f;
  make_demo(f.t / "in" / "s1", 11);
  make_demo(f.t / "in" / "s2", 22);
  make_demo(f.t / "in" / "broken", 33, /*bad=*/true);
  make_demo(f.t / "in" / "s3", 44);
  write_text(f.t / "in" / "notes.txt", "x");
  auto o = f.options();
  o.inputs = {(f.t / "in").string()};
  std::vector<std::string> messages;
  size_t last_done = 0, last_total = 0;
  BatchEvents ev;
  ev.message = [&](const std::string& m) { messages.push_back(m); };
  ev.progress = [&](size_t d, size_t n) {
    EXPECT_GE(d, last_done);
    last_done = d;
    last_total = n;
  };
  auto r = run_batch(o, ev);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->ok, 3u);
  EXPECT_EQ(r->failed, 1u);
  EXPECT_EQ(r->skipped, 1u);
  EXPECT_FALSE(r->all_ok());
  EXPECT_EQ(r->started, 4u);
  EXPECT_EQ(last_done, 4u);
  EXPECT_EQ(last_total, 4u);
  const auto& broken = f.row(*r, "/broken");
  EXPECT_EQ(broken.status, "failed");
  EXPECT_EQ(broken.reason,
            (f.t / "in" / "broken" / "session.yaml").string() + ": line 1: malformed");
  EXPECT_EQ(f.row(*r, "/notes.txt").status, "skipped");
  const auto& s2 = f.row(*r, "/s2");
  EXPECT_EQ(s2.status, "ok");
  EXPECT_EQ(s2.figures.at("ticks"), "22");
  ASSERT_TRUE(s2.seconds.has_value());
  // Outputs: folder with the done record, the log with the child's stderr and the outcome.
  EXPECT_TRUE(fs::exists(o.out_dir / s2.output / kDoneFile));
  const std::string log = read_text(o.out_dir / (s2.output + ".log"));
  EXPECT_NE(log.find("[info] analysing"), std::string::npos) << log;
  EXPECT_NE(log.find("batch: ok after"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(o.out_dir / broken.output / kDoneFile));
  // The table on disk is the report's.
  EXPECT_EQ(read_text(o.out_dir / kTableFile), format_table(r->rows));
  EXPECT_NE(read_text(o.out_dir / kTableFile).find("input,output,status,reason,seconds,"),
            std::string::npos);
  bool told = false;
  for (const auto& m : messages) told = told || m.find("failed") == 0;
  EXPECT_TRUE(told);
}

TEST(Batch, RerunKeepsFinishedAndRedoesPartial) {
  Fixture f;
  for (int i = 1; i <= 3; ++i) make_demo(f.t / ("s" + std::to_string(i)), i);
  auto o = f.options();
  o.inputs = {(f.t / "s1").string(), (f.t / "s2").string(), (f.t / "s3").string()};
  auto first = run_batch(o);
  ASSERT_TRUE(first && first->all_ok());
  ASSERT_EQ(runs(f.t).size(), 3u);
  // s2: interrupted before its done record; s3: its folder half written.
  fs::remove(o.out_dir / f.row(*first, "/s2").output / kDoneFile);
  fs::remove(o.out_dir / f.row(*first, "/s3").output / kSummaryFile);
  const auto s1_done = fs::last_write_time(o.out_dir / f.row(*first, "/s1").output / kDoneFile);
  auto second = run_batch(o);
  ASSERT_TRUE(second) << second.error().message;
  EXPECT_TRUE(second->all_ok());
  EXPECT_EQ(second->reused, 1u);
  EXPECT_EQ(second->redone, 2u);
  EXPECT_EQ(second->started, 2u);
  const auto r = runs(f.t);
  ASSERT_EQ(r.size(), 5u);
  // The two redone (in either order: two run at a time).
  EXPECT_EQ(std::set<std::string>(r.begin() + 3, r.end()),
            (std::set<std::string>{fs::canonical(f.t / "s2").string(),
                                   fs::canonical(f.t / "s3").string()}));
  EXPECT_EQ(fs::last_write_time(o.out_dir / f.row(*second, "/s1").output / kDoneFile), s1_done);
  // --force redoes everything; other analyze flags too.
  o.force = true;
  ASSERT_TRUE(run_batch(o));
  EXPECT_EQ(runs(f.t).size(), 8u);
  o.force = false;
  o.analyze_args = {"--overlay"};
  auto flagged = run_batch(o);
  ASSERT_TRUE(flagged);
  EXPECT_EQ(runs(f.t).size(), 11u);
  // The analysis gets one thread (the batch's jobs are its parallelism), then the flags.
  EXPECT_EQ(f.row(*flagged, "/s1").figures.at("extra"), "--threads 1 --overlay");
}

TEST(Batch, CollectRebuildsTheSameTable) {
  Fixture f;
  make_demo(f.t / "a", 5);
  make_demo(f.t / "b", 6, /*bad=*/true);
  auto o = f.options();
  o.inputs = {(f.t / "a").string(), (f.t / "b").string(), (f.t / "nope").string()};
  auto r = run_batch(o);
  ASSERT_TRUE(r);
  const std::string table = read_text(o.out_dir / kTableFile);
  fs::remove(o.out_dir / kTableFile);
  auto c = collect_batch(o.out_dir);
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(read_text(o.out_dir / kTableFile), table);
  EXPECT_EQ(c->ok, 1u);
  EXPECT_EQ(c->failed, 2u);
  EXPECT_NE(f.row(*c, "/nope").reason.find("no such file"), std::string::npos);
  EXPECT_FALSE(collect_batch(f.t / "a"));  // not a batch folder
}

TEST(Batch, BadOutputFolders) {
  Fixture f;
  make_demo(f.t / "a", 5);
  make_demo(f.t / "b", 6);
  auto o = f.options();
  o.inputs = {(f.t / "a").string(), (f.t / "b").string()};
  // --out is a file.
  write_text(f.t / "file", "x");
  o.out_dir = f.t / "file";
  auto r = run_batch(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("not a folder"), std::string::npos) << r.error().message;
  // --out is someone's folder: never touched.
  write_text(f.t / "mine" / "thesis.tex", "x");
  o.out_dir = f.t / "mine";
  r = run_batch(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("not a batch folder"), std::string::npos);
  // An empty folder is fine; a file where one input's output folder goes fails that input only.
  fs::create_directories(f.t / "empty");
  o.out_dir = f.t / "empty";
  o.inputs = {(f.t / "b").string()};
  ASSERT_TRUE(run_batch(o));
  o.inputs = {(f.t / "a").string(), (f.t / "b").string()};
  write_text(o.out_dir / output_name(fs::canonical(f.t / "a")), "in the way");
  r = run_batch(o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->ok, 1u);
  EXPECT_EQ(r->failed, 1u);
  EXPECT_NE(f.row(*r, "/a").reason.find("not a folder"), std::string::npos)
      << f.row(*r, "/a").reason;
  EXPECT_EQ(read_text(o.out_dir / output_name(fs::canonical(f.t / "a"))), "in the way");
}

TEST(Batch, InterruptionLeavesPartialOutputsThatTheNextRunRedoes) {
  Fixture f;
  make_demo(f.t / "quick", 1);
  make_demo(f.t / "slow", 2);
  write_text(f.t / "slow" / "slow", "");
  make_demo(f.t / "later", 3);
  auto o = f.options();
  o.jobs = 1;
  o.inputs = {(f.t / "quick").string(), (f.t / "slow").string(), (f.t / "later").string()};
  // Stop as soon as the slow one has started writing.
  const fs::path slow_out = o.out_dir / output_name(fs::canonical(f.t / "slow"));
  auto r = run_batch(o, {}, [&] { return fs::exists(slow_out / "primitives.jsonl"); });
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_TRUE(r->interrupted);
  EXPECT_FALSE(r->all_ok());
  EXPECT_EQ(f.row(*r, "/quick").status, "ok");
  EXPECT_NE(f.row(*r, "/slow").reason.find("interrupted"), std::string::npos);
  EXPECT_EQ(f.row(*r, "/later").reason, "not run");
  EXPECT_EQ(check_output(slow_out, fs::canonical(f.t / "slow").string(), {}).state,
            OutputState::kPartial);
  fs::remove(f.t / "slow" / "slow");
  auto again = run_batch(o);
  ASSERT_TRUE(again);
  EXPECT_TRUE(again->all_ok());
  EXPECT_EQ(again->reused, 1u);
  EXPECT_EQ(again->redone, 1u);
  EXPECT_EQ(again->started, 2u);
}

TEST(Batch, OneBatchAtATimePerFolder) {
  Fixture f;
  make_demo(f.t / "a", 1);
  auto o = f.options();
  o.inputs = {(f.t / "a").string()};
  fs::create_directories(o.out_dir);
  auto held = lock_batch_folder(o.out_dir);
  ASSERT_TRUE(held);
  auto r = run_batch(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("another dreamsense batch"), std::string::npos);
}

TEST(Batch, OptionsCheck) {
  BatchOptions o;
  EXPECT_FALSE(o.check());
  o.inputs = {"x"};
  o.out_dir = "y";
  o.executable = "/bin/true";
  EXPECT_TRUE(o.check());
  o.jobs = 0;
  EXPECT_FALSE(o.check());
  o.jobs = 1;
  o.analyze_args = {"--overlay", "--out=x"};
  EXPECT_FALSE(o.check());
}

TEST(Slurm, ScriptRunsOneListedInputPerArrayTask) {
  BatchOptions o;
  o.out_dir = "/data/out";
  o.executable = "/opt/ds/dreamsense";
  o.analyze_args = {"--mutual-gaze", "camera-plane", "it's"};
  SlurmOptions s;
  s.max_running = 2;
  s.directives = {"--partition=short", "--time=01:00:00"};
  const std::string script = slurm_script(o, s, 5);
  EXPECT_EQ(script.rfind("#!/bin/bash\n", 0), 0u);
  EXPECT_NE(script.find("#SBATCH --array=0-4%2\n"), std::string::npos) << script;
  EXPECT_NE(script.find("#SBATCH --partition=short\n"), std::string::npos);
  EXPECT_NE(script.find("#SBATCH --output=/data/out/slurm/task-%A_%a.out\n"), std::string::npos);
  EXPECT_NE(script.find("exec '/opt/ds/dreamsense' -q batch task '/data/out' "
                        "\"${SLURM_ARRAY_TASK_ID:?"),
            std::string::npos)
      << script;
  EXPECT_NE(script.find(" -- '--mutual-gaze' 'camera-plane' 'it'\\''s'\n"), std::string::npos)
      << script;
  s.max_running = 0;
  EXPECT_NE(slurm_script(o, s, 3).find("#SBATCH --array=0-2\n"), std::string::npos);
  s.directives = {"partition=x"};
  EXPECT_FALSE(s.check());
}

TEST(Slurm, SubmitsTheUnfinishedInputsAndACollectJob) {
  Fixture f;
  make_demo(f.t / "a", 1);
  make_demo(f.t / "b", 2);
  make_demo(f.t / "c", 3);
  auto o = f.options();
  o.inputs = {(f.t / "a").string()};
  ASSERT_TRUE(run_batch(o));  // a is finished before
  // A stand-in sbatch: records its arguments, prints job ids 100, 101, ...
  const fs::path sbatch = f.t / "fake-sbatch";
  write_text(sbatch, "#!/bin/sh\necho \"$*\" >> '" + (f.t / "sbatch.txt").string() +
                         "'\nn=$(wc -l < '" + (f.t / "sbatch.txt").string() +
                         "')\necho \"$((99 + n));cluster\"\n");
  ::chmod(sbatch.c_str(), 0755);
  o.inputs = {(f.t / "a").string(), (f.t / "b").string(), (f.t / "c").string()};
  SlurmOptions s;
  s.sbatch = sbatch.string();
  auto sub = submit_slurm(o, s);
  ASSERT_TRUE(sub) << sub.error().message;
  EXPECT_EQ(sub->tasks, 2u);
  EXPECT_EQ(sub->already_finished, 1u);
  EXPECT_EQ(sub->job_id, "100");
  EXPECT_EQ(sub->collect_job_id, "101");
  EXPECT_EQ(read_text(sub->list),
            fs::canonical(f.t / "b").string() + "\n" + fs::canonical(f.t / "c").string() + "\n");
  const std::string calls = read_text(f.t / "sbatch.txt");
  EXPECT_NE(calls.find("--parsable " + sub->script.string() + "\n"), std::string::npos) << calls;
  EXPECT_NE(calls.find("--dependency=afterany:100"), std::string::npos) << calls;
  EXPECT_NE(calls.find("batch collect"), std::string::npos) << calls;
  EXPECT_TRUE(fs::exists(o.out_dir / "slurm" / "submission.json"));

  // What each array task then does.
  auto t1 = run_task(o.out_dir, 1, {}, f.exe);
  ASSERT_TRUE(t1) << t1.error().message;
  EXPECT_TRUE(*t1);
  auto missing = run_task(o.out_dir, 5, {}, f.exe);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("line 5"), std::string::npos);
  auto c = collect_batch(o.out_dir);
  ASSERT_TRUE(c);
  EXPECT_EQ(f.row(*c, "/a").status, "ok");
  EXPECT_EQ(f.row(*c, "/b").status, "failed");  // task 0 has not run
  EXPECT_EQ(f.row(*c, "/b").reason, "not run");
  EXPECT_EQ(f.row(*c, "/c").status, "ok");
  EXPECT_EQ(f.row(*c, "/c").figures.at("ticks"), "3");

  // Submitting sbatch fails: one clear error.
  s.sbatch = (f.t / "no-sbatch").string();
  o.force = true;
  auto bad = submit_slurm(o, s);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("no-sbatch"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace dreamsense::batch
