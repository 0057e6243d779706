#pragma once
// An Analyzer is a thin adapter: it pulls its inputs from a MultiFrame (and earlier results from
// the blackboard), calls a plain algorithm and writes typed results. What it needs and produces
// is declared up front (AnalyzerContract) and checked when the pipeline is built.

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace dreamsense {

struct AnalyzerContract {
  // Sensor streams the analyser consumes, by id. A missing required stream fails the build.
  std::vector<SensorId> required_inputs;
  std::vector<SensorId> optional_inputs;
  // Blackboard keys read from analysers that run before this one in the same tick.
  std::vector<std::string> reads;
  // Blackboard keys this analyser writes; two analysers may not write the same key.
  std::vector<std::string> writes;
  // Keys read as feedback from earlier ticks (e.g. face detection reads the last head pose to
  // select the most frontal camera). Any analyser may write them, or none: then they are absent.
  std::vector<std::string> reads_previous = {};
};

class Analyzer {
 public:
  virtual ~Analyzer() = default;
  virtual std::string_view name() const = 0;
  virtual AnalyzerContract contract() const = 0;
  // `prior` holds everything committed before this analyser ran in this tick.
  // "Nothing detected" is success with an absent write, not an error.
  virtual Status process(const MultiFrame& in, const BlackboardView& prior,
                         BlackboardWriter& out) = 0;
  // New session or lost state.
  virtual void reset() {}
};

}  // namespace dreamsense
