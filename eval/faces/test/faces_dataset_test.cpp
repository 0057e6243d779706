// Dataset checks (label dataset) on the real face sets in ../shared/data (or $DREAMSENSE_DATA):
// CK+48 expression (subject-disjoint CV, and train on some subjects' folder / test on another's),
// AT&T identity with unknown rejection. Each skips cleanly without its data
// (and the network parts without the npm package). Thresholds sit below the measured values
// (README.md) so that they catch regressions, not noise.
#include "dreamsense/eval/faces/datasets.hpp"
#include "dreamsense/eval/faces/expression_eval.hpp"
#include "dreamsense/eval/faces/identity_eval.hpp"
#include "dreamsense/expression/expression_analyzer.hpp"
#include "dreamsense/vision/face_api_net.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
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

// FER2013 faces in the wild (issue 20): the shipped model is trained on all of fer2013_public,
// so testing it there would be in-sample; instead the shipped model's method is
// cross-validated on a fixed subset (the first kPerClass images of each class in natural order,
// 5 folds), which checks the method and the crop path on unseen faces. The heads are trained on
// the package's frozen network: the shipped fine-tuned network is cross-validated by
// tools/train_fer_net.py (PyTorch, too slow for a test).
TEST(FacesDataset, Fer2013CrossValidationOfTheShippedMethod) {
  constexpr size_t kPerClass = 100;
  const fs::path dir = data_dir("fer2013_public");
  if (!fs::exists(dir / "happy")) GTEST_SKIP() << "FER2013 absent (" << dir << ")";
  auto shipped = expression::ExpressionModel::load(expression::default_expression_model());
  ASSERT_TRUE(shipped.has_value()) << shipped.error().message;
  if (shipped->method().features.uses_network() && !have_face_api())
    GTEST_SKIP() << "face-api.js weights absent (npm @vladmandic/face-api)";
  auto items = read_fer2013(dir);
  ASSERT_TRUE(items.has_value()) << items.error().message;
  const fs::path root = fs::temp_directory_path() / ("ds_fer_subset_" + std::to_string(::getpid()));
  fs::remove_all(root);
  std::map<std::string, size_t> taken;
  for (const auto& it : *items) {
    if (taken[it.label]++ >= kPerClass) continue;
    const fs::path target = root / it.path.parent_path().filename() / it.path.filename();
    fs::create_directories(target.parent_path());
    fs::create_symlink(fs::absolute(it.path), target);
  }
  ExpressionEvalOptions o;
  o.dataset = "fer2013";
  o.dir = root;
  o.methods = {shipped->method().name};
  o.folds = 5;
  auto r = run_expression_eval(o);
  fs::remove_all(root);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(r->per_class.size(), 7u);
  EXPECT_TRUE(r->per_class.contains("neutral"));
  const double accuracy = r->metrics.at("accuracy").get<double>();
  std::printf("FER2013 subset (%zu images), 5-fold CV of %s: accuracy %.4f\n", r->items,
              shipped->method().name.c_str(), accuracy);
  // Measured 0.515 (face_api:no_flip:unbalanced:l2=0.3; 10-fold CV on all 3,589 images: 0.548).
  EXPECT_GE(accuracy, 0.47) << r->to_json().dump();
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
