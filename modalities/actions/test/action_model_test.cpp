#include "dreamsense/actions/action_model.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "synthetic_body.hpp"

namespace dreamsense::actions {
namespace {

namespace fs = std::filesystem;
using test::BodyParams;
using test::Motion;

const std::vector<std::pair<Motion, const char*>> kClasses = {{Motion::kWaveRight, "wave_right"},
                                                              {Motion::kWaveLeft, "wave_left"},
                                                              {Motion::kArmsUp, "arms_up"},
                                                              {Motion::kPunchRight, "punch"}};

// Examples of each class by several "subjects" (sizes, places, facing, speeds, noise).
std::vector<LabelledSequence> examples(int subjects, uint64_t seed) {
  std::vector<LabelledSequence> out;
  for (int s = 0; s < subjects; ++s)
    for (const auto& [motion, label] : kClasses) {
      BodyParams p;
      p.seed = seed * 100 + static_cast<uint64_t>(s);
      p.scale = 0.6 + 0.1 * (s % 5);
      p.yaw_deg = -30 + 15 * (s % 5);
      p.position = {0.2 * (s % 3) - 0.2, 0.1, 2.0 + 0.2 * (s % 4)};
      p.speed = 0.8 + 0.1 * (s % 4);
      p.noise_m = 0.01;
      LabelledSequence e;
      e.label = label;
      e.subject = "s" + std::to_string(s);
      e.frames = test::sequence(motion, 0.1 * s, 1.2, p);
      out.push_back(std::move(e));
    }
  return out;
}

fs::path temp_file(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "dreamsense_actions_test";
  fs::create_directories(dir);
  return dir / name;
}

class ActionModelTest : public ::testing::TestWithParam<std::pair<FeatureMethod, ClassifierKind>> {
};

TEST_P(ActionModelTest, LearnsSyntheticClassesAndRoundTripsThroughItsFile) {
  ActionModelOptions o;
  o.features.method = GetParam().first;
  o.classifier.kind = GetParam().second;
  o.classifier.c = o.classifier.kind == ClassifierKind::kRbfSvm ? 10 : 1;
  o.features.distances = o.classifier.kind == ClassifierKind::kShrinkageLda;
  if (o.classifier.kind == ClassifierKind::kRbfSvm) {  // non-default options must survive the file
    o.body.normalize_bones = false;
    o.features.joints = JointSet::kAll;
    o.features.rjp_average = true;
    o.features.pose_relative = false;
    o.classifier.standardize_each = false;
  }
  auto m = ActionModel::train(examples(6, 1), o);
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->labels().size(), 4u);
  EXPECT_NEAR(m->window_s(), 1.2, 0.05);
  const auto tests = examples(4, 2);
  int correct = 0;
  for (const auto& e : tests) correct += m->classify(e.frames, false).label == e.label;
  EXPECT_GE(correct, static_cast<int>(tests.size()) - 1);

