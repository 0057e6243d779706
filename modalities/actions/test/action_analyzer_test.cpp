// The actions analyser alone: body entries in, body.action out, with the negative cases (no body
// in view, a model file that does not load).

#include "dreamsense/actions/action_analyzer.hpp"

#include <gtest/gtest.h>

#include "synthetic_body.hpp"

namespace dreamsense::actions {
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

// Runs the analyser over 25 Hz ticks; `body_at(t)` gives the body or nullopt (not in view).
std::vector<ActionState> run(Analyzer& a,
                             const std::function<std::optional<SkeletonFrame>(double)>& body_at,
                             double seconds) {
  Blackboard bb;
  std::vector<ActionState> out;
  for (int k = 0; k * 0.04 < seconds; ++k) {
    MultiFrame mf;
    mf.stamp = Timestamp::from_ns(k * 40'000'000LL);
    BlackboardWriter wb("body");
    if (auto f = body_at(k * 0.04)) {
      BodyState s;
      s.body.joints = f->joints;
      wb.set(keys::kChildBody, s, mf.stamp, 1.f);
    } else {
      wb.set_absent(keys::kChildBody, mf.stamp);
    }
    bb.commit(wb, mf.stamp);
    BlackboardWriter w("actions");
    EXPECT_TRUE(a.process(mf, bb.snapshot(), w));
    bb.commit(w, mf.stamp);
    auto e = bb.snapshot().get(keys::kChildAction);
    EXPECT_TRUE(e && e->present() && e->stamp == mf.stamp);
    if (e && e->present()) out.push_back(*e->value);
  }
  return out;
}

TEST(ActionAnalyzer, WritesTheChildsActionEveryTick) {
  auto a = make_action_analyzer(model(), nullptr);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ((*a)->contract().reads, std::vector<std::string>{"body.child"});
  EXPECT_EQ((*a)->contract().writes, std::vector<std::string>{"body.action"});
  BodyParams p;
  p.noise_m = 0.005;
  const auto states = run(
      **a, [&](double t) { return test::body_at(Motion::kWaveRight, t, p); }, 3.0);
  ASSERT_EQ(states.size(), 75u);
  int waves = 0;
  for (size_t k = 30; k < states.size(); ++k)
    waves += states[k].label == "wave" && states[k].dream_id == 1;
  EXPECT_GE(waves, 40);
  EXPECT_EQ(states.front().label, "none");
  EXPECT_FALSE(states.front().ready);
}

TEST(ActionAnalyzer, NobodyInViewIsNoneAndBadModelFilesFail) {
  auto a = make_action_analyzer(model(), nullptr);
  ASSERT_TRUE(a);
  const auto states = run(
      **a, [](double) { return std::nullopt; }, 2.0);
  for (const auto& s : states) {
    EXPECT_EQ(s.label, "none");
    EXPECT_EQ(s.dream_id, 0);
    EXPECT_FALSE(s.ready);
  }
  ActionAnalyzerOptions o;
  EXPECT_FALSE(make_action_analyzer(o));  // no model at all
  o.model = "/nonexistent/dream_gestures.yaml";
  auto bad = make_action_analyzer(o);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("dream_gestures.yaml"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::actions
