// Face detection latency on real demo frames, three 1280x960 cameras per tick: full-frame search
// of every camera versus the analyser (ROI tracking, frontalness, selection).
// Frames: the session in $DREAMSENSE_FACE_BENCH_SESSION, else a 2 s demo (seed 1) generated into
// a temporary folder. JPEG decoding happens before the timed region.
// Run: <build>/bench/face_detection_bench

#include "dreamsense/face_detection/face_detection_analyzer.hpp"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <unistd.h>

#include "../test/demo_frames.hpp"

namespace dreamsense::face_detection {
namespace {

const testing::DemoFrames& frames() {
  static const testing::DemoFrames f = [] {
    const char* env = std::getenv("DREAMSENSE_FACE_BENCH_SESSION");
    std::filesystem::path dir = env != nullptr ? std::filesystem::path(env)
                                               : std::filesystem::temp_directory_path() /
                                                     ("ds_face_bench_" + std::to_string(getpid()));
    Result<testing::DemoFrames> r = tl::unexpected(Error{});
    if (auto made = testing::ensure_demo(dir, 2.0, 1); !made)
      r = tl::unexpected(made.error());
    else
      r = testing::load_demo(dir, 50);
    if (env == nullptr) std::filesystem::remove_all(dir);
    if (!r) {
      std::fprintf(stderr, "%s\n", r.error().to_string().c_str());
      std::exit(1);
    }
    return std::move(*r);
  }();
  return f;
}

void BM_FullFrameAllCameras(benchmark::State& state) {
  FaceDetectorOptions o;
  o.estimate_frontalness = state.range(0) != 0;
  auto d = FaceDetector::create(o);
  if (!d) return state.SkipWithError(d.error().message.c_str());
  const auto& ticks = frames().ticks;
  size_t i = 0, faces = 0;
  for (auto _ : state) {
    for (const auto& [id, f] : ticks[i % ticks.size()].frames)
      faces += d->detect(f->as<ColorImage>()->image).size();
    ++i;
  }
  state.counters["faces_per_tick"] = static_cast<double>(faces) / std::max<size_t>(1, i);
  state.SetLabel(o.estimate_frontalness ? "with frontalness" : "detection only");
}
BENCHMARK(BM_FullFrameAllCameras)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The pieces, for one camera (camera_middle): ROI search around the face, frontalness of it.
void BM_OneCameraPieces(benchmark::State& state) {
  FaceDetectorOptions o;
  o.estimate_frontalness = false;
  auto d = FaceDetector::create(o);
  if (!d) return state.SkipWithError(d.error().message.c_str());
  const auto& ticks = frames().ticks;
  std::vector<cv::Rect2d> boxes;
  for (const auto& t : ticks) {
    auto f = d->detect(t.frame("camera_middle")->as<ColorImage>()->image);
    boxes.push_back(f.empty() ? cv::Rect2d(560, 440, 180, 180) : f[0].box_px);
  }
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % ticks.size();
    const cv::Mat& image = ticks[k].frame("camera_middle")->as<ColorImage>()->image;
    const cv::Rect2d& b = boxes[k];
    if (state.range(0) == 0) {
      const double s = std::max(b.width, b.height), m = 0.75 * s;
      benchmark::DoNotOptimize(d->detect(
          image,
          SearchRegion{cv::Rect(cv::Rect2d(b.x - m, b.y - m, b.width + 2 * m, b.height + 2 * m)),
                       0.6 * s, 1.6 * s}));
    } else if (state.range(0) == 1) {
      benchmark::DoNotOptimize(d->frontalness(image, b));
    } else {
      benchmark::DoNotOptimize(d->detect(image));
    }
  }
  state.SetLabel(state.range(0) == 0   ? "roi search"
                 : state.range(0) == 1 ? "frontalness"
                                       : "full search");
}
BENCHMARK(BM_OneCameraPieces)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_AnalyzerRoiTracked(benchmark::State& state) {
  FaceDetectionAnalyzerOptions o;
  o.parallel = state.range(0) != 0;
  auto a = make_face_detection_analyzer(o);
  if (!a) return state.SkipWithError(a.error().message.c_str());
  const auto& ticks = frames().ticks;
  Blackboard bb;
  size_t i = 0;
  for (auto _ : state) {
    // Give every tick a distinct sequence so that wrapping around is not "the same frame".
    MultiFrame mf = ticks[i % ticks.size()];
    for (auto& [id, f] : mf.frames) {
      SensorFrame copy = *f;
      copy.sequence = i;
      f = std::make_shared<const SensorFrame>(std::move(copy));
    }
    BlackboardWriter w("face_detection");
    auto s = (*a)->process(mf, bb.snapshot(), w);
    if (!s) return state.SkipWithError(s.error().message.c_str());
    bb.commit(w, mf.stamp);
    ++i;
  }
  state.SetLabel(o.parallel ? "parallel over cameras" : "serial");
}
BENCHMARK(BM_AnalyzerRoiTracked)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dreamsense::face_detection

BENCHMARK_MAIN();
