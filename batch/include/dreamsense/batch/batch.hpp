#pragma once
// `dreamsense batch`: many analyses, one `dreamsense analyze INPUT --out OUT/<name> -q [flags]`
// child process per input, resumable, summarised in OUT/batch.csv (docs/batch.md).
//
// Layout of the batch folder OUT:
//   batch.json        the plan: every input with its kind, output name, or why it is skipped /
//                     failed; the extra analyze flags (read by `batch collect`)
//   <name>/           the analysis of one input (analyze's outputs + batch_done.json when
//                     finished, see output_state.hpp)
//   <name>.log        the child's stdout+stderr, then one line "batch: ok|failed|interrupted ..."
//   batch.csv         one row per input (table.hpp), rebuilt from the folders' state
//   slurm/            --slurm: the job script, the list of inputs, the job ids
//
// Resume rule: a finished output is kept (unless force); anything else is removed and redone.

#include "dreamsense/batch/inputs.hpp"
#include "dreamsense/batch/output_state.hpp"
#include "dreamsense/batch/process_pool.hpp"
#include "dreamsense/batch/table.hpp"
#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace dreamsense::batch {

inline constexpr const char* kPlanFile = "batch.json";
inline constexpr const char* kTableFile = "batch.csv";
inline constexpr const char* kLockFile = "batch.lock";

struct BatchOptions {
  std::vector<std::string> inputs;        // sessions, videos, folders of them
  std::filesystem::path out_dir;          // the batch folder (created; must be new, empty or a
                                          // batch folder already)
  int jobs = 1;                           // analyses at a time
  bool force = false;                     // redo finished analyses too
  std::vector<std::string> analyze_args;  // extra flags for every analyze
  std::filesystem::path executable;       // the dreamsense binary to run
  InputOptions input_options;
  double kill_grace_s = 3.0;  // on interruption: SIGTERM, then SIGKILL after this long
  Status check() const;
};

struct BatchReport {
  std::vector<TableRow> rows;  // batch.csv, built from the folders' state
  size_t ok = 0, failed = 0, skipped = 0;
  size_t reused = 0;   // finished before this run and kept
  size_t redone = 0;   // outputs removed and analysed again (partial, or finished with force)
  size_t started = 0;  // analyses started by this run
  bool interrupted = false;
  std::filesystem::path table;  // batch.csv
  bool all_ok() const { return failed == 0 && !interrupted; }
};

struct BatchEvents {
  std::function<void(size_t done, size_t total)> progress;  // over the inputs to analyse
  std::function<void(const std::string&)> message;  // one human line per reuse, redo, result
};

// The argv of one analysis: `analyze INPUT --out OUT -q`, `--threads 1` unless analyze_args
// set --threads, then analyze_args.
std::vector<std::string> analyze_command(const std::filesystem::path& executable,
                                         const std::filesystem::path& input,
                                         const std::filesystem::path& out,
                                         const std::vector<std::string>& analyze_args);

// Runs the batch locally with a pool of options.jobs child processes. `stop` is polled (e.g.
// StopSignals::requested): when it turns true, nothing more starts, the running analyses are
// terminated and stay partial, and the report says interrupted. Errors: bad options, an --out
// that is a file or a non-empty folder that is not a batch folder, another batch running on it.
Result<BatchReport> run_batch(const BatchOptions& options, const BatchEvents& events = {},
                              const std::function<bool()>& stop = {});

// Rebuilds OUT/batch.csv from batch.json and the folders' state (no analysis runs).
Result<BatchReport> collect_batch(const std::filesystem::path& out_dir);

// ---- building blocks shared with --slurm (slurm.hpp) ----

// Checks the options and creates the batch folder, or checks that an existing one is a batch
// folder (has batch.json) or empty: partial outputs are only ever removed inside batch folders.
Status open_batch_folder(const BatchOptions& options);

// An exclusive lock (flock) on OUT/batch.lock, held while a batch runs or submits on OUT.
class FolderLock {
 public:
  FolderLock(FolderLock&& o) noexcept;
  FolderLock& operator=(FolderLock&&) = delete;
  ~FolderLock();

 private:
  friend Result<FolderLock> lock_batch_folder(const std::filesystem::path& out_dir);
  explicit FolderLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};
Result<FolderLock> lock_batch_folder(const std::filesystem::path& out_dir);

// open_batch_folder, then expands the inputs and writes batch.json.
Result<std::vector<PlannedInput>> plan_batch(const BatchOptions& options);

// What to do with one input's output folder before running: kept (finished and !force), or
// cleared for a run (partial or forced: removed). Returns the decision, or a failure reason
// (e.g. a file in the folder's place).
enum class Preparation { kKeep, kRun };
Result<Preparation> prepare_output(const std::filesystem::path& out_dir, const PlannedInput& in,
                                   const std::vector<std::string>& analyze_args, bool force,
                                   std::string* note = nullptr);

// Records how one analysis ended: the done record (success with summary.json) and the
// "batch: ..." line appended to its log. Returns true when it is finished.
bool record_outcome(const std::filesystem::path& out_dir, const PlannedInput& in,
                    const std::vector<std::string>& analyze_args, const ChildOutcome& outcome,
                    std::string* reason = nullptr);

// One analysis in the foreground (`batch task`, run by each Slurm array task): the input on line
// `index` (0-based) of OUT/slurm/inputs.txt. Returns true when the input is finished.
Result<bool> run_task(const std::filesystem::path& out_dir, size_t index,
                      const std::vector<std::string>& analyze_args,
                      const std::filesystem::path& executable,
                      const std::function<bool()>& stop = {});

}  // namespace dreamsense::batch
