#include "dreamsense/testing/analyzer_runner.hpp"

#include <algorithm>

namespace dreamsense::testing {

AnalyzerRunner::AnalyzerRunner(std::unique_ptr<Analyzer> analyzer, BlackboardOptions blackboard)
    : analyzer_(std::move(analyzer)), blackboard_(blackboard) {
  DS_CHECK(analyzer_ != nullptr);
  contract_ = analyzer_->contract();
}

Status AnalyzerRunner::run(const MultiFrame& tick) {
  if (!presets_.empty()) {
    blackboard_.commit(presets_, tick.stamp);
    presets_ = BlackboardWriter("preset");
  }
  BlackboardWriter out{std::string(analyzer_->name())};
  Status s = analyzer_->process(tick, blackboard_.snapshot(), out);
  last_writes_ = out.keys();
  for (const auto& k : last_writes_)
    if (std::find(contract_.writes.begin(), contract_.writes.end(), k) == contract_.writes.end())
      return make_error(ErrorCode::kFailedPrecondition,
                        "analyser '{}' wrote '{}', which its contract does not declare",
                        analyzer_->name(), k);
  if (!s) return s;
  blackboard_.commit(out, tick.stamp);
  return ok_status();
}

Status AnalyzerRunner::run(Timestamp stamp, const std::vector<FramePtr>& frames) {
  MultiFrame mf;
  mf.stamp = stamp;
  for (const auto& f : frames) {
    if (f->kind() == SensorKind::kAudio)
      mf.chunks[f->sensor].push_back(f);
    else
      mf.frames[f->sensor] = f;
  }
  return run(mf);
}

}  // namespace dreamsense::testing
