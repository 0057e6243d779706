#include "dreamsense/audio/audio_file.hpp"

#include "dreamsense/audio/resampler.hpp"

#include <sndfile.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <soxr.h>
#include <string>
#include <system_error>

namespace dreamsense::audio {
namespace fs = std::filesystem;

namespace {

bool is_raw(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e == ".raw";
}

struct SndFile {
  SNDFILE* f = nullptr;
  SF_INFO info{};
  ~SndFile() {
    if (f) sf_close(f);
  }
};

Status open(const fs::path& path, int raw_sample_rate, SndFile& s) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    return make_error(ErrorCode::kNotFound, "{}: audio file missing", path.string());
  if (is_raw(path)) {
    if (raw_sample_rate <= 0)
      return make_error(ErrorCode::kInvalidArgument, "{}: headerless audio needs a sample rate",
                        path.string());
    s.info.samplerate = raw_sample_rate;
    s.info.channels = 1;
    s.info.format = SF_FORMAT_RAW | SF_FORMAT_PCM_16 | SF_ENDIAN_LITTLE;
  }
  s.f = sf_open(path.string().c_str(), SFM_READ, &s.info);
  if (!s.f)
    return make_error(ErrorCode::kCorruptData, "{}: cannot read audio ({})", path.string(),
                      sf_strerror(nullptr));
  if (s.info.channels <= 0 || s.info.samplerate <= 0)
    return make_error(ErrorCode::kCorruptData, "{}: no audio channels", path.string());
  return ok_status();
}

}  // namespace

Result<AudioFileInfo> audio_file_info(const fs::path& path, int raw_sample_rate) {
  SndFile s;
  DS_RETURN_IF_ERROR(open(path, raw_sample_rate, s));
  return AudioFileInfo{s.info.samplerate, s.info.channels, static_cast<int64_t>(s.info.frames)};
}

Result<AudioClip> read_audio(const fs::path& path, const ReadAudioOptions& options) {
  SndFile s;
  DS_RETURN_IF_ERROR(open(path, options.raw_sample_rate, s));
  const int ch = s.info.channels;
  if ((options.require_mono && ch != 1) ||
      (options.expected_sample_rate > 0 && s.info.samplerate != options.expected_sample_rate))
    return make_error(ErrorCode::kUnsupported, "{}: expected {}{} Hz, got {} channels {} Hz",
                      path.string(), options.require_mono ? "mono " : "",
                      options.expected_sample_rate > 0
                          ? std::to_string(options.expected_sample_rate)
                          : std::string("any"),
                      ch, s.info.samplerate);
  if (options.channel >= ch)
    return make_error(ErrorCode::kInvalidArgument, "{}: has {} channel(s), channel {} asked for",
                      path.string(), ch, options.channel);
  std::vector<float> all(static_cast<size_t>(s.info.frames) * static_cast<size_t>(ch));
  const sf_count_t got = std::max<sf_count_t>(0, sf_readf_float(s.f, all.data(), s.info.frames));
  all.resize(static_cast<size_t>(got) * static_cast<size_t>(ch));
  AudioClip clip;
  clip.sample_rate = s.info.samplerate;
  if (options.channel < 0 || ch == 1) {
    clip.channels = ch;
    clip.samples = std::move(all);
  } else {
    clip.channels = 1;
    clip.samples.resize(static_cast<size_t>(got));
    for (size_t i = 0; i < clip.samples.size(); ++i)
      clip.samples[i] = all[i * static_cast<size_t>(ch) + static_cast<size_t>(options.channel)];
  }
  if (options.resample_to_hz > 0 && options.resample_to_hz != clip.sample_rate) {
    auto converted = Resampler::convert(clip.samples, clip.channels, clip.sample_rate,
                                        options.resample_to_hz, ResamplerQuality::kVeryHigh);
    if (!converted)
      return make_error(converted.error().code, "{}: {}", path.string(), converted.error().message);
    clip.samples = std::move(*converted);
    clip.sample_rate = options.resample_to_hz;
  }
  return clip;
}

