// Eye-centre localisation: time per eye of the three methods on the synthetic BioID-layout set,
// then (same run) their accuracy under the BioID protocol (`eval eyes --method all`).
// Inputs: 100 synthetic images (seed 1) rendered in memory; face detection and landmarks run
// once before the timed region, so only the locator call is timed (one iteration = one eye).
// Accuracy: 200 synthetic images (seed 1) written to a temporary folder; set
// DREAMSENSE_EYES_BENCH_ACCURACY=0 to skip it.
// Run: <build>/bench/eye_centers_bench

#include "dreamsense/eye_centers/eye_center_locator.hpp"
#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <unistd.h>

#include "eye_eval.hpp"
#include "synthetic_eyes.hpp"

namespace dreamsense::eye_centers {
namespace {

struct Eye {
  const cv::Mat* image;
  std::array<cv::Point2d, 6> contour;
};

struct Inputs {
  std::vector<cv::Mat> images;
  std::vector<Eye> eyes;
};

const Inputs& inputs() {
  static const Inputs in = [] {
    Inputs r;
    auto renderer = SyntheticEyeRenderer::create(SyntheticEyeSetOptions{});
    face_detection::FaceDetectorOptions fo;
    fo.min_face_px = 40;
    fo.detection_width = 640;
    fo.estimate_frontalness = false;
    auto det = face_detection::FaceDetector::create(fo);
    auto lm = face_landmarks::make_dlib_landmarker();
    if (!renderer || !det || !lm) {
      std::fprintf(stderr, "eye_centers_bench: portrait, cascade or dlib model missing\n");
      std::exit(1);
    }
    r.images.reserve(100);
    for (int i = 0; i < 100; ++i) r.images.push_back(renderer->render(i).grey);
    for (const cv::Mat& img : r.images) {
      const auto faces = det->detect(img);
      if (faces.empty()) continue;
      auto pts = (*lm)->fit(img, faces.front().box_px);
      if (!pts || !*pts) continue;
      for (int base : {36, 42}) {
        Eye e{&img, {}};
        for (int k = 0; k < 6; ++k) e.contour[k] = (**pts)[base + k];
        r.eyes.push_back(e);
      }
    }
    return r;
  }();
  return in;
}

// The improved operator's previous default (limbus stage only, exhaustive candidate search, iris
// radius prior from 0.12 x width, no closed-eye test), for before/after timing in one run.
EyeCenterLocatorOptions previous_improved() {
  EyeCenterLocatorOptions o;
  o.region.min_iris_radius = 0.12;
  o.improved.pupil.enabled = false;
  o.improved.coarse_step = 1;
  o.improved.min_step_of_range = 0;
  return o;
}

constexpr int kPrevious = 100;  // BM_LocateEye argument: previous_improved()

void BM_LocateEye(benchmark::State& state) {
  EyeCenterLocatorOptions o;
  if (state.range(0) == kPrevious)
    o = previous_improved();
  else
    o.method = static_cast<EyeCenterMethod>(state.range(0));
  auto loc = EyeCenterLocator::create(o);
  if (!loc) return state.SkipWithError(loc.error().message.c_str());
  const auto& eyes = inputs().eyes;
  if (eyes.empty()) return state.SkipWithError("no eyes (face detection failed everywhere)");
  size_t i = 0, found = 0;
  for (auto _ : state) {
    const Eye& e = eyes[i++ % eyes.size()];
    auto r = loc->locate(*e.image, e.contour);
    found += r && r->found;
    benchmark::DoNotOptimize(r);
  }
  state.counters["found"] =
      static_cast<double>(found) / static_cast<double>(std::max<size_t>(1, i));
  state.SetLabel(state.range(0) == kPrevious ? std::string("improved (previous default)")
                                             : std::string(to_string(o.method)));
}
BENCHMARK(BM_LocateEye)
    ->Arg(static_cast<int>(EyeCenterMethod::kImprovedIntegroDifferential))
    ->Arg(kPrevious)
    ->Arg(static_cast<int>(EyeCenterMethod::kDaugman))
    ->Arg(static_cast<int>(EyeCenterMethod::kTimmBarth))
    ->Unit(benchmark::kMillisecond);

void print_accuracy() {
  const char* env = std::getenv("DREAMSENSE_EYES_BENCH_ACCURACY");
  if (env != nullptr && std::strcmp(env, "0") == 0) return;
  EyeEvalOptions o;
  o.dataset = "synthetic-eyes";
  o.dir = std::filesystem::temp_directory_path() /
          fmt::format("ds_eyes_bench_{}", static_cast<long>(::getpid()));
  o.generate = SyntheticEyeSetOptions{};
  o.generate->count = 200;
  o.methods = {"all"};
  auto r = run_eye_eval(o);
  // The previous default of the improved operator on the same (already written) set.
  EyeEvalOptions prev = o;
  prev.generate.reset();
  prev.methods = {"improved"};
  prev.locator = previous_improved();
  auto rp = r ? run_eye_eval(prev) : r;
  std::filesystem::remove_all(o.dir);
  if (!r || !rp) {
    std::fprintf(stderr, "accuracy: %s\n", (r ? rp : r).error().to_string().c_str());
    return;
  }
  (*r)["methods"].push_back("improved (previous default)");
  (*r)["metrics"]["improved (previous default)"] =
      (*rp)["metrics"]["improved_integro_differential"];
  (*r)["timing"]["improved (previous default)"] = (*rp)["timing"]["improved_integro_differential"];
  std::printf(
      "\nAccuracy, BioID protocol on %d synthetic images (seed 1), e = max eye error / "
      "inter-ocular:\n%-31s %8s %8s %8s %9s %11s\n",
      o.generate->count, "method", "e<=0.05", "e<=0.10", "e<=0.25", "median_e", "ms_per_eye");
  for (const auto& jm : (*r)["methods"]) {
    const std::string m = jm.get<std::string>();
    const auto& x = (*r)["metrics"][m];
    const auto& t = (*r)["timing"][m];
    std::printf("%-31s %8.3f %8.3f %8.3f %9.4f %11.3f\n", m.c_str(), x["acc_e005"].get<double>(),
                x["acc_e010"].get<double>(), x["acc_e025"].get<double>(),
                x["median_e"].is_null() ? -1.0 : x["median_e"].get<double>(),
                t["ms_per_eye_median"].is_null() ? -1.0 : t["ms_per_eye_median"].get<double>());
  }
}

}  // namespace
}  // namespace dreamsense::eye_centers

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  dreamsense::eye_centers::print_accuracy();
  return 0;
}
