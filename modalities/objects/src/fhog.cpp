// fHOG (Felzenszwalb et al. 2010), see the header. Written for small patches called many times
// per frame (the trackers' windows and scale samples): scratch buffers are reused per thread.

#include "dreamsense/objects/fhog.hpp"

#include <opencv2/core/hal/hal.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::objects {
namespace {

struct Scratch {
  std::vector<float> gx, gy, mag, ang, hist, energy;
  std::vector<int> cx0;
  std::vector<float> wx1;
};

template <typename T>
void gradients_row(const cv::Mat& img, int y, float* gx, float* gy) {
  const int h = img.rows, w = img.cols;
  const T* p = img.ptr<T>(y);
  const T* up = img.ptr<T>(std::max(y - 1, 0));
  const T* dn = img.ptr<T>(std::min(y + 1, h - 1));
  if (w == 1) {
    gx[0] = 0;
  } else {
    gx[0] = static_cast<float>(p[1]) - static_cast<float>(p[0]);
    for (int x = 1; x < w - 1; ++x)
      gx[x] = static_cast<float>(p[x + 1]) - static_cast<float>(p[x - 1]);
    gx[w - 1] = static_cast<float>(p[w - 1]) - static_cast<float>(p[w - 2]);
  }
  for (int x = 0; x < w; ++x) gy[x] = static_cast<float>(dn[x]) - static_cast<float>(up[x]);
}

}  // namespace