std::vector<int16_t> to_pcm16(std::span<const float> samples) {
  std::vector<int16_t> out(samples.size());
  for (size_t i = 0; i < samples.size(); ++i)
    out[i] = static_cast<int16_t>(
        std::clamp(std::lround(static_cast<double>(samples[i]) * 32768.0), -32768L, 32767L));
  return out;
}

bool is_audio_file(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e == ".wav" || e == ".flac" || e == ".ogg" || e == ".raw";
}

std::vector<fs::path> audio_files_in(const fs::path& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && is_audio_file(e.path())) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

std::vector<int16_t> resample_soxr(std::span<const int16_t> in, int from_hz, int to_hz) {
  const size_t n_out =
      static_cast<size_t>(std::floor(static_cast<double>(in.size()) * to_hz / from_hz));
  std::vector<int16_t> out(n_out + 64);
  size_t done = 0;
  // Very high quality, linear phase; soxr_oneshot compensates the filter delay and flushes.
  soxr_io_spec_t io = soxr_io_spec(SOXR_INT16_I, SOXR_INT16_I);
  io.flags |= SOXR_NO_DITHER;  // deterministic output
  const soxr_quality_spec_t q = soxr_quality_spec(SOXR_VHQ | SOXR_LINEAR_PHASE, 0);
  const soxr_error_t err = soxr_oneshot(from_hz, to_hz, 1, in.data(), in.size(), nullptr,
                                        out.data(), out.size(), &done, &io, &q, nullptr);
  if (err) done = 0;  // only on allocation failure; never for valid rates
  out.resize(done);
  out.resize(n_out, 0);
  return out;
}

std::vector<int16_t> resample_sinc(std::span<const int16_t> in, int from_hz, int to_hz) {
  constexpr int kZeros = 32;
  constexpr double kBeta = 8.0;
  const double ratio = static_cast<double>(to_hz) / from_hz;
  const double cutoff = std::min(1.0, ratio);  // fraction of the input Nyquist
  const size_t n_out = static_cast<size_t>(std::floor(in.size() * ratio));
  auto bessel_i0 = [](double x) {
    double sum = 1, term = 1;
    for (int k = 1; k < 30; ++k) {
      term *= (x / (2 * k)) * (x / (2 * k));
      sum += term;
    }
    return sum;
  };
  const double i0_beta = bessel_i0(kBeta);
  const double half_width = kZeros / cutoff;  // in input samples
  std::vector<int16_t> out(n_out);
  for (size_t i = 0; i < n_out; ++i) {
    const double t = i / ratio;  // position in input samples
    const long lo = static_cast<long>(std::ceil(t - half_width));
    const long hi = static_cast<long>(std::floor(t + half_width));
    double acc = 0;
    for (long j = std::max(0L, lo); j <= std::min<long>(static_cast<long>(in.size()) - 1, hi);
         ++j) {
      const double x = (t - j) * cutoff;
      const double sinc = x == 0 ? 1.0 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
      const double r = (t - j) / half_width;
      const double w = bessel_i0(kBeta * std::sqrt(std::max(0.0, 1 - r * r))) / i0_beta;
      acc += in[j] * cutoff * sinc * w;
    }
    out[i] = static_cast<int16_t>(std::clamp(std::lround(acc), -32768L, 32767L));
  }
  return out;
}

}  // namespace

std::vector<int16_t> resample_pcm16(std::span<const int16_t> in, int from_hz, int to_hz,
                                    Pcm16Resampler method) {
  if (from_hz == to_hz || in.empty() || from_hz <= 0 || to_hz <= 0) return {in.begin(), in.end()};
  return method == Pcm16Resampler::kSoxr ? resample_soxr(in, from_hz, to_hz)
                                         : resample_sinc(in, from_hz, to_hz);
}

}  // namespace dreamsense::audio
