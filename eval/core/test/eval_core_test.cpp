#include "dreamsense/eval/classification.hpp"
#include "dreamsense/eval/report.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

namespace dreamsense::eval {
namespace {

TEST(ConfusionMatrix, CountsRowsByTruthAndRejectionsAsErrors) {
  ConfusionMatrix m({"happy", "sad"}, "unknown");
  m.add("happy", "happy");
  m.add("happy", "sad");
  m.add("sad", "sad");
  m.add("sad", "unknown");
  m.add("angry", "happy");  // not a scored class
  EXPECT_EQ(m.total(), 4u);
  EXPECT_DOUBLE_EQ(*m.accuracy(), 0.5);
  EXPECT_DOUBLE_EQ(*m.recall("happy"), 0.5);
  EXPECT_DOUBLE_EQ(*m.precision("sad"), 0.5);
  const auto c = m.confusion_json();
  EXPECT_EQ(c["rows"][1][2], 1) << "the rejection lands in the extra column";
  EXPECT_EQ(c["predicted_labels"].back(), "unknown");
  EXPECT_DOUBLE_EQ(m.per_class_json()["sad"]["recall"].get<double>(), 0.5);
  EXPECT_FALSE(ConfusionMatrix({"a"}).accuracy().has_value()) << "no data is not zero";
}

TEST(Splits, FoldsAreDisjointAndCoverEverySubject) {
  std::vector<std::string> s;
  for (int i = 0; i < 23; ++i) s.push_back("S" + std::to_string(i));
  const auto folds = subject_folds(s, 10, 7);
  ASSERT_EQ(folds.size(), 10u);
  std::set<std::string> seen;
  for (const auto& f : folds) {
    EXPECT_GE(f.size(), 2u);
    for (const auto& x : f) EXPECT_TRUE(seen.insert(x).second) << x << " in two folds";
  }
  EXPECT_EQ(seen.size(), 23u);
  EXPECT_EQ(subject_folds(s, 10, 7), folds) << "deterministic";
  const auto halves = random_half_splits(s, 10, 1);
  ASSERT_EQ(halves.size(), 10u);
  EXPECT_EQ(halves[0].size(), 11u);
  EXPECT_NE(halves[0], halves[1]);
}

TEST(EvalReport, HasTheCliShapeAndWritesAtomically) {
  EvalReport r;
  r.task = "expression";
  r.dataset = "ckplus48";
  r.items = 12;
  r.protocol = "test";
  r.metrics["accuracy"] = 0.5;
  r.extra["curve"] = nlohmann::json::array();
  const auto j = r.to_json();
  EXPECT_EQ(j["dataset"]["items"], 12);
  EXPECT_TRUE(j.contains("timing") && j.contains("per_class") && j.contains("curve"));
  const auto path = std::filesystem::temp_directory_path() / "ds_eval_core_report.json";
  ASSERT_TRUE(write_report(r, path.string()));
  std::ifstream in(path);
  EXPECT_EQ(nlohmann::json::parse(in)["task"], "expression");
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".partial"));
  EXPECT_FALSE(write_report(r, "/nonexistent-dir/x.json")) << "a bad target is an error";
  Stopwatch w;
  EXPECT_FALSE(w.median_ms().has_value());
  w.add_ms(3);
  w.add_ms(1);
  EXPECT_DOUBLE_EQ(*w.median_ms(), 2);
}

}  // namespace
}  // namespace dreamsense::eval
