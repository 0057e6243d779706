#include "dreamsense/sources/resampling_source.hpp"

#include "dreamsense/audio/resampler.hpp"

#include <algorithm>
#include <deque>
#include <map>
#include <string>

namespace dreamsense::sources {

Status ResamplingSourceOptions::check() const {
  std::string bad;
  if (sample_rate < 1000 || sample_rate > 384000)
    bad += fmt::format("sample_rate must be in [1000, 384000] (is {})", sample_rate);
  if (quality < 0 || quality > 4)
    bad += fmt::format("{}quality must be in [0, 4] (is {})", bad.empty() ? "" : "; ", quality);
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "ResamplingSourceOptions: {}", bad);
  return ok_status();
}

struct ResamplingSource::Impl {
  ResamplingSourceOptions options;
  SourceInfo info;
  struct Stream {
    std::unique_ptr<audio::Resampler> resampler;  // created at the first chunk (its layout)
    int rate = 0, channels = 0;
    uint64_t sequence = 0;
  };
  std::map<SensorId, Stream> streams;  // the converted ones
  std::deque<FramePtr> ready;
  bool ended = false;
  std::vector<audio::StampedAudio> blocks;  // scratch

  void emit(const SensorId& id, Stream& s) {
    for (auto& b : blocks)
      ready.push_back(make_frame(id, b.stamp, s.sequence++, std::move(b.audio)));
    blocks.clear();
  }
};

ResamplingSource::ResamplingSource(std::unique_ptr<Source> inner, std::unique_ptr<Impl> impl)
    : inner_(std::move(inner)), impl_(std::move(impl)) {}
ResamplingSource::~ResamplingSource() = default;

Result<std::unique_ptr<ResamplingSource>> ResamplingSource::wrap(
    std::unique_ptr<Source> inner, const ResamplingSourceOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (!inner) return make_error(ErrorCode::kInvalidArgument, "ResamplingSource: no source");
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->info = inner->info();
  for (const auto& id : options.streams) {
    const SensorDescription* d = impl->info.find(id);
    if (d == nullptr || d->kind != SensorKind::kAudio)
      return make_error(ErrorCode::kInvalidArgument,
                        "ResamplingSource: '{}' is not an audio stream of the source", id);
  }
  for (auto& d : impl->info.sensors) {
    if (d.kind != SensorKind::kAudio) continue;
    if (!options.streams.empty() &&
        std::find(options.streams.begin(), options.streams.end(), d.id) == options.streams.end())
      continue;
    impl->streams[d.id];
    d.sample_rate = options.sample_rate;
  }
  return std::unique_ptr<ResamplingSource>(new ResamplingSource(std::move(inner), std::move(impl)));
}

Result<FramePtr> ResamplingSource::next() {
  Impl& m = *impl_;
  while (m.ready.empty()) {
    if (m.ended) return make_error(ErrorCode::kEndOfStream, "resampling source: end of stream");
    Result<FramePtr> r = inner_->next();
    if (!r) {
      if (!is_end_of_stream(r.error())) return r;
      m.ended = true;
      for (auto& [id, s] : m.streams)
        if (s.resampler) {
          if (auto st = s.resampler->flush(m.blocks); !st) return tl::unexpected(st.error());
          m.emit(id, s);
        }
      continue;
    }
    const FramePtr& f = *r;
    auto it = m.streams.find(f->sensor);
    const AudioChunk* a = f->as<AudioChunk>();
    if (it == m.streams.end() || a == nullptr) return f;  // not converted: pass through
    Impl::Stream& s = it->second;
    if (a->sample_rate == m.options.sample_rate && !s.resampler) {
      // Already at the target rate (and never converted before): pass through as it is.
      return f;
    }
    if (!s.resampler || a->sample_rate != s.rate || a->channels != s.channels) {
      if (s.resampler) {  // layout changed mid-stream: finish the old conversion first
        if (auto st = s.resampler->flush(m.blocks); !st) return tl::unexpected(st.error());
        m.emit(f->sensor, s);
      }
      audio::ResamplerOptions o;
      o.input_rate = a->sample_rate;
      o.output_rate = m.options.sample_rate;
      o.channels = a->channels;
      o.quality = static_cast<audio::ResamplerQuality>(m.options.quality);
      auto rs = audio::Resampler::create(o);
      if (!rs) return make_error(rs.error().code, "stream '{}': {}", f->sensor, rs.error().message);
      s.resampler = std::move(*rs);
      s.rate = a->sample_rate;
      s.channels = a->channels;
    }
    if (auto st = s.resampler->process(a->samples, f->stamp, m.blocks); !st)
      return make_error(st.error().code, "stream '{}' at {}: {}", f->sensor, f->stamp.to_string(),
                        st.error().message);
    m.emit(f->sensor, s);
  }
  FramePtr f = std::move(m.ready.front());
  m.ready.pop_front();
  return f;
}

SourceInfo ResamplingSource::info() const { return impl_->info; }

}  // namespace dreamsense::sources
