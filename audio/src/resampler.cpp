#include "dreamsense/audio/resampler.hpp"

#include <algorithm>
#include <cmath>
#include <soxr.h>
#include <string>

namespace dreamsense::audio {

Status ResamplerOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (input_rate <= 0) add(fmt::format("input_rate must be > 0 (is {})", input_rate));
  if (output_rate <= 0) add(fmt::format("output_rate must be > 0 (is {})", output_rate));
  if (channels < 1 || channels > 64)
    add(fmt::format("channels must be in [1, 64] (is {})", channels));
  if (max_jitter < Duration()) add("max_jitter must be >= 0");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "ResamplerOptions: {}", bad);
  return ok_status();
}

struct Resampler::Impl {
  soxr_t soxr = nullptr;
  std::vector<float> out;  // output scratch
  ~Impl() {
    if (soxr != nullptr) soxr_delete(soxr);
  }
};

namespace {

unsigned long recipe(ResamplerQuality q) {
  switch (q) {
    case ResamplerQuality::kQuick:
      return SOXR_QQ;
    case ResamplerQuality::kLow:
      return SOXR_LQ;
    case ResamplerQuality::kMedium:
      return SOXR_MQ;
    case ResamplerQuality::kHigh:
      return SOXR_HQ;
    case ResamplerQuality::kVeryHigh:
      return SOXR_VHQ;
  }
  return SOXR_HQ;
}

}  // namespace

Resampler::Resampler(ResamplerOptions options, std::unique_ptr<Impl> impl)
    : options_(options), impl_(std::move(impl)) {}
Resampler::~Resampler() = default;

Result<std::unique_ptr<Resampler>> Resampler::create(const ResamplerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto impl = std::make_unique<Impl>();
  soxr_error_t err = nullptr;
  const soxr_io_spec_t io = soxr_io_spec(SOXR_FLOAT32_I, SOXR_FLOAT32_I);
  const soxr_quality_spec_t q = soxr_quality_spec(recipe(options.quality), 0);
  const soxr_runtime_spec_t rt = soxr_runtime_spec(1);  // one thread: the pipeline owns the cores
  impl->soxr = soxr_create(options.input_rate, options.output_rate,
                           static_cast<unsigned>(options.channels), &err, &io, &q, &rt);
  if (err != nullptr || impl->soxr == nullptr)
    return make_error(ErrorCode::kInternal, "resampler: soxr_create({} Hz -> {} Hz, {} ch): {}",
                      options.input_rate, options.output_rate, options.channels,
                      err != nullptr ? err : "unknown error");
  return std::unique_ptr<Resampler>(new Resampler(options, std::move(impl)));
}

Status Resampler::process(std::span<const float> interleaved, Timestamp stamp,
                          std::vector<StampedAudio>& out) {
  if (interleaved.size() % static_cast<size_t>(options_.channels) != 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "resampler: {} values is not a whole number of {}-channel frames",
                      interleaved.size(), options_.channels);
  return feed(interleaved.data(), static_cast<int64_t>(interleaved.size()) / options_.channels,
              stamp, out);
}

Status Resampler::process(std::span<const int16_t> interleaved, Timestamp stamp,
                          std::vector<StampedAudio>& out) {
  scratch_.resize(interleaved.size());
  for (size_t i = 0; i < interleaved.size(); ++i) scratch_[i] = interleaved[i] * (1.f / 32768.f);
  return process(std::span<const float>(scratch_), stamp, out);
}

