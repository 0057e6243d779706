#include "dreamsense/actions/gesture_model.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "synthetic_body.hpp"

namespace dreamsense::actions {
namespace {

namespace fs = std::filesystem;
using test::BodyParams;
using test::Motion;

LabelledSequence demo(Motion motion, const std::string& label, int k, double cycles = 1.0) {
  BodyParams p;
  p.seed = 500 + static_cast<uint64_t>(k);
  p.scale = 0.7 + 0.05 * k;
  p.yaw_deg = -10 + 7 * k;
  p.speed = 0.9 + 0.07 * k;
  p.noise_m = 0.005;
  LabelledSequence e;
  e.label = label;
  e.source = label + " #" + std::to_string(k);
  // One full cycle of the motion at this speed.
  e.frames = test::sequence(motion, 0, cycles / (1.5 * p.speed), p);
  return e;
}

TEST(GestureModel, ThreeExamplesRecogniseAFourthAndRejectOtherMotions) {
  std::vector<LabelledSequence> demos;
  for (int k = 0; k < 3; ++k) demos.push_back(demo(Motion::kCircleRight, "circle", k));
  auto g = GestureModel::train(demos, GestureOptions{});
  ASSERT_TRUE(g) << g.error().message;
  ASSERT_EQ(g->labels(), std::vector<std::string>{"circle"});
  EXPECT_GE(g->thresholds()[0], GestureOptions{}.min_threshold);

  // The live history holds two cycles of the movement (matching looks for the template inside).
  const LabelledSequence fourth = demo(Motion::kCircleRight, "circle", 3, 2.0);
  const GestureMatch hit = g->match(fourth.frames);
  EXPECT_EQ(hit.label, "circle") << hit.distance << " vs " << hit.threshold;
  for (Motion other : {Motion::kStill, Motion::kWaveRight, Motion::kArmsUp, Motion::kPunchRight,
                       Motion::kWaveLeft}) {
    const GestureMatch miss = g->match(demo(other, "x", 3, 2.0).frames);
    EXPECT_EQ(miss.label, "none") << static_cast<int>(other) << ": " << miss.distance << " vs "
                                  << miss.threshold;
  }
}

TEST(GestureModel, RoundTripAndErrors) {
  std::vector<LabelledSequence> demos;
  for (int k = 0; k < 3; ++k) demos.push_back(demo(Motion::kCircleRight, "circle", k));
  for (int k = 0; k < 2; ++k) demos.push_back(demo(Motion::kPunchRight, "punch", k));
  auto g = GestureModel::train(demos, GestureOptions{});
  ASSERT_TRUE(g) << g.error().message;
  const fs::path dir = fs::temp_directory_path() / "dreamsense_actions_test";
  fs::create_directories(dir);
  const fs::path file = dir / "gestures.yaml";
  ASSERT_TRUE(g->save(file));
  auto back = GestureModel::load(file);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->labels(), g->labels());
  EXPECT_EQ(back->templates().size(), 5u);
  const auto probe = demo(Motion::kPunchRight, "punch", 4, 2.0).frames;
  EXPECT_EQ(back->match(probe).label, "punch");
  EXPECT_EQ(g->match(probe).label, "punch");
  EXPECT_NEAR(back->match(probe).distance, g->match(probe).distance, 1e-5);

  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("version: 1"), 10, "version: 2");
  std::ofstream(dir / "gestures_v2.yaml") << text;
  auto r = GestureModel::load(dir / "gestures_v2.yaml");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);

  // A demonstration labelled none, or too short, is refused with its source named.
  auto bad = demos;
  bad[1].label = "none";
  auto t = GestureModel::train(bad, GestureOptions{});
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find("circle #1"), std::string::npos);
  bad = demos;
  bad[0].frames.resize(2);
  EXPECT_FALSE(GestureModel::train(bad, GestureOptions{}));
}

}  // namespace
}  // namespace dreamsense::actions
