#pragma once
// Runs analysers over a Source: frames -> synchroniser -> analysers (in order, each seeing the
// commits of those before it) -> blackboard -> per-tick callback (primitives, outputs).

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/source.hpp"
#include "dreamsense/core/synchronizer.hpp"

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense {

struct PipelineOptions {
  SynchronizerOptions sync;
  BlackboardOptions blackboard;
  // Live policy only: pace the source by its stamps (replay in real time), so that a slow
  // pipeline drops frames as it would with real sensors.
  bool pace_source = true;
  Status check() const;
};

struct AnalyzerStats {
  std::string name;
  uint64_t calls = 0;
  uint64_t errors = 0;             // process() returned an error or broke a check
  std::vector<double> latency_ms;  // one sample per call
};

struct PipelineStats {
  uint64_t ticks = 0;
  uint64_t frames = 0;
  double wall_seconds = 0;
  double media_seconds = 0;             // span of session time processed
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

  // Processes the whole source. Stops at the first source error (returned) or callback error.
  Status run(Source& source, const TickCallback& on_tick,
             const ProgressCallback& on_progress = nullptr);

  const PipelineStats& stats() const { return stats_; }
  const Blackboard& blackboard() const { return blackboard_; }
  const std::vector<std::unique_ptr<Analyzer>>& analyzers() const { return analyzers_; }

 private:
  Pipeline(PipelineOptions options, SourceInfo info, std::vector<std::unique_ptr<Analyzer>> a);
  Status process_tick(const MultiFrame& frame, const TickCallback& on_tick);
  Status run_settled(Source& source, const TickCallback& on_tick, const ProgressCallback& p);
  Status run_live(Source& source, const TickCallback& on_tick, const ProgressCallback& p);
  std::vector<StreamSpec> stream_specs() const;
  void finish_stats(const Synchronizer& sync, Timestamp first, Timestamp last);

  PipelineOptions options_;
  SourceInfo info_;
  std::vector<std::unique_ptr<Analyzer>> analyzers_;
  Blackboard blackboard_;
  PipelineStats stats_;
};

}  // namespace dreamsense
