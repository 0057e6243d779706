// Per-face cost of the face analysers once the 68 landmarks are known (what the pipeline pays:
// warp to the canonical crop, descriptors, classifier / gallery match), one thread. The
// expression models are trained on synthetic faces (the cost does not depend on the weights);
// the gallery holds 20 people x 5 images.
#include "dreamsense/expression/expression_model.hpp"
#include "dreamsense/face_identity/face_gallery.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <optional>

namespace {
using namespace dreamsense;

struct Frame {
  cv::Mat grey;
  std::vector<cv::Point2d> landmarks;
};

Frame frame() {
  Frame f;
  f.grey = cv::Mat(480, 640, CV_8UC1);
  cv::randu(f.grey, 0, 255);
  f.landmarks = vision::mean_face_landmarks(120);
  for (auto& p : f.landmarks) p += cv::Point2d(250, 150);
  return f;
}

std::optional<expression::ExpressionRecognizer> expression_recognizer(const std::string& method) {
  auto m = expression::expression_method(method);
  if (!m) return std::nullopt;
  auto e = expression::ExpressionFeatureExtractor::create(m->features);
  if (!e) return std::nullopt;
  const Frame f = frame();
  auto face = vision::align_face(f.grey, f.landmarks, m->features.alignment);
  cv::Mat x;
  std::vector<int> y;
  for (int i = 0; i < 6; ++i) {
    const auto v = e->extract(f.grey, **face);
    x.push_back(
        cv::Mat(1, static_cast<int>(v.size()), CV_32F, const_cast<float*>(v.data())).clone());
    x.row(x.rows - 1) += static_cast<float>(i % 3);
    y.push_back(i % 3);
  }
  auto model = expression::ExpressionModel::train(*m, x, y, {"happy", "sadness", "neutral"}, {},
                                                  e->face_api_hash());
  if (!model) return std::nullopt;
  auto r = expression::ExpressionRecognizer::create(std::move(*model));
  if (!r) return std::nullopt;
  return std::move(*r);
}

struct Identity {
  face_identity::IdentityFeatureExtractor extractor;
  face_identity::FaceIdentifier identifier;
};

std::optional<Identity> identity(const std::string& method) {
  auto m = face_identity::identity_method(method);
  if (!m) return std::nullopt;
  auto e = face_identity::IdentityFeatureExtractor::create(*m);
  if (!e) return std::nullopt;
  face_identity::FaceGallery g(*m, e->weights_hash());
  cv::RNG rng(1);
  for (int p = 0; p < 20; ++p)
    for (int k = 0; k < 5; ++k) {
      std::vector<float> v(face_identity::identity_feature_length(*m));
      for (float& x : v) x = static_cast<float>(rng.uniform(0.0, 1.0));
      (void)g.add(p, v);
    }
  auto id = face_identity::FaceIdentifier::create(std::move(g));
  if (!id) return std::nullopt;
  return Identity{std::move(*e), std::move(*id)};
}

void run(benchmark::State& state, const char* expression_method, const char* identity_method) {
  cv::setNumThreads(1);
  std::optional<expression::ExpressionRecognizer> ex;
  std::optional<Identity> id;
  if (expression_method && !(ex = expression_recognizer(expression_method))) {
    state.SkipWithError("expression method unavailable (face-api weights installed?)");
    return;
  }
  if (identity_method && !(id = identity(identity_method))) {
    state.SkipWithError("identity method unavailable (face-api weights installed?)");
    return;
  }
  const Frame f = frame();
  for (auto _ : state) {
    if (ex) {
      auto face = vision::align_face(f.grey, f.landmarks, ex->model().method().features.alignment);
      benchmark::DoNotOptimize(ex->recognize(f.grey, **face));
    }
    if (id) {
      auto face = vision::align_face(f.grey, f.landmarks, id->extractor.method().alignment);
      benchmark::DoNotOptimize(id->identifier.identify(id->extractor.extract(f.grey, **face)));
    }
  }
}

// What the analysers pay per frame in the pipeline with their defaults: expression (lbp_hog) on
// every frame, identity (face_api) refreshed once per second of a face track, i.e. on one frame
// in 25 at 25 Hz (face_identity_analyzer.hpp, refresh_s = 1).
void BM_Both_pipeline_default(benchmark::State& state) {
  cv::setNumThreads(1);
  auto ex = expression_recognizer("lbp_hog");
  auto id = identity("face_api");
  if (!ex || !id) {
    state.SkipWithError("method unavailable (face-api weights installed?)");
    return;
  }
  const Frame f = frame();
  int frame_index = 0;
  for (auto _ : state) {
    auto face = vision::align_face(f.grey, f.landmarks, ex->model().method().features.alignment);
    benchmark::DoNotOptimize(ex->recognize(f.grey, **face));
    if (frame_index++ % 25 == 0) {
      auto idf = vision::align_face(f.grey, f.landmarks, id->extractor.method().alignment);
      benchmark::DoNotOptimize(id->identifier.identify(id->extractor.extract(f.grey, **idf)));
    }
  }
}

void BM_Expression_lbp_svm(benchmark::State& s) { run(s, "lbp_svm", nullptr); }
void BM_Expression_lbp_hog(benchmark::State& s) { run(s, "lbp_hog", nullptr); }
void BM_Expression_face_api(benchmark::State& s) { run(s, "face_api", nullptr); }
void BM_Expression_face_api_no_flip(benchmark::State& s) { run(s, "face_api:no_flip", nullptr); }
void BM_Identity_lbp_svm(benchmark::State& s) { run(s, nullptr, "lbp_svm"); }
void BM_Identity_lbp_tt(benchmark::State& s) { run(s, nullptr, "lbp_tt"); }
void BM_Identity_face_api(benchmark::State& s) { run(s, nullptr, "face_api"); }
void BM_Both_classical(benchmark::State& s) { run(s, "lbp_hog", "lbp_tt"); }
void BM_Both_seed(benchmark::State& s) { run(s, "lbp_svm", "lbp_svm"); }
BENCHMARK(BM_Expression_lbp_svm)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Expression_lbp_hog)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Expression_face_api)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Expression_face_api_no_flip)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Identity_lbp_svm)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Identity_lbp_tt)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Identity_face_api)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Both_classical)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Both_seed)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Both_pipeline_default)->Unit(benchmark::kMillisecond)->Iterations(500);

}  // namespace

BENCHMARK_MAIN();
