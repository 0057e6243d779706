// `eval expression` with a model on a dataset whose classes differ from the model's (issue 20):
// the FER2013 folder names map to the project's labels, and a class the model lacks keeps its
// row, counts as wrong and is reported. Synthetic images (no real data needed).
#include "dreamsense/eval/faces/expression_eval.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <unistd.h>

namespace dreamsense::eval::faces {
namespace {
namespace fs = std::filesystem;

TEST(ExpressionEvalLabels, ClassesMissingFromModel) {
  const std::vector<std::string> ck = {"anger", "contempt", "disgust", "fear",
                                       "happy", "sadness",  "surprise"};
  const std::vector<std::string> fer = {"anger",   "disgust",  "fear",   "happy",
                                        "sadness", "surprise", "neutral"};
  EXPECT_EQ(classes_missing_from_model(fer, ck), std::vector<std::string>{"neutral"});
  EXPECT_TRUE(classes_missing_from_model(ck, ck).empty());
  // A model with more classes than the dataset misses nothing.
  EXPECT_TRUE(classes_missing_from_model({"happy", "neutral"}, fer).empty());
  EXPECT_EQ(classes_missing_from_model({"happy", "happy", "fear"}, {"sadness"}),
            (std::vector<std::string>{"happy", "fear"}));
}

TEST(ExpressionEvalLabels, Fer2013FolderNamesOfTheProjectLabels) {
  const auto names = dataset_class_names("fer2013");
  EXPECT_EQ(names.size(), 7u);
  EXPECT_EQ(names.at("anger"), "angry");
  EXPECT_EQ(names.at("sadness"), "sad");
  EXPECT_EQ(names.at("neutral"), "neutral");
  EXPECT_EQ(names.count("contempt"), 0u);
  EXPECT_EQ(dataset_class_names("ckplus48").at("contempt"), "contempt");
}

// Stripes whose direction is the class: horizontal (happy) or vertical (sad / neutral here).
cv::Mat stripes(bool horizontal, int seed) {
  cv::Mat m(48, 48, CV_8UC1);
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x)
      m.at<uchar>(y, x) = static_cast<uchar>(((horizontal ? y : x) / 3) % 2 ? 190 : 50);
  cv::Mat noise(m.size(), CV_8UC1);
  cv::theRNG().state = static_cast<uint64_t>(seed) + 1;
  cv::randu(noise, 0, 30);
  return m + noise;
}

TEST(ExpressionEvalModel, AClassTheModelLacksCountsAsWrongAndIsReported) {
  const fs::path root = fs::temp_directory_path() / ("ds_expr_eval_" + std::to_string(::getpid()));
  fs::remove_all(root);
  auto write = [&](const fs::path& dir, bool horizontal, int n, int seed0) {
    fs::create_directories(dir);
    for (int i = 0; i < n; ++i)
      cv::imwrite((dir / ("PublicTest_" + std::to_string(seed0 + i) + ".png")).string(),
                  stripes(horizontal, seed0 + i));
  };
  write(root / "train" / "happy", true, 8, 0);
  write(root / "train" / "sad", false, 8, 100);
  write(root / "test" / "happy", true, 4, 200);
  write(root / "test" / "neutral", false, 3, 300);

  ExpressionTrainOptions t;
  t.dataset = "fer2013";
  t.dir = root / "train";
  auto model = run_expression_train(t);
  ASSERT_TRUE(model.has_value()) << model.error().message;
  EXPECT_EQ(model->labels(), (std::vector<std::string>{"happy", "sadness"}));
  ASSERT_TRUE(model->save(root / "model.yaml").has_value());

  ExpressionEvalOptions e;
  e.dataset = "fer2013";
  e.dir = root / "test";
  e.model = root / "model.yaml";
  auto r = run_expression_eval(e);
  fs::remove_all(root);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  const nlohmann::json j = r->to_json();
  EXPECT_EQ(r->items, 7u);
  EXPECT_EQ(r->extra.at("classes_missing_from_model"), nlohmann::json::array({"neutral"}));
  EXPECT_NE(r->protocol.find("neutral"), std::string::npos) << r->protocol;
  // Neutral has a row with every image wrong; the accuracy cannot exceed happy's share.
  ASSERT_TRUE(r->per_class.contains("neutral")) << j.dump();
  EXPECT_EQ(r->per_class.at("neutral").at("recall").get<double>(), 0.0);
  EXPECT_EQ(r->per_class.at("neutral").at("support").get<int>(), 3);
  EXPECT_LE(r->metrics.at("accuracy").get<double>(), 4.0 / 7 + 1e-9);
  EXPECT_EQ(r->extra.at("dataset_class_names").at("sadness"), "sad");
  EXPECT_TRUE(r->timing.at("ms_per_face_median").is_number());
}

}  // namespace
}  // namespace dreamsense::eval::faces
