#pragma once
// Runs analysers over a Source: frames -> synchroniser -> analysers (in order, each seeing the
// commits of those before it) -> blackboard -> per-tick callback (primitives, outputs).
// Analysers of one tick that share no blackboard key may run at the same time
// (PipelineOptions::threads); the results are those of the one-after-the-other order.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/source.hpp"
#include "dreamsense/core/synchronizer.hpp"

#include <condition_variable>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace dreamsense {

struct PipelineOptions {
  SynchronizerOptions sync;
  BlackboardOptions blackboard;
  // Live policy only: pace the source by its stamps (replay in real time), so that a slow
  // pipeline drops frames as it would with real sensors.
  bool pace_source = true;
  // Threads that run one tick's analysers, the calling thread included. Two analysers run at the
  // same time only when neither reads a key the other writes (this tick's or, through
  // reads_previous, an earlier tick's), so every analyser sees exactly what it would see one
  // after the other and the outputs do not depend on this number (tested). 1: one after the
  // other on the calling thread. 0 (auto): 1 on machines with fewer than 4 cores, else the cores
  // less one (left to the session reader's decoding), at most kMaxAutoThreads. On the 2-core
  // reference machine 2 threads were not faster: both cores are already busy (docs/
  // architecture.md, "Parallel ticks").
  int threads = 0;
  static constexpr int kMaxAutoThreads = 4;
  static constexpr int kMaxThreads = 64;
  // What threads = 0 means on a machine with `cores` cores.
  static int auto_threads(unsigned cores);
  Status check() const;
};

struct AnalyzerStats {
  std::string name;
  uint64_t calls = 0;
  uint64_t errors = 0;             // process() returned an error or broke a check
  std::vector<double> latency_ms;  // one sample per call
  double latency_total_ms = 0;     // their sum
};

struct PipelineStats {
  uint64_t ticks = 0;
  uint64_t frames = 0;
  double wall_seconds = 0;
  double media_seconds = 0;             // span of session time processed
  int threads = 1;                      // that ran each tick's analysers (PipelineOptions)
  std::vector<double> tick_latency_ms;  // per tick: from MultiFrame ready to callback done
  std::vector<AnalyzerStats> analyzers;
  SyncStats sync;
};

using TickCallback = std::function<Status(const MultiFrame&, const BlackboardView&)>;
using ProgressCallback = std::function<void(Timestamp)>;

// Orders analysers by their contracts: a key's writer runs before the analysers that read it in
// the same tick; an analyser that reads a key from earlier ticks (reads_previous) runs before
// that key's writer, so it always sees the previous tick's value. Among analysers free to run,
// the earlier one in `analyzers` goes first (deterministic). A cycle is an error naming the
// analysers in it. Reads without a writer are left for Pipeline::build to report.
Result<std::vector<std::unique_ptr<Analyzer>>> order_by_contracts(
    std::vector<std::unique_ptr<Analyzer>> analyzers);

// The sensors behind each blackboard key the analysers write: the writer's required inputs, its
// optional inputs that the source has, and the sensors behind the keys it reads, transitively.
// `analyzers` must be in execution order. Sorted, without duplicates.
std::map<std::string, std::vector<SensorId>, std::less<>> key_sensors(
    const std::vector<std::unique_ptr<Analyzer>>& analyzers, const SourceInfo& source);

class Pipeline {
 public:
  // Checks the wiring: every required input is a sensor of the source, every key read is written
  // by an analyser earlier in the list, no key has two writers, names are unique.
  static Result<std::unique_ptr<Pipeline>> build(PipelineOptions options, SourceInfo source_info,
                                                 std::vector<std::unique_ptr<Analyzer>> analyzers);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Processes the whole source. Stops at the first source error (returned) or callback error.
  Status run(Source& source, const TickCallback& on_tick,
             const ProgressCallback& on_progress = nullptr);

  // Swaps running analysers for new ones of the same names and contracts (e.g. head pose with
  // the child's face model once a live self-calibration converged), from the next tick on: call
  // it between ticks, e.g. from the TickCallback. Each replacement starts fresh (its own state);
  // its stats continue the old one's. Errors (nothing replaced): an unknown name, a different
  // contract, a null analyser.
  Status replace_analyzers(std::vector<std::unique_ptr<Analyzer>> replacements);

  const PipelineStats& stats() const { return stats_; }
  const Blackboard& blackboard() const { return blackboard_; }
  const std::vector<std::unique_ptr<Analyzer>>& analyzers() const { return analyzers_; }
  // Threads that run a tick's analysers (PipelineOptions::threads resolved).
  int threads() const { return stats_.threads; }

 private:
  Pipeline(PipelineOptions options, SourceInfo info, std::vector<std::unique_ptr<Analyzer>> a);
  Status process_tick(const MultiFrame& frame, const TickCallback& on_tick);
  void run_analyzer(size_t i, const MultiFrame& frame);
  void run_analyzers_in_parallel(const MultiFrame& frame);
  void worker_loop();
  void run_one(size_t i, std::unique_lock<std::mutex>& lock);
  // Takes the ready analyser on the longest remaining path (by mean latency so far), or nullopt.
  std::optional<size_t> take_ready();
  Status run_settled(Source& source, const TickCallback& on_tick, const ProgressCallback& p);
  Status run_live(Source& source, const TickCallback& on_tick, const ProgressCallback& p);
  std::vector<StreamSpec> stream_specs() const;
  void finish_stats(const Synchronizer& sync, Timestamp first, Timestamp last);

  PipelineOptions options_;
  SourceInfo info_;
  std::vector<std::unique_ptr<Analyzer>> analyzers_;
  Blackboard blackboard_;
  PipelineStats stats_;

  // Parallel ticks (threads() > 1). dependencies_[i]: the earlier analysers that i waits for (a
  // key one writes and the other reads); unblocks_[i]: the later ones that wait for i.
  std::vector<size_t> dependencies_;
  std::vector<std::vector<size_t>> unblocks_;
  std::vector<std::thread> workers_;
  std::mutex tick_mutex_;
  std::condition_variable tick_cv_;
  const MultiFrame* tick_frame_ = nullptr;  // the tick being processed, or null between ticks
  std::vector<size_t> waiting_on_;          // per analyser: dependencies not yet done
  std::vector<size_t> ready_;
  std::vector<double> path_ms_;  // per analyser: its mean latency plus its longest dependent path
  size_t finished_ = 0, running_ = 0;
  std::exception_ptr tick_exception_;
  bool stopping_ = false;
};

}  // namespace dreamsense
