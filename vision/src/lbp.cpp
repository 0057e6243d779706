#include "dreamsense/vision/lbp.hpp"

#include "dreamsense/core/status.hpp"

#include <array>
#include <cmath>
#include <limits>

namespace dreamsense::vision {
namespace {

std::array<uint8_t, 256> make_uniform_table() {
  std::array<uint8_t, 256> table{};
  int next = 0;
  for (unsigned code = 0; code < 256; ++code) {
    int transitions = 0;
    for (int b = 0; b < 8; ++b) transitions += ((code >> b) & 1u) != ((code >> ((b + 1) % 8)) & 1u);
    table[code] = static_cast<uint8_t>(transitions <= 2 ? next++ : kUniformLbpBins - 1);
  }
  return table;
}

const std::array<uint8_t, 256>& uniform_table() {
  static const std::array<uint8_t, 256> table = make_uniform_table();
  return table;
}

template <typename T>
cv::Mat codes_impl(const cv::Mat& src, double radius) {
  const int r = static_cast<int>(std::ceil(radius - 1e-9));
  if (src.rows <= 2 * r || src.cols <= 2 * r) return {};
  cv::Mat dst(src.rows - 2 * r, src.cols - 2 * r, CV_8UC1, cv::Scalar(0));
  constexpr float kEps = std::numeric_limits<float>::epsilon();
  for (int n = 0; n < 8; ++n) {
    // Sample point, rounded so that cos(pi/2) = 6e-17 does not straddle a pixel boundary.
    const double x = std::round(radius * std::cos(2.0 * CV_PI * n / 8) * 1e9) / 1e9;
    const double y = std::round(-radius * std::sin(2.0 * CV_PI * n / 8) * 1e9) / 1e9;
    const int fx = static_cast<int>(std::floor(x)), fy = static_cast<int>(std::floor(y));
    const int cx = static_cast<int>(std::ceil(x)), cy = static_cast<int>(std::ceil(y));
    const float tx = static_cast<float>(x - fx), ty = static_cast<float>(y - fy);
    const float w1 = (1 - tx) * (1 - ty), w2 = tx * (1 - ty), w3 = (1 - tx) * ty, w4 = tx * ty;
    const uint8_t bit = static_cast<uint8_t>(1u << n);
    for (int i = r; i < src.rows - r; ++i) {
      const T* c_row = src.ptr<T>(i);
      const T* f_row = src.ptr<T>(i + fy);
      const T* e_row = src.ptr<T>(i + cy);
      uint8_t* d = dst.ptr<uint8_t>(i - r);
      for (int j = r; j < src.cols - r; ++j) {
        const float t =
            w1 * static_cast<float>(f_row[j + fx]) + w2 * static_cast<float>(f_row[j + cx]) +
            w3 * static_cast<float>(e_row[j + fx]) + w4 * static_cast<float>(e_row[j + cx]);
        const float c = static_cast<float>(c_row[j]);
        if (t > c || std::abs(t - c) < kEps) d[j - r] |= bit;
      }
    }
  }
  return dst;
}

}  // namespace

int uniform_lbp_label(unsigned code) { return uniform_table()[code & 0xffu]; }

cv::Mat lbp_codes(const cv::Mat& grey, double radius) {
  DS_CHECK(radius > 0);
  if (grey.type() == CV_8UC1) return codes_impl<uint8_t>(grey, radius);
  DS_CHECK_EQ(grey.type(), CV_32FC1);
  return codes_impl<float>(grey, radius);
}

cv::Mat uniform_lbp_labels(const cv::Mat& grey, double radius) {
  cv::Mat codes = lbp_codes(grey, radius);
  const auto& table = uniform_table();
  for (int i = 0; i < codes.rows; ++i) {
    uint8_t* p = codes.ptr<uint8_t>(i);
    for (int j = 0; j < codes.cols; ++j) p[j] = table[p[j]];
  }
  return codes;
}

void grid_histograms(const cv::Mat& labels, int bins, int grid_cols, int grid_rows,
                     bool sqrt_normalise, std::vector<float>& out) {
  DS_CHECK(labels.empty() || labels.type() == CV_8UC1);
  DS_CHECK(bins > 0 && bins <= 256 && grid_cols > 0 && grid_rows > 0);
  std::vector<float> h(static_cast<size_t>(bins));
  for (int gy = 0; gy < grid_rows; ++gy) {
    for (int gx = 0; gx < grid_cols; ++gx) {
      std::fill(h.begin(), h.end(), 0.f);
      const int y0 = gy * labels.rows / grid_rows, y1 = (gy + 1) * labels.rows / grid_rows;
      const int x0 = gx * labels.cols / grid_cols, x1 = (gx + 1) * labels.cols / grid_cols;
      int count = 0;
      for (int y = y0; y < y1; ++y) {
        const uint8_t* p = labels.ptr<uint8_t>(y);
        for (int x = x0; x < x1; ++x) {
          DS_CHECK_LT(static_cast<int>(p[x]), bins);
          h[p[x]] += 1.f;
          ++count;
        }
      }
      for (float& v : h) {
        if (count > 0) v /= static_cast<float>(count);
        if (sqrt_normalise) v = std::sqrt(v);
      }
      out.insert(out.end(), h.begin(), h.end());
    }
  }
}

}  // namespace dreamsense::vision
