// Dataset checks (label dataset) on the real face sets in ../shared/data (or $DREAMSENSE_DATA):
// CK+48 expression (subject-disjoint CV, and train on some subjects' folder / test on another's),
// AT&T identity with unknown rejection. Each skips cleanly without its data
// (and the network parts without the npm package). Thresholds sit below the measured values
// (README.md) so that they catch regressions, not noise.
#include "dreamsense/eval/faces/datasets.hpp"
#include "dreamsense/eval/faces/expression_eval.hpp"
#include "dreamsense/eval/faces/identity_eval.hpp"
#include "dreamsense/vision/face_api_net.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <set>
#include <unistd.h>

namespace dreamsense::eval::faces {
namespace {
namespace fs = std::filesystem;

fs::path data_dir(const std::string& set) {
  if (const char* d = std::getenv("DREAMSENSE_DATA")) return fs::path(d) / set;
  return fs::path(DREAMSENSE_SOURCE_DIR) / "../shared/data" / set;
}

bool have_face_api() {
  return fs::exists(vision::default_face_api_model_dir() /
                    "face_recognition_model-weights_manifest.json");
}

double metric(const EvalReport& r, const std::string& method, const std::string& key) {
  const auto& m = r.metrics.at(method);
  return m.at(key).is_number() ? m.at(key).get<double>() : -1.0;
}

TEST(FacesDataset, CkPlusCrossValidationImprovedBeatsTheSeed) {
  ExpressionEvalOptions o;
  o.dataset = "ckplus48";
  o.dir = data_dir("ckplus48");
  if (!fs::exists(o.dir / "happy")) GTEST_SKIP() << "CK+48 absent (" << o.dir << ")";
  o.methods = {"lbp_hog", "lbp_svm"};
  auto r = run_expression_eval(o);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(r->per_class.size(), 7u);
  const double improved = metric(*r, "lbp_hog", "accuracy"),
               seed = metric(*r, "lbp_svm", "accuracy");
  EXPECT_GE(improved, 0.89) << r->to_json().dump();  // measured 0.910 (issue 12 target 0.89)
  EXPECT_GE(seed, 0.78);                             // measured 0.833 (D4.2: 0.53)
  EXPECT_GT(improved, seed + 0.05);
  EXPECT_GE(r->extra.at("alignment").at("landmarks").get<size_t>(), r->items * 9 / 10);
}

TEST(FacesDataset, CkPlusTrainOnSomeSubjectsTestOnOthers) {
  const fs::path dir = data_dir("ckplus48");
  if (!fs::exists(dir / "happy")) GTEST_SKIP() << "CK+48 absent (" << dir << ")";
  auto items = read_ckplus48(dir);
  ASSERT_TRUE(items.has_value());
  // Two folders of symbolic links: subjects in the first and second half of the sorted ids.
  std::set<std::string> subjects;
  for (const auto& it : *items) subjects.insert(it.subject);
  const std::string middle = *std::next(subjects.begin(), static_cast<long>(subjects.size() / 2));
  const fs::path root =
      fs::temp_directory_path() / ("ds_ckplus_split_" + std::to_string(::getpid()));
  fs::remove_all(root);
  for (const auto& it : *items) {
    const fs::path target = root / (it.subject < middle ? "train" : "test") /
                            it.path.parent_path().filename() / it.path.filename();
    fs::create_directories(target.parent_path());
    fs::create_symlink(fs::absolute(it.path), target);
  }
  ExpressionTrainOptions t;
  t.dataset = "ckplus48";
  t.dir = root / "train";
  auto model = run_expression_train(t);
  ASSERT_TRUE(model.has_value()) << model.error().message;
  ASSERT_TRUE(model->save(root / "model.yaml").has_value());
  ExpressionEvalOptions e;
  e.dataset = "ckplus48";
  e.dir = root / "test";
  e.model = root / "model.yaml";
  auto r = run_expression_eval(e);
  fs::remove_all(root);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  // Measured 0.785 (lbp_hog trained on the 39 lower-numbered subjects only, tested on the 40
  // others: contempt and sadness collapse with half the training data; README.md). Below the
  // issue's 0.89, which cross-validation with 90 % of the subjects for training reaches.
  EXPECT_GE(r->metrics.at("accuracy").get<double>(), 0.75) << r->to_json().dump();
  EXPECT_TRUE(r->timing.at("ms_per_face_median").is_number());
}

TEST(FacesDataset, AttOpenSetIdentification) {
  FaceIdEvalOptions o;
  o.dataset = "att";
  o.dir = data_dir("att_faces");
  if (!fs::exists(o.dir / "s1")) GTEST_SKIP() << "AT&T absent (" << o.dir << ")";
  o.enroll = 5;
  o.unknown = 5;
  o.methods = {"lbp_tt", "lbp_svm"};
  if (have_face_api()) o.methods.insert(o.methods.begin(), "face_api");
  auto r = run_face_id_eval(o);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(r->extra.at("known_probes").get<size_t>(), 75u);
  EXPECT_EQ(r->extra.at("unknown_probes").get<size_t>(), 50u);
  // The classical methods identify well but must reject many known faces to refuse strangers.
  EXPECT_GE(metric(*r, "lbp_tt", "closed_set_accuracy"), 0.9);
  EXPECT_LE(metric(*r, "lbp_tt", "false_accept_rate"), 0.1);
  if (have_face_api()) {
    EXPECT_GE(metric(*r, "face_api", "accuracy"), 0.93) << r->to_json().dump();  // measured 0.973
    EXPECT_LE(metric(*r, "face_api", "false_accept_rate"), 0.08);                // measured 0.02
    EXPECT_GT(metric(*r, "face_api", "accuracy"), metric(*r, "lbp_tt", "accuracy"));
  }
}

}  // namespace
}  // namespace dreamsense::eval::faces