Status Resampler::feed(const float* data, int64_t frames, Timestamp stamp,
                       std::vector<StampedAudio>& out) {
  if (!stamp.is_set() || stamp.is_special())
    return make_error(ErrorCode::kInvalidArgument, "resampler: input chunk has no stamp");
  if (origin_.is_set()) {
    const Timestamp expected = origin_ + frames_to_duration(in_frames_, options_.input_rate);
    if ((stamp - expected).abs() > options_.max_jitter) {
      if (auto s = flush(out); !s) return s;
    }
  }
  if (!origin_.is_set()) {
    origin_ = stamp;
    in_frames_ = out_frames_ = 0;
  }
  if (frames == 0) return ok_status();
  const double ratio = static_cast<double>(options_.output_rate) / options_.input_rate;
  const size_t ch = static_cast<size_t>(options_.channels);
  const size_t olen = static_cast<size_t>(std::ceil(static_cast<double>(frames) * ratio)) + 64;
  impl_->out.resize(olen * ch);
  StampedAudio block;
  block.stamp = origin_ + frames_to_duration(out_frames_, options_.output_rate);
  block.audio.sample_rate = options_.output_rate;
  block.audio.channels = options_.channels;
  size_t consumed = 0;
  while (true) {
    size_t idone = 0, odone = 0;
    soxr_error_t err =
        soxr_process(impl_->soxr, data + consumed * ch, static_cast<size_t>(frames) - consumed,
                     &idone, impl_->out.data(), olen, &odone);
    if (err != nullptr) return make_error(ErrorCode::kInternal, "resampler: soxr_process: {}", err);
    consumed += idone;
    block.audio.samples.insert(block.audio.samples.end(), impl_->out.begin(),
                               impl_->out.begin() + static_cast<std::ptrdiff_t>(odone * ch));
    if (consumed >= static_cast<size_t>(frames) && odone < olen) break;
  }
  in_frames_ += frames;
  out_frames_ += block.audio.frames();
  if (!block.audio.samples.empty()) out.push_back(std::move(block));
  return ok_status();
}

Status Resampler::drain(std::vector<StampedAudio>& out) {
  const size_t ch = static_cast<size_t>(options_.channels);
  const size_t olen = 4096;
  impl_->out.resize(olen * ch);
  StampedAudio block;
  block.stamp = origin_ + frames_to_duration(out_frames_, options_.output_rate);
  block.audio.sample_rate = options_.output_rate;
  block.audio.channels = options_.channels;
  // The segment's exact length: round(n * out / in) samples (soxr's own count; enforced so that
  // stamps and lengths can never drift, whatever the library version does at the very end).
  const int64_t total = static_cast<int64_t>(
      std::llround(static_cast<double>(in_frames_) * options_.output_rate / options_.input_rate));
  while (true) {
    size_t odone = 0;
    soxr_error_t err =
        soxr_process(impl_->soxr, nullptr, 0, nullptr, impl_->out.data(), olen, &odone);
    if (err != nullptr)
      return make_error(ErrorCode::kInternal, "resampler: soxr_process (flush): {}", err);
    block.audio.samples.insert(block.audio.samples.end(), impl_->out.begin(),
                               impl_->out.begin() + static_cast<std::ptrdiff_t>(odone * ch));
    if (odone == 0) break;
  }
  const int64_t have = out_frames_ + block.audio.frames();
  if (have > total) {
    const int64_t keep = std::max<int64_t>(0, block.audio.frames() - (have - total));
    block.audio.samples.resize(static_cast<size_t>(keep) * ch);
  } else if (have < total) {
    block.audio.samples.resize(block.audio.samples.size() + static_cast<size_t>(total - have) * ch,
                               0.f);
  }
  out_frames_ += block.audio.frames();
  if (!block.audio.samples.empty()) out.push_back(std::move(block));
  return ok_status();
}

Status Resampler::flush(std::vector<StampedAudio>& out) {
  if (origin_.is_set() && in_frames_ > 0)
    if (auto s = drain(out); !s) return s;
  reset();
  return ok_status();
}

void Resampler::reset() {
  soxr_clear(impl_->soxr);
  origin_ = Timestamp::unset();
  in_frames_ = out_frames_ = 0;
}

Result<std::vector<float>> Resampler::convert(std::span<const float> interleaved, int channels,
                                              int input_rate, int output_rate,
                                              ResamplerQuality quality) {
  ResamplerOptions o;
  o.input_rate = input_rate;
  o.output_rate = output_rate;
  o.channels = channels;
  o.quality = quality;
  auto r = create(o);
  if (!r) return tl::unexpected(r.error());
  std::vector<StampedAudio> blocks;
  if (auto s = (*r)->process(interleaved, Timestamp::from_ns(0), blocks); !s)
    return tl::unexpected(s.error());
  if (auto s = (*r)->flush(blocks); !s) return tl::unexpected(s.error());
  std::vector<float> out;
  for (const auto& b : blocks)
    out.insert(out.end(), b.audio.samples.begin(), b.audio.samples.end());
  return out;
}

}  // namespace dreamsense::audio
