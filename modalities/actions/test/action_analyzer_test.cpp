// The actions analyser alone (testing::AnalyzerRunner): body.child presets in, body.action out
// every tick, with the negative cases: no body in view, NaN joints, another person taken for the
// child for a few ticks, a model file that does not load.

#include "dreamsense/actions/action_analyzer.hpp"

#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/testing/analyzer_runner.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

#include "synthetic_body.hpp"

namespace dreamsense::actions {
void register_analyzers(AnalyzerRegistry& registry);  // src/register.cpp
namespace {

using test::BodyParams;
using test::Motion;

std::shared_ptr<const ActionModel> model() {
  std::vector<LabelledSequence> ex;
  for (int s = 0; s < 6; ++s)
    for (auto [motion, label] :
         {std::pair{Motion::kStill, "none"}, std::pair{Motion::kWaveRight, "wave"},
          std::pair{Motion::kArmsUp, "hands_on_head"}}) {
      BodyParams p;
      p.seed = 30 + static_cast<uint64_t>(s);
      p.scale = 0.6 + 0.08 * s;
      p.speed = 0.8 + 0.1 * s;
      p.noise_m = 0.01;
      ex.push_back({label, "s" + std::to_string(s), "", test::sequence(motion, 0.3 * s, 1.0, p)});
    }
  ActionModelOptions o;
  o.window_s = 1.0;
  return std::make_shared<const ActionModel>(*ActionModel::train(ex, o));
}

// The body at time t, or nullopt when the body analyser found nobody (absent entry).
using BodyAt = std::function<std::optional<BodyState>(double t)>;

BodyState state_of(const SkeletonFrame& f, int bodies = 1) {
  BodyState s;
  s.body.joints = f.joints;
  s.sensor = "front.skeleton";
  s.bodies_in_view = bodies;
  return s;
}

// Runs the analyser over 25 Hz ticks; every tick must write body.action at the tick's stamp.
std::vector<ActionState> run(testing::AnalyzerRunner& runner, const BodyAt& body_at, double seconds,
                             double t0 = 0) {
  std::vector<ActionState> out;
  for (int k = 0; k * 0.04 < seconds; ++k) {
    const double t = t0 + k * 0.04;
    const Timestamp stamp = Timestamp::from_ns(std::llround(t * 1e9));
    if (auto b = body_at(t))
      runner.preset(keys::kChildBody, *b, stamp, 1.f);
    else
      runner.preset_absent(keys::kChildBody, stamp);
    EXPECT_TRUE(runner.run(stamp, {}));
    const auto e = runner.output(keys::kChildAction);
    EXPECT_TRUE(e && e->present() && e->stamp == stamp) << "t " << t;
    if (e && e->present()) out.push_back(*e->value);
  }
  return out;
}

testing::AnalyzerRunner runner_with(std::shared_ptr<const ActionModel> m) {
  auto a = make_action_analyzer(std::move(m), nullptr);
  EXPECT_TRUE(a) << a.error().message;
  return testing::AnalyzerRunner(std::move(*a));
}

int count_label(const std::vector<ActionState>& states, size_t from, const std::string& label) {
  int n = 0;
  for (size_t k = from; k < states.size(); ++k) n += states[k].label == label;
  return n;
}

TEST(ActionAnalyzer, WritesTheChildsActionEveryTick) {
  auto runner = runner_with(model());
  EXPECT_EQ(runner.contract().reads, std::vector<std::string>{"body.child"});
  EXPECT_EQ(runner.contract().writes, std::vector<std::string>{"body.action"});
  BodyParams p;
  p.noise_m = 0.005;
  const auto states = run(
      runner, [&](double t) { return state_of(test::body_at(Motion::kWaveRight, t, p)); }, 3.0);
  ASSERT_EQ(states.size(), 75u);
  int waves = 0;
  for (size_t k = 30; k < states.size(); ++k)
    waves += states[k].label == "wave" && states[k].dream_id == 1;
  EXPECT_GE(waves, 40);
  EXPECT_EQ(states.front().label, "none");
  EXPECT_FALSE(states.front().ready);
  EXPECT_TRUE(states.back().ready);
  EXPECT_DOUBLE_EQ(states.back().window_s, 1.0);
  ASSERT_EQ(states.back().scores.size(), 3u) << "one score per class";
}

TEST(ActionAnalyzer, NobodyInViewIsNotReady) {
  auto runner = runner_with(model());
  for (const auto& s : run(
           runner, [](double) { return std::nullopt; }, 2.0)) {
    EXPECT_EQ(s.label, "none");
    EXPECT_EQ(s.dream_id, 0);
    EXPECT_FALSE(s.ready);
  }
  // The child leaves view for 1.5 s in the middle of a wave: once the window holds no body,
  // nothing is classified (no gesture), and the wave is recognised again once it has refilled.
  BodyParams p;
  auto states = run(
      runner,
      [&](double t) -> std::optional<BodyState> {
        if (t >= 4.0 && t < 5.5) return std::nullopt;
        return state_of(test::body_at(Motion::kWaveRight, t, p));
      },
      6.0, 2.0);
  ASSERT_EQ(states.size(), 150u);
  for (size_t k = 76; k < 87; ++k) {
    EXPECT_EQ(states[k].label, "none") << "tick " << k;
    EXPECT_FALSE(states[k].ready) << "tick " << k;
  }
  EXPECT_GE(count_label(states, 113, "wave"), 25);
}

TEST(ActionAnalyzer, NanAndMissingJointsKeepTheLabel) {
  auto runner = runner_with(model());
  BodyParams p;
  // Every fourth tick one arm joint is NaN, every third the left side is missing, legs and feet
  // are never tracked: the wave is still recognised.
  auto states = run(
      runner,
      [&](double t) {
        SkeletonFrame f = test::body_at(Motion::kWaveRight, t, p);
        const int k = static_cast<int>(std::lround(t / 0.04));
        if (k % 4 == 0)
          f.joint(JointId::kElbowRight).position_m[0] = std::numeric_limits<double>::quiet_NaN();
        if (k % 3 == 0)
          for (JointId j : {JointId::kShoulderLeft, JointId::kElbowLeft, JointId::kWristLeft})
            f.joint(j).confidence = 0.f;
        for (int j = static_cast<int>(JointId::kKneeLeft); j < kJointCount; ++j)
          if (j != static_cast<int>(JointId::kHipRight)) f.joints[static_cast<size_t>(j)] = {};
        return state_of(f);
      },
      3.0);
  EXPECT_GE(count_label(states, 30, "wave"), 40);
  // A body whose joints are all NaN is nothing to classify: no gesture, no crash.
  auto nan_runner = runner_with(model());
  states = run(
      nan_runner,
      [&](double t) {
        SkeletonFrame f = test::body_at(Motion::kWaveRight, t, p);
        for (auto& j : f.joints) j.position_m = {std::numeric_limits<double>::quiet_NaN(), 0, 0};
        return state_of(f);
      },
      2.0);
  for (const auto& s : states) {
    EXPECT_EQ(s.label, "none");
    EXPECT_FALSE(s.ready);
  }
}

TEST(ActionAnalyzer, AnotherPersonForAFewTicksDoesNotStickTheLabel) {
  // The body analyser takes a second person (an adult standing behind, arms up) for the child
  // for 3 ticks: only the windows that contain them can change (to none: they are rejected, never
  // the intruder's gesture), and the child's wave is back after a window.
  auto runner = runner_with(model());
  BodyParams child;
  child.scale = 0.65;
  BodyParams adult;
  adult.position = {0.8, 0, 3.2};
  const auto states = run(
      runner,
      [&](double t) {
        if (t >= 2.0 && t < 2.12) return state_of(test::body_at(Motion::kArmsUp, t, adult), 2);
        return state_of(test::body_at(Motion::kWaveRight, t, child), 2);
      },
      5.0);
  ASSERT_EQ(states.size(), 125u);
  EXPECT_EQ(count_label(states, 0, "hands_on_head"), 0) << "the intruder's pose is not reported";
  EXPECT_GE(count_label(states, 30, "wave"), 18) << "before the intrusion";
  // The windows that hold the intruder (about one window length) are rejected; then the wave is
  // back.
  EXPECT_GE(count_label(states, 80, "wave"), 40) << "recovered within a window";
}

TEST(ActionAnalyzer, BadModelFilesFail) {
  ActionAnalyzerOptions o;
  EXPECT_FALSE(make_action_analyzer(o));  // no model at all
  o.model = "/nonexistent/dream_gestures.yaml";
  auto bad = make_action_analyzer(o);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("dream_gestures.yaml"), std::string::npos);
  o.model = default_action_model_path();
  auto shipped = make_action_analyzer(o);
  ASSERT_TRUE(shipped) << shipped.error().message;
}

// The declared pipeline's factory: the shipped model by default, custom gestures from the
// subject folder or the `gestures` option, `none` to switch a model off, one-line errors.
TEST(ActionsFactory, ShippedModelByDefaultGesturesFromTheSubjectFolder) {
  AnalyzerRegistry registry;
  register_analyzers(registry);
  const AnalyzerFactory* f = registry.find("actions");
  ASSERT_NE(f, nullptr);
  PlanContext ctx;
  OptionsNode no_options;
  auto skipped = f->plan(ctx, no_options);
  ASSERT_TRUE(skipped);
  EXPECT_FALSE(skipped->skipped.empty()) << "no skeleton stream: not planned";

  StreamDescription body;
  body.id = "front.skeleton";
  body.kind = SensorKind::kSkeleton;
  body.roles = {roles::kBody};
  ctx.streams.push_back(body);
  OptionsNode defaults;
  auto p = f->plan(ctx, defaults);
  ASSERT_TRUE(p) << p.error().message;
  ASSERT_EQ(p->analyzers.size(), 1u);
  ASSERT_EQ(p->notes.size(), 2u);
  EXPECT_NE(p->notes[0].find("dream_gestures.yaml"), std::string::npos) << p->notes[0];
  EXPECT_EQ(p->notes[1], "custom gestures none");

  // A subject folder with gestures.yaml (from `train gestures`).
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "dreamsense_actions_factory_test";
  std::filesystem::create_directories(dir);
  std::vector<LabelledSequence> demos;
  for (int k = 0; k < 3; ++k) {
    BodyParams bp;
    bp.seed = 50 + static_cast<uint64_t>(k);
    demos.push_back({"circle", "demo" + std::to_string(k), "",
                     test::sequence(Motion::kCircleRight, 0.2 * k, 1.5, bp)});
  }
  auto g = GestureModel::train(demos, GestureOptions{});
  ASSERT_TRUE(g) << g.error().message;
  ASSERT_TRUE(g->save(dir / "gestures.yaml"));
  ctx.subject.folder = dir;
  OptionsNode subject_defaults;
  p = f->plan(ctx, subject_defaults);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_NE(p->notes[1].find("gestures.yaml"), std::string::npos) << p->notes[1];

  OptionsNode off;
  ASSERT_TRUE(off.set("gestures", "none"));
  ASSERT_TRUE(off.set("model", "none"));
  auto nothing = f->plan(ctx, off);
  ASSERT_FALSE(nothing) << "neither model: an error, not a silent analyser";

  OptionsNode gestures_only;
  ASSERT_TRUE(gestures_only.set("model", "none"));
  p = f->plan(ctx, gestures_only);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_EQ(p->notes[0], "action model none");

  std::ofstream(dir / "broken.yaml") << "format: something_else\n";
  OptionsNode broken;
  ASSERT_TRUE(broken.set("model", (dir / "broken.yaml").string()));
  auto bad = f->plan(ctx, broken);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("broken.yaml"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace dreamsense::actions
