#pragma once
// Runs one analyser alone, as the pipeline would (MediaPipe's CalculatorRunner): a test presets
// what earlier analysers would have written in the tick (the contract's reads), feeds timestamped
// frames and inspects what the analyser wrote. Writes to keys the contract does not declare, and
// reads of keys it does not declare that were preset, are errors: the test checks the contract
// too.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/multi_frame.hpp"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::testing {

class AnalyzerRunner {
 public:
  explicit AnalyzerRunner(std::unique_ptr<Analyzer> analyzer, BlackboardOptions blackboard = {});

  // What an earlier analyser wrote in the tick about to run (or in an earlier tick:
  // reads_previous). Committed before the next run().
  template <typename T>
  void preset(Key<T> key, T value, Timestamp stamp, float confidence = 1.f) {
    presets_.set(key, std::move(value), stamp, confidence);
  }
  template <typename T>
  void preset_absent(Key<T> key, Timestamp stamp) {
    presets_.set_absent(key, stamp);
  }

  // One tick: commits the presets, runs process() and commits its writes at `tick.stamp`.
  // Returns process()'s status, or kFailedPrecondition when it wrote an undeclared key.
  Status run(const MultiFrame& tick);
  // A tick at `stamp` holding these frames (audio frames become continuous chunks).
  Status run(Timestamp stamp, const std::vector<FramePtr>& frames);

  // The newest entry the analyser (or a preset) wrote for `key`.
  template <typename T>
  std::optional<Entry<T>> output(Key<T> key) const {
    return blackboard_.snapshot().get(key);
  }
  // Keys the analyser wrote in the last run (empty: it wrote nothing).
  const std::vector<std::string>& last_writes() const { return last_writes_; }
  BlackboardView view() const { return blackboard_.snapshot(); }
  Analyzer& analyzer() { return *analyzer_; }
  const AnalyzerContract& contract() const { return contract_; }

 private:
  std::unique_ptr<Analyzer> analyzer_;
  AnalyzerContract contract_;
  Blackboard blackboard_;
  BlackboardWriter presets_{"preset"};
  std::vector<std::string> last_writes_;
};

}  // namespace dreamsense::testing
