#include "dreamsense/audio/fft.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <thread>
#include <vector>

namespace dreamsense::audio {
namespace {

TEST(RealFft, SineLandsInItsBinAndInverseRestoresTheSignal) {
  RealFft fft(64);
  ASSERT_EQ(fft.bins(), 33);
  for (int i = 0; i < 64; ++i) fft.real()[i] = std::cos(2 * std::numbers::pi * 5 * i / 64);
  fft.forward();
  EXPECT_NEAR(std::abs(fft.spectrum()[5]), 32.0, 1e-9);
  EXPECT_NEAR(std::abs(fft.spectrum()[4]), 0.0, 1e-9);
  fft.inverse();
  for (int i = 0; i < 64; ++i)
    EXPECT_NEAR(fft.real()[i] / 64, std::cos(2 * std::numbers::pi * 5 * i / 64), 1e-12);
}

TEST(RealFft, OtherAlignedBuffersGiveTheSameSpectrum) {
  RealFft fft(48);  // not a power of two
  AlignedReal in = aligned_real(48);
  AlignedComplex out = aligned_complex(fft.bins());
  for (int i = 0; i < 48; ++i) in[i] = fft.real()[i] = std::sin(0.3 * i) + 0.1 * i;
  fft.forward();
  fft.forward(in.get(), out.get());
  for (int k = 0; k < fft.bins(); ++k) EXPECT_EQ(out[k], fft.spectrum()[k]);
}

TEST(RealFft, ObjectsOfManySizesOnManyThreadsAgree) {
  // Plans are made once per size under the cache's lock; concurrent construction must neither
  // crash nor change results.
  std::vector<double> reference;
  {
    RealFft f(256);
    for (int i = 0; i < 256; ++i) f.real()[i] = std::sin(0.1 * i);
    f.forward();
    for (int k = 0; k < f.bins(); ++k) reference.push_back(std::abs(f.spectrum()[k]));
  }
  std::vector<int> bad(8, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([t, &bad, &reference] {
      for (int rep = 0; rep < 20; ++rep) {
        RealFft other(100 + 7 * t + rep);  // new sizes: planning races if unguarded
        RealFft f(256);
        for (int i = 0; i < 256; ++i) f.real()[i] = std::sin(0.1 * i);
        f.forward();
        for (int k = 0; k < f.bins(); ++k)
          if (std::abs(std::abs(f.spectrum()[k]) - reference[static_cast<size_t>(k)]) > 1e-12)
            ++bad[static_cast<size_t>(t)];
      }
    });
  for (auto& th : threads) th.join();
  for (int b : bad) EXPECT_EQ(b, 0);
}

}  // namespace
}  // namespace dreamsense::audio
