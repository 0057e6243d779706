// Detection + identification + tracking of four toys per top-camera frame (TableTopObjects::
// process) on synthetic 640x480 table scenes, and the parts.
//   build/bin/objects_bench --benchmark_filter=TableTop

#include "dreamsense/objects/identification.hpp"
#include "dreamsense/objects/table_detector.hpp"
#include "dreamsense/objects/table_top_objects.hpp"

#include <benchmark/benchmark.h>

#include "../test/synthetic_table.hpp"

namespace {

using namespace dreamsense::objects;

std::vector<testing::Toy> toys_at(int frame) {
  const double s = 0.002 * frame;
  return {{0, {-0.33 + s, 0.27, 0.58}, 10.0 + frame},
          {1, {-0.1, 0.27, 0.62 - s}, -15},
          {2, {0.12 + s, 0.27, 0.55}, 25},
          {3, {0.35, 0.27, 0.6 + s}, -5.0 - frame}};
}

const std::vector<cv::Mat>& frames() {
  static const std::vector<cv::Mat> f = [] {
    std::vector<cv::Mat> v;
    for (int i = 0; i < 60; ++i)
      v.push_back(testing::render_table(toys_at(i), {}, static_cast<uint64_t>(i)));
    return v;
  }();
  return f;
}

std::shared_ptr<const ObjectGallery> gallery() {
  static const auto g = [] {
    std::vector<LabelledView> views;
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 8; ++i) {
        const testing::Toy t{k, {-0.3 + 0.08 * i, 0.27, 0.5 + 0.03 * i}, -40.0 + 12 * i};
        const cv::Mat img = testing::render_table({t}, {}, 50 + static_cast<uint64_t>(i));
        const cv::Rect box = cv::Rect(testing::toy_box(testing::table_camera(), t)) +
                             cv::Size(6, 6) - cv::Point(3, 3);
        auto v = make_view(img, box);
        views.push_back({k, {v->crop.clone(), v->mask.clone(), v->footprint}});
      }
    return std::make_shared<const ObjectGallery>(*ObjectGallery::enrol(dream_toy_classes(), views));
  }();
  return g;
}

void BM_TableTopObjects(benchmark::State& state) {
  (void)frames();  // rendered before timing
  auto p = TableTopObjects::create({}, gallery(), testing::table_camera(), testing::table_plane());
  size_t i = 0;
  int64_t stamp = 0;
  for (auto _ : state) {
    auto out = (*p)->process(frames()[i], stamp);
    benchmark::DoNotOptimize(out);
    stamp += 33'333'333;
    if (++i == frames().size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TableTopObjects)->Unit(benchmark::kMillisecond);

void BM_TableTopDetector(benchmark::State& state) {
  (void)frames();
  TableTopDetector d;
  size_t i = 0;
  for (auto _ : state) {
    auto out = d.detect(frames()[i]);
    benchmark::DoNotOptimize(out);
    if (++i == frames().size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TableTopDetector)->Unit(benchmark::kMillisecond);

void BM_IdentifyOneToy(benchmark::State& state, bool baseline) {
  const testing::Toy t{2, {0.1, 0.27, 0.6}, 20};
  const cv::Mat img = testing::render_table({t});
  auto v = make_view(img, cv::Rect(testing::toy_box(testing::table_camera(), t)));
  const auto g = gallery();
  for (auto _ : state) {
    auto id = baseline ? g->identify_baseline(*v) : g->identify(*v);
    benchmark::DoNotOptimize(id);
  }
}
BENCHMARK_CAPTURE(BM_IdentifyOneToy, gallery, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_IdentifyOneToy, hog_svm, true)->Unit(benchmark::kMicrosecond);

}  // namespace
