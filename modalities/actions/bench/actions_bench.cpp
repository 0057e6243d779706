// ms per window of the action classifiers (target <= 1 ms on one core): normalisation +
// descriptor + SVM for a 1 s window at 30 Hz, and the custom-gesture matcher.
// Run: build/bench/actions_bench

#include "dreamsense/actions/action_model.hpp"
#include "dreamsense/actions/gesture_model.hpp"

#include <benchmark/benchmark.h>

#include "../test/synthetic_body.hpp"

namespace dreamsense::actions {
namespace {

using test::BodyParams;
using test::Motion;

std::vector<LabelledSequence> training() {
  std::vector<LabelledSequence> ex;
  for (int s = 0; s < 10; ++s)
    for (auto [motion, label] :
         {std::pair{Motion::kStill, "none"}, std::pair{Motion::kWaveRight, "wave"},
          std::pair{Motion::kArmsUp, "arms_up"}, std::pair{Motion::kPunchRight, "punch"},
          std::pair{Motion::kWaveLeft, "wave_left"}, std::pair{Motion::kCircleRight, "circle"}}) {
      BodyParams p;
      p.seed = 10 + static_cast<uint64_t>(s);
      p.scale = 0.6 + 0.05 * s;
      p.speed = 0.8 + 0.05 * s;
      p.noise_m = 0.01;
      ex.push_back({label, "s" + std::to_string(s), "", test::sequence(motion, 0.3 * s, 1.0, p)});
    }
  return ex;
}

void classify(benchmark::State& state, FeatureMethod method, ClassifierKind kind) {
  ActionModelOptions o;
  o.features.method = method;
  o.classifier.kind = kind;
  o.classifier.reject_folds = 0;
  auto m = ActionModel::train(training(), o);
  if (!m) {
    state.SkipWithError(m.error().message.c_str());
    return;
  }
  BodyParams p;
  p.noise_m = 0.01;
  const auto window = test::sequence(Motion::kWaveRight, 5.0, 1.0, p);
  for (auto _ : state) benchmark::DoNotOptimize(m->classify(window));
}

void BM_PyramidLinearSvm(benchmark::State& s) {
  classify(s, FeatureMethod::kPyramid, ClassifierKind::kLinearSvm);
}
void BM_RelativePositionsRbfSvm(benchmark::State& s) {
  classify(s, FeatureMethod::kRelativePositions, ClassifierKind::kRbfSvm);
}
BENCHMARK(BM_PyramidLinearSvm)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RelativePositionsRbfSvm)->Unit(benchmark::kMillisecond);

void BM_GestureMatchFiveGesturesThreeExamples(benchmark::State& state) {
  std::vector<LabelledSequence> demos;
  const Motion motions[] = {Motion::kCircleRight, Motion::kPunchRight, Motion::kWaveLeft,
                            Motion::kWaveRight, Motion::kArmsUp};
  for (int g = 0; g < 5; ++g)
    for (int k = 0; k < 3; ++k) {
      BodyParams p;
      p.seed = 100 + static_cast<uint64_t>(g * 3 + k);
      p.speed = 0.9 + 0.05 * k;
      demos.push_back({"g" + std::to_string(g), "", "", test::sequence(motions[g], 0, 1.2, p)});
    }
  auto m = GestureModel::train(demos, GestureOptions{});
  if (!m) {
    state.SkipWithError(m.error().message.c_str());
    return;
  }
  BodyParams p;
  const auto history = test::sequence(Motion::kCircleRight, 3.0, m->history_s(), p);
  for (auto _ : state) benchmark::DoNotOptimize(m->match(history));
}
BENCHMARK(BM_GestureMatchFiveGesturesThreeExamples)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dreamsense::actions

BENCHMARK_MAIN();