  const fs::path file = temp_file(std::string(to_string(o.features.method)) + "_" +
                                  std::string(to_string(o.classifier.kind)) + ".yaml");
  m->description = "unit test";
  ASSERT_TRUE(m->save(file));
  auto back = ActionModel::load(file);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->labels(), m->labels());
  EXPECT_EQ(back->description, "unit test");
  const ActionModelOptions& b = back->options();
  EXPECT_EQ(b.body.normalize_bones, o.body.normalize_bones);
  EXPECT_EQ(b.body.normalize_facing, o.body.normalize_facing);
  EXPECT_EQ(b.features.joints, o.features.joints);
  EXPECT_EQ(b.features.method, o.features.method);
  EXPECT_EQ(b.features.rjp_average, o.features.rjp_average);
  EXPECT_EQ(b.features.pose_relative, o.features.pose_relative);
  EXPECT_EQ(b.features.distances, o.features.distances);
  EXPECT_EQ(b.classifier.standardize_each, o.classifier.standardize_each);
  EXPECT_EQ(b.classifier.kind, o.classifier.kind);
  EXPECT_DOUBLE_EQ(back->reject_threshold(), m->reject_threshold());
  for (const auto& e : tests) {
    const ActionScores a = m->classify(e.frames), b = back->classify(e.frames);
    EXPECT_EQ(a.label, b.label);
    ASSERT_EQ(a.decision.size(), b.decision.size());
    for (size_t k = 0; k < a.decision.size(); ++k) EXPECT_NEAR(a.decision[k], b.decision[k], 1e-4);
    double sum = 0;
    for (double s : a.scores) sum += s;
    EXPECT_NEAR(sum, 1.0, 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Methods, ActionModelTest,
    ::testing::Values(std::make_pair(FeatureMethod::kPyramid, ClassifierKind::kLinearSvm),
                      std::make_pair(FeatureMethod::kRelativePositions, ClassifierKind::kRbfSvm),
                      std::make_pair(FeatureMethod::kPyramid, ClassifierKind::kRbfSvm),
                      std::make_pair(FeatureMethod::kPyramid, ClassifierKind::kShrinkageLda)));

TEST(ActionModel, LdaDecisionsAreLogPosteriorsAndItRejectsTheUnknown) {
  ActionModelOptions o;
  o.features.distances = true;
  o.classifier.kind = ClassifierKind::kShrinkageLda;
  auto m = ActionModel::train(examples(6, 1), o);
  ASSERT_TRUE(m) << m.error().message;
  const auto tests = examples(4, 2);
  for (const auto& e : tests) {
    const ActionScores s = m->classify(e.frames, false);
    double sum = 0;
    for (double d : s.decision) {
      EXPECT_LE(d, 1e-9);
      sum += std::exp(d);
    }
    EXPECT_NEAR(sum, 1.0, 1e-6);
  }
  EXPECT_LE(m->reject_threshold(), 0.0);
  int rejected = 0;
  for (int s = 0; s < 5; ++s) {
    BodyParams p;
    p.seed = 77 + static_cast<uint64_t>(s);
    p.speed = 2.0;
    rejected += m->classify(test::sequence(Motion::kCircleRight, 0.2 * s, 1.2, p)).rejected;
  }
  EXPECT_GE(rejected, 3);
}

TEST(ActionModel, UnknownMotionIsRejectedAndEmptyWindowIsNoData) {
  auto m = ActionModel::train(examples(6, 1), ActionModelOptions{});
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_GT(m->reject_threshold(), -1e29);
  // Drawing circles in front of the body at twice the speed is none of the four classes.
  int rejected = 0;
  for (int s = 0; s < 5; ++s) {
    BodyParams p;
    p.seed = 77 + static_cast<uint64_t>(s);
    p.speed = 2.0;
    const auto seq = test::sequence(Motion::kCircleRight, 0.2 * s, 1.2, p);
    const ActionScores r = m->classify(seq);
    rejected += r.rejected;
    if (r.rejected) {
      EXPECT_EQ(r.label, kNoneLabel);
      EXPECT_EQ(r.index, -1);
    }
  }
  EXPECT_GE(rejected, 3);
  const ActionScores empty = m->classify({});
  EXPECT_TRUE(empty.no_data);
  EXPECT_EQ(empty.label, kNoneLabel);
}

TEST(ActionModel, TrainingNeedsTwoClasses) {
  auto all = examples(3, 1);
  std::vector<LabelledSequence> one;
  for (auto& e : all)
    if (e.label == "punch") one.push_back(e);
  auto m = ActionModel::train(one, ActionModelOptions{});
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("two classes"), std::string::npos);
}

TEST(ActionModel, FilesFromAnotherVersionOrCorruptGiveOneLineErrors) {
  auto m = ActionModel::train(examples(4, 1), ActionModelOptions{});
  ASSERT_TRUE(m);
  const fs::path good = temp_file("good.yaml");
  ASSERT_TRUE(m->save(good));
  std::ifstream in(good);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

  auto write = [](const fs::path& p, const std::string& s) {
    std::ofstream(p) << s;
    return p;
  };
  std::string v2 = text;
  v2.replace(v2.find("version: 1"), 10, "version: 7");
  auto r = ActionModel::load(write(temp_file("v7.yaml"), v2));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(r.error().message.find("version 7"), std::string::npos);
  EXPECT_NE(r.error().message.find("v7.yaml"), std::string::npos);

  r = ActionModel::load(write(temp_file("truncated.yaml"), text.substr(0, text.size() / 2)));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("truncated.yaml"), std::string::npos);
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos);

  r = ActionModel::load(write(temp_file("garbage.yaml"), "%YAML:1.0\n---\nfoo: [1, 2\n"));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos);

  std::string other = text;
  other.replace(other.find("dreamsense.actions.model"), 24, "dreamsense.voices.model!");
  r = ActionModel::load(write(temp_file("other.yaml"), other));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("format"), std::string::npos);

  r = ActionModel::load(temp_file("does_not_exist.yaml"));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::kNotFound);
}

}  // namespace
}  // namespace dreamsense::actions
