// `dreamsense batch INPUTS... --out DIR [--jobs N] [--slurm] [--force] [-- analyze flags]`,
// `dreamsense batch collect DIR` and `dreamsense batch task DIR INDEX [-- analyze flags]` (run by
// each Slurm array task). Everything is in batch/ (docs/batch.md); this only parses flags.

#include "dreamsense/batch/batch.hpp"
#include "dreamsense/batch/slurm.hpp"

#include <cstdio>
#include <optional>
#include <thread>
#include <unistd.h>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {

struct BatchFlags {
  std::vector<std::string> inputs;
  std::string out;
  int jobs = 0;
  bool slurm = false, force = false, quiet = false;
  std::vector<std::string> slurm_options;
  std::string collect_dir;
  std::string task_dir;
  size_t task_index = 0;
};

std::filesystem::path this_executable() {
  std::error_code ec;
  auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : p;
}

int default_jobs() { return std::max(1u, std::thread::hardware_concurrency()); }

void print_report(const batch::BatchReport& r, bool quiet, double seconds) {
  for (const auto& row : r.rows)
    if (row.status == "failed")
      std::fprintf(stderr, "failed: %s: %s\n", row.input.c_str(), row.reason.c_str());
  if (r.interrupted)
    std::fprintf(stderr,
                 "batch: interrupted; unfinished analyses are left partial and redone by the "
                 "same command\n");
  if (quiet) return;
  std::string kept = r.reused > 0 ? fmt::format(" ({} finished earlier)", r.reused) : "";
  std::fprintf(stderr, "batch: %zu ok%s, %zu failed, %zu skipped", r.ok, kept.c_str(), r.failed,
               r.skipped);
  if (seconds > 0) std::fprintf(stderr, " in %.1f s", seconds);
  std::fprintf(stderr, "; table: %s\n", r.table.string().c_str());
}