void compute_fhog(const cv::Mat& grey, int cell, float* out) {
  CV_Assert(cell >= 1 && grey.channels() == 1 && (grey.depth() == CV_8U || grey.depth() == CV_32F));
  const int h = grey.rows, w = grey.cols;
  const int hc = h / cell, wc = w / cell;
  if (hc < 1 || wc < 1) return;
  thread_local Scratch s;
  s.gx.resize(static_cast<size_t>(w));
  s.gy.resize(static_cast<size_t>(w));
  s.mag.resize(static_cast<size_t>(w));
  s.ang.resize(static_cast<size_t>(w));
  s.hist.assign(static_cast<size_t>(hc) * wc * 18, 0.f);
  s.energy.resize(static_cast<size_t>(hc) * wc);
  // Horizontal cell coordinates and weights, the same for every row.
  s.cx0.resize(static_cast<size_t>(w));
  s.wx1.resize(static_cast<size_t>(w));
  const float inv_cell = 1.f / static_cast<float>(cell);
  for (int x = 0; x < w; ++x) {
    const float fx = (static_cast<float>(x) + 0.5f) * inv_cell - 0.5f;
    const int c0 = static_cast<int>(std::floor(fx));
    s.cx0[static_cast<size_t>(x)] = c0;
    s.wx1[static_cast<size_t>(x)] = fx - static_cast<float>(c0);
  }
  const float bins_per_deg = 18.f / 360.f;
  float* hist = s.hist.data();
  for (int y = 0; y < h; ++y) {
    if (grey.depth() == CV_8U)
      gradients_row<uchar>(grey, y, s.gx.data(), s.gy.data());
    else
      gradients_row<float>(grey, y, s.gx.data(), s.gy.data());
    cv::hal::magnitude32f(s.gx.data(), s.gy.data(), s.mag.data(), w);
    cv::hal::fastAtan32f(s.gy.data(), s.gx.data(), s.ang.data(), w, true);
    const float fy = (static_cast<float>(y) + 0.5f) * inv_cell - 0.5f;
    const int cy0 = static_cast<int>(std::floor(fy));
    const float wy1 = fy - static_cast<float>(cy0), wy0 = 1.f - wy1;
    float* row0 = cy0 >= 0 ? hist + static_cast<size_t>(cy0) * wc * 18 : nullptr;
    float* row1 = cy0 + 1 < hc ? hist + static_cast<size_t>(cy0 + 1) * wc * 18 : nullptr;
    for (int x = 0; x < w; ++x) {
      const float m = s.mag[static_cast<size_t>(x)];
      if (m <= 0) continue;
      const float o = s.ang[static_cast<size_t>(x)] * bins_per_deg;
      int o0 = static_cast<int>(o);
      const float wo1 = o - static_cast<float>(o0), wo0 = 1.f - wo1;
      if (o0 >= 18) o0 -= 18;
      const int o1 = o0 + 1 == 18 ? 0 : o0 + 1;
      const int cx = s.cx0[static_cast<size_t>(x)];
      const float wx1 = s.wx1[static_cast<size_t>(x)], wx0 = 1.f - wx1;
      const float a0 = m * wo0, a1 = m * wo1;
      const bool left = cx >= 0, right = cx + 1 < wc;
      if (row0) {
        if (left) {
          float* hh = row0 + static_cast<size_t>(cx) * 18;
          const float k = wy0 * wx0;
          hh[o0] += a0 * k;
          hh[o1] += a1 * k;
        }
        if (right) {
          float* hh = row0 + static_cast<size_t>(cx + 1) * 18;
          const float k = wy0 * wx1;
          hh[o0] += a0 * k;
          hh[o1] += a1 * k;
        }
      }
      if (row1) {
        if (left) {
          float* hh = row1 + static_cast<size_t>(cx) * 18;
          const float k = wy1 * wx0;
          hh[o0] += a0 * k;
          hh[o1] += a1 * k;
        }
        if (right) {
          float* hh = row1 + static_cast<size_t>(cx + 1) * 18;
          const float k = wy1 * wx1;
          hh[o0] += a0 * k;
          hh[o1] += a1 * k;
        }
      }
    }
  }
  // Energy of the contrast-insensitive histogram per cell.
  for (int c = 0; c < hc * wc; ++c) {
    const float* hh = hist + static_cast<size_t>(c) * 18;
    float e = 0;
    for (int o = 0; o < 9; ++o) {
      const float u = hh[o] + hh[o + 9];
      e += u * u;
    }
    s.energy[static_cast<size_t>(c)] = e;
  }
  const float* energy = s.energy.data();
  auto E = [&](int cy, int cx) {
    cy = std::clamp(cy, 0, hc - 1);
    cx = std::clamp(cx, 0, wc - 1);
    return energy[static_cast<size_t>(cy) * wc + cx];
  };
  const size_t plane = static_cast<size_t>(hc) * wc;
  constexpr float kEps = 1e-4f, kTrunc = 0.2f;
  for (int cy = 0; cy < hc; ++cy)
    for (int cx = 0; cx < wc; ++cx) {
      float n[4];
      int k = 0;
      for (int by = -1; by <= 0; ++by)
        for (int bx = -1; bx <= 0; ++bx)
          n[k++] = 1.f / std::sqrt(E(cy + by, cx + bx) + E(cy + by + 1, cx + bx) +
                                   E(cy + by, cx + bx + 1) + E(cy + by + 1, cx + bx + 1) + kEps);
      const float* hh = hist + (static_cast<size_t>(cy) * wc + cx) * 18;
      float* o_cell = out + static_cast<size_t>(cy) * wc + cx;
      float texture[4] = {0, 0, 0, 0};
      for (int o = 0; o < 18; ++o) {
        float sum = 0;
        for (int q = 0; q < 4; ++q) {
          const float t = std::min(hh[o] * n[q], kTrunc);
          sum += t;
          texture[q] += t;
        }
        o_cell[static_cast<size_t>(o) * plane] = 0.5f * sum;
      }
      for (int o = 0; o < 9; ++o) {
        const float u = hh[o] + hh[o + 9];
        float sum = 0;
        for (int q = 0; q < 4; ++q) sum += std::min(u * n[q], kTrunc);
        o_cell[static_cast<size_t>(18 + o) * plane] = 0.5f * sum;
      }
      for (int q = 0; q < 4; ++q)
        o_cell[static_cast<size_t>(27 + q) * plane] = 0.2357f * texture[q];
    }
}

void compute_fhog(const cv::Mat& grey, int cell, std::vector<cv::Mat>& channels, cv::Mat& storage) {
  const cv::Size c = fhog_cells(grey.size(), cell);
  channels.resize(kFhogChannels);
  if (c.width < 1 || c.height < 1) {
    for (auto& m : channels)
      m = cv::Mat::zeros(std::max(c.height, 0), std::max(c.width, 0), CV_32F);
    return;
  }
  storage.create(kFhogChannels * c.height, c.width, CV_32F);
  compute_fhog(grey, cell, storage.ptr<float>(0));
  for (int k = 0; k < kFhogChannels; ++k)
    channels[static_cast<size_t>(k)] = storage.rowRange(k * c.height, (k + 1) * c.height);
}

void compute_fhog(const cv::Mat& grey, int cell, std::vector<cv::Mat>& channels) {
  cv::Mat storage;
  compute_fhog(grey, cell, channels, storage);
}

}  // namespace dreamsense::objects