int run_local(const batch::BatchOptions& o, bool quiet) {
  batch::StopSignals signals;
  ProgressBar bar("batch", quiet);
  const bool lines = !quiet && ::isatty(STDERR_FILENO) != 1;  // a log, not a terminal
  batch::BatchEvents events;
  events.progress = [&bar](size_t done, size_t total) {
    bar.update(total == 0 ? 1.0 : static_cast<double>(done) / static_cast<double>(total));
  };
  if (lines) events.message = [](const std::string& m) { std::fprintf(stderr, "%s\n", m.c_str()); };
  const auto start = std::chrono::steady_clock::now();
  auto r = batch::run_batch(o, events, [&signals] { return signals.requested(); });
  bar.finish();
  if (!r) return fail(r.error());
  print_report(*r, quiet,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return r->all_ok() ? kExitOk : kExitFailure;
}

int run_slurm(const batch::BatchOptions& o, int max_running,
              const std::vector<std::string>& directives, bool quiet) {
  batch::SlurmOptions so;
  so.max_running = max_running;
  so.directives = directives;
  auto sub = batch::submit_slurm(o, so);
  if (!sub) return fail(sub.error());
  if (sub->tasks == 0) {
    std::fprintf(stderr, "batch: nothing left to analyse (%zu finished); batch.csv in %s\n",
                 sub->already_finished, o.out_dir.string().c_str());
    return kExitOk;
  }
  // The job id goes to stdout (for scripts); the rest is for people.
  std::printf("%s\n", sub->job_id.c_str());
  if (!quiet) {
    std::fprintf(stderr, "submitted Slurm job array %s: %zu analyses%s (script %s)\n",
                 sub->job_id.c_str(), sub->tasks,
                 sub->already_finished > 0
                     ? fmt::format(", {} finished earlier", sub->already_finished).c_str()
                     : "",
                 sub->script.string().c_str());
    std::fprintf(stderr,
                 "batch.csv is written by job %s when the array has ended; to check before:\n"
                 "  squeue -j %s\n  %s batch collect %s\n",
                 sub->collect_job_id.c_str(), sub->job_id.c_str(), o.executable.string().c_str(),
                 o.out_dir.string().c_str());
  }
  return kExitOk;
}

int run_collect(const std::string& dir, bool quiet) {
  auto r = batch::collect_batch(dir);
  if (!r) return fail(r.error());
  print_report(*r, quiet, 0);
  return r->failed == 0 ? kExitOk : kExitFailure;
}

int run_task(const std::string& dir, size_t index, const std::vector<std::string>& analyze_args) {
  batch::StopSignals signals;
  auto r = batch::run_task(dir, index, analyze_args, this_executable(),
                           [&signals] { return signals.requested(); });
  if (!r) return fail(r.error());
  return kExitOk;
}

// The arguments after `batch`, parsed here rather than by CLI11's tree so that `--` can separate
// the analyze flags (CLI11 would hand them to the input list).
int parse_and_run(std::vector<std::string> args, const GlobalFlags& g) {
  std::vector<std::string> analyze_args;
  if (auto dd = std::find(args.begin(), args.end(), "--"); dd != args.end()) {
    analyze_args.assign(dd + 1, args.end());
    args.erase(dd, args.end());
  }
  BatchFlags f;
  const auto parse = [&args](CLI::App& cli) -> std::optional<int> {
    try {
      std::vector<std::string> reversed(args.rbegin(), args.rend());
      cli.parse(reversed);
    } catch (const CLI::ParseError& e) {
      return cli.exit(e);
    }
    return std::nullopt;
  };
  const std::string mode = args.empty() ? "" : args.front();
  if (mode == "collect" || mode == "task") {
    args.erase(args.begin());
    CLI::App cli{mode == "collect" ? "Rewrite DIR/batch.csv from the state of DIR's outputs "
                                     "(what a --slurm batch runs when its array has ended)"
                                   : "Analyse the input on line INDEX (0-based) of "
                                     "DIR/slurm/inputs.txt into DIR, as one task of the "
                                     "Slurm job array of `batch --slurm` does; flags after -- "
                                     "go to analyze",
                 "dreamsense batch " + mode};
    cli.add_flag("-q,--quiet", f.quiet, "Only failures on stderr");
    cli.add_option("dir", mode == "collect" ? f.collect_dir : f.task_dir,
                   "The batch folder (--out of the batch)")
        ->required();
    if (mode == "task")
      cli.add_option("index", f.task_index, "Line of inputs.txt, 0-based")->required();
    if (auto code = parse(cli)) return *code;
    if (mode == "collect") return run_collect(f.collect_dir, g.quiet || f.quiet);
    return run_task(f.task_dir, f.task_index, analyze_args);
  }
  CLI::App cli{
      "Analyse many recordings (session folders, videos, folders of them), one `dreamsense "
      "analyze INPUT --out DIR/<name> -q` process per input, resumable: finished outputs are "
      "kept, partial ones redone. Writes DIR/<name>/ and DIR/<name>.log per input and "
      "DIR/batch.csv (docs/batch.md). Flags after -- go to every analyze. Exit code 1 when an "
      "input failed.\n"
      "  dreamsense batch INPUTS... --out DIR [--jobs N] [--force] [--slurm] [-- FLAGS]\n"
      "  dreamsense batch collect DIR      rewrites DIR/batch.csv from the outputs\n"
      "  dreamsense batch task DIR INDEX   one input of DIR/slurm/inputs.txt (--slurm's task)",
      "dreamsense batch"};
  cli.add_flag("-q,--quiet", f.quiet, "No progress bar; only failures on stderr");
  cli.add_option("inputs", f.inputs,
                 "Session folders (with session.yaml), video files, or folders holding them")
      ->required();
  cli.add_option("--out", f.out, "The batch folder (new, empty, or one batch made before)")
      ->required();
  cli.add_option("--jobs", f.jobs,
                 "Analyses at a time (default: the number of cores); with --slurm: array "
                 "tasks running at a time (default: no limit)")
      ->check(CLI::Range(1, 1024));
  cli.add_flag("--force", f.force, "Redo finished analyses too");
  cli.add_flag("--slurm", f.slurm,
               "Submit a Slurm job array (sbatch --array) instead of running here; a collect "
               "job writes batch.csv when it has ended");
  cli.add_option("--slurm-option", f.slurm_options,
                 "An extra sbatch option for every job, e.g. --slurm-option=--partition=short "
                 "(repeatable)");
  if (auto code = parse(cli)) return *code;
  const bool quiet = g.quiet || f.quiet;
  batch::BatchOptions o;
  o.inputs = f.inputs;
  o.out_dir = f.out;
  o.jobs = f.jobs > 0 ? f.jobs : default_jobs();
  o.force = f.force;
  o.analyze_args = analyze_args;
  o.executable = this_executable();
  if (f.slurm) return run_slurm(o, f.jobs, f.slurm_options, quiet);
  if (!f.slurm_options.empty()) return fail("batch: --slurm-option needs --slurm");
  return run_local(o, quiet);
}

}  // namespace

void add_batch(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "batch",
      "Many analyses (sessions, videos, folders of them), resumable, with a batch.csv summary; "
      "--slurm submits a Slurm job array; `batch collect DIR` rewrites batch.csv "
      "(dreamsense batch --help)");
  // Everything after the verb reaches parse_and_run untouched (see there).
  cmd->fallthrough(false);
  cmd->allow_extras();
  cmd->prefix_command();
  cmd->set_help_flag();
  cmd->callback([cmd, &g, &exit_code] { exit_code = parse_and_run(cmd->remaining(), g); });
}

}  // namespace dreamsense::app
