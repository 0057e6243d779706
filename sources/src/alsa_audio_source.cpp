#include "dreamsense/sources/alsa_audio_source.hpp"

#include "dreamsense/core/log.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

#include "capture_queue.hpp"

#ifdef DREAMSENSE_HAVE_ALSA
#include <alsa/asoundlib.h>
#endif

namespace dreamsense::sources {

Status AlsaAudioSourceOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (sensor.empty()) add("sensor is empty");
  if (device.empty()) add("device is empty");
  if (sample_rate < 1000 || sample_rate > 384000)
    add(fmt::format("sample_rate must be in [1000, 384000] (is {})", sample_rate));
  if (channels < 1 || channels > 64)
    add(fmt::format("channels must be in [1, 64] (is {})", channels));
  if (!(chunk_s >= 0.001 && chunk_s <= 1.0))
    add(fmt::format("chunk_s must be in [0.001, 1] (is {})", chunk_s));
  if (!(buffer_s >= 2 * chunk_s))
    add(fmt::format("buffer_s must be >= 2 chunks (is {} s for {} s chunks)", buffer_s, chunk_s));
  if (max_queued < 1) add("max_queued must be >= 1");
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "AlsaAudioSourceOptions: {}", bad);
  return ok_status();
}

struct AlsaAudioSource::Impl {
  AlsaAudioSourceOptions options;
  int64_t chunk_frames = 0;
#ifdef DREAMSENSE_HAVE_ALSA
  snd_pcm_t* pcm = nullptr;
#endif
  std::thread thread;
  std::atomic<bool> stop{false};
  std::unique_ptr<detail::CaptureQueue> queue;  // made by open()
  mutable std::mutex stats_mutex;
  AlsaCaptureStats stats;

  ~Impl() {
    stop = true;
    if (thread.joinable()) thread.join();
#ifdef DREAMSENSE_HAVE_ALSA
    if (pcm != nullptr) snd_pcm_close(pcm);
#endif
  }

  void finish(std::optional<Error> e) { queue->finish(std::move(e)); }

#ifdef DREAMSENSE_HAVE_ALSA
  void capture();
#endif
};

#ifdef DREAMSENSE_HAVE_ALSA
namespace {

// alsa-lib prints its own errors to stderr; route them to our log at debug level (the Result
// returned to the caller says what went wrong).
void alsa_error_handler(const char* file, int line, const char* function, int err,
                        const char* format, ...) {
  char text[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(text, sizeof text, format, args);
  va_end(args);
  log::debug("alsa-lib {}:{} ({}): {}{}", file, line, function, text,
             err != 0 ? fmt::format(" ({})", snd_strerror(err)) : std::string());
}

Duration since_origin(std::chrono::steady_clock::time_point origin) {
  return Duration::from_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::steady_clock::now() - origin)
                               .count());
}

Duration frames_to(int64_t frames, int rate) {
  return Duration::from_ns(frames / rate * 1'000'000'000LL +
                           frames % rate * 1'000'000'000LL / rate);
}

}  // namespace

void AlsaAudioSource::Impl::capture() {
  const int ch = options.channels, rate = options.sample_rate;
  std::vector<int16_t> buf(static_cast<size_t>(chunk_frames * ch));
  Timestamp anchor = Timestamp::unset();  // stamp of sample 0 of the current segment
  Timestamp last_end = Timestamp::unset();
  int64_t since_anchor = 0;  // samples delivered since the anchor
  uint64_t sequence = 0;
  int idle_ms = 0;
  while (!stop) {
    // Wait (at most 100 ms at a time) so that stop() is noticed even if the device stalls.
    const int w = snd_pcm_wait(pcm, 100);
    if (w == 0) {
      idle_ms += 100;
      if (idle_ms >= 3000)
        return finish(
            Error{ErrorCode::kIoError,
                  fmt::format("ALSA device '{}' delivered no audio for 3 s", options.device)});
      continue;
    }
    idle_ms = 0;
    int64_t have = 0;
    bool lost = false;
    while (have < chunk_frames && !stop) {
      const snd_pcm_sframes_t n = snd_pcm_readi(
          pcm, buf.data() + have * ch, static_cast<snd_pcm_uframes_t>(chunk_frames - have));
      if (n >= 0) {
        have += n;
        continue;
      }
      if (n == -EAGAIN) continue;
      if (n == -ENODEV)
        return finish(
            Error{ErrorCode::kIoError,
                  fmt::format("ALSA device '{}' disappeared while capturing", options.device)});
      // Overrun (-EPIPE) or suspend (-ESTRPIPE): recover; the samples of this chunk are lost.
      if (snd_pcm_recover(pcm, static_cast<int>(n), 1) < 0)
        return finish(Error{ErrorCode::kIoError,
                            fmt::format("ALSA device '{}': read failed: {}", options.device,
                                        snd_strerror(static_cast<int>(n)))});
      lost = true;
      have = 0;
      std::lock_guard lock(stats_mutex);
      ++stats.overruns;
    }
    if (stop) break;
    if (lost || !anchor.is_set()) {
      // Anchor: now, minus this chunk and whatever is still buffered in the device.
      snd_pcm_sframes_t avail = snd_pcm_avail(pcm);
      if (avail < 0) avail = 0;
      Timestamp a = Timestamp::from_ns(0) + since_origin(options.clock_origin) -
                    frames_to(chunk_frames + avail, rate);
      if (last_end.is_set() && a < last_end) a = last_end;  // stamps never go back
      if (anchor.is_set())
        log::warn("audio '{}': ALSA overrun on '{}': samples lost, stamps re-anchored",
                  options.sensor, options.device);
      anchor = a;
      since_anchor = 0;
    }
    AudioChunk c;
    c.sample_rate = rate;
    c.channels = ch;
    c.samples.resize(buf.size());
    for (size_t i = 0; i < buf.size(); ++i) c.samples[i] = buf[i] * (1.f / 32768.f);
    const Timestamp stamp = anchor + frames_to(since_anchor, rate);
    since_anchor += chunk_frames;
    last_end = anchor + frames_to(since_anchor, rate);
    FramePtr f = make_frame(options.sensor, stamp, sequence++, std::move(c));
    const size_t dropped = queue->push(std::move(f));
    std::lock_guard lock(stats_mutex);
    ++stats.chunks;
    stats.dropped_chunks += dropped;
  }
  finish(std::nullopt);
}
#endif

AlsaAudioSource::AlsaAudioSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AlsaAudioSource::~AlsaAudioSource() = default;

Result<std::unique_ptr<AlsaAudioSource>> AlsaAudioSource::open(
    const AlsaAudioSourceOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
#ifndef DREAMSENSE_HAVE_ALSA
  return make_error(ErrorCode::kUnsupported,
                    "audio '{}': this build has no ALSA support (install libasound2-dev and "
                    "reconfigure)",
                    options.sensor);
#else
  static std::once_flag handler_once;
  std::call_once(handler_once, [] { snd_lib_error_set_handler(alsa_error_handler); });
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->queue = std::make_unique<detail::CaptureQueue>(options.max_queued);
  const std::string& dev = options.device;
  int err = snd_pcm_open(&impl->pcm, dev.c_str(), SND_PCM_STREAM_CAPTURE, 0);
  if (err < 0) {
    impl->pcm = nullptr;
    if (err == -ENOENT || err == -ENODEV || err == -ENXIO)
      return make_error(ErrorCode::kNotFound,
                        "audio '{}': no ALSA capture device '{}' ({}); list devices with "
                        "`arecord -L` (alsa-utils)",
                        options.sensor, dev, snd_strerror(err));
    if (err == -EBUSY)
      return make_error(ErrorCode::kIoError,
                        "audio '{}': ALSA device '{}' is busy (another program is capturing)",
                        options.sensor, dev);
    return make_error(ErrorCode::kIoError, "audio '{}': cannot open ALSA device '{}': {}",
                      options.sensor, dev, snd_strerror(err));
  }
  snd_pcm_hw_params_t* hw = nullptr;
  snd_pcm_hw_params_alloca(&hw);
  auto fail = [&](ErrorCode code, const std::string& what, int e) {
    return make_error(code, "audio '{}': ALSA device '{}': {}: {}", options.sensor, dev, what,
                      snd_strerror(e));
  };
  if ((err = snd_pcm_hw_params_any(impl->pcm, hw)) < 0)
    return fail(ErrorCode::kIoError, "no configuration", err);
  if ((err = snd_pcm_hw_params_set_access(impl->pcm, hw, SND_PCM_ACCESS_RW_INTERLEAVED)) < 0)
    return fail(ErrorCode::kUnsupported, "interleaved access not supported", err);
  if ((err = snd_pcm_hw_params_set_format(impl->pcm, hw, SND_PCM_FORMAT_S16_LE)) < 0)
    return fail(ErrorCode::kUnsupported, "16-bit little-endian samples not supported", err);
  if ((err = snd_pcm_hw_params_set_channels(impl->pcm, hw,
                                            static_cast<unsigned>(options.channels))) < 0) {
    unsigned lo = 0, hi = 0;
    snd_pcm_hw_params_get_channels_min(hw, &lo);
    snd_pcm_hw_params_get_channels_max(hw, &hi);
    return fail(ErrorCode::kUnsupported,
                fmt::format("{} channels not supported (device: {}..{})", options.channels, lo, hi),
                err);
  }
  snd_pcm_hw_params_set_rate_resample(impl->pcm, hw, 0);  // the device's own rate, or fail
  if ((err = snd_pcm_hw_params_set_rate(impl->pcm, hw, static_cast<unsigned>(options.sample_rate),
                                        0)) < 0) {
    unsigned lo = 0, hi = 0;
    int dir = 0;
    snd_pcm_hw_params_get_rate_min(hw, &lo, &dir);
    snd_pcm_hw_params_get_rate_max(hw, &hi, &dir);
    return fail(ErrorCode::kUnsupported,
                fmt::format("{} Hz not supported (device: {}..{} Hz; capture at a supported rate "
                            "and wrap the source in a ResamplingSource, or use a plughw: device)",
                            options.sample_rate, lo, hi),
                err);
  }
  impl->chunk_frames = std::max<int64_t>(1, std::llround(options.chunk_s * options.sample_rate));
  snd_pcm_uframes_t period = static_cast<snd_pcm_uframes_t>(impl->chunk_frames);
  int dir = 0;
  snd_pcm_hw_params_set_period_size_near(impl->pcm, hw, &period, &dir);
  snd_pcm_uframes_t buffer =
      static_cast<snd_pcm_uframes_t>(std::llround(options.buffer_s * options.sample_rate));
  snd_pcm_hw_params_set_buffer_size_near(impl->pcm, hw, &buffer);
  if ((err = snd_pcm_hw_params(impl->pcm, hw)) < 0)
    return fail(ErrorCode::kUnsupported, "cannot apply the configuration", err);
  if ((err = snd_pcm_prepare(impl->pcm)) < 0) return fail(ErrorCode::kIoError, "prepare", err);
  if ((err = snd_pcm_start(impl->pcm)) < 0) return fail(ErrorCode::kIoError, "start", err);
  log::info("audio '{}': capturing from ALSA '{}' ({} ch, {} Hz, period {}, buffer {} frames)",
            options.sensor, dev, options.channels, options.sample_rate, period, buffer);
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->capture(); });
  return std::unique_ptr<AlsaAudioSource>(new AlsaAudioSource(std::move(impl)));
#endif
}

Result<FramePtr> AlsaAudioSource::next() {
  return impl_->queue->pop(fmt::format("audio '{}': capture stopped", impl_->options.sensor));
}

SourceInfo AlsaAudioSource::info() const {
  SourceInfo i;
  SensorDescription d;
  d.id = impl_->options.sensor;
  d.kind = SensorKind::kAudio;
  d.sample_rate = impl_->options.sample_rate;
  d.channels = impl_->options.channels;
  d.rate_hz = static_cast<double>(impl_->options.sample_rate) /
              static_cast<double>(std::max<int64_t>(1, impl_->chunk_frames));
  d.frame = d.id;
  i.sensors.push_back(d);
  i.live = true;
  return i;
}

void AlsaAudioSource::stop() { impl_->stop = true; }  // the capture thread then finishes the queue

AlsaCaptureStats AlsaAudioSource::stats() const {
  std::lock_guard lock(impl_->stats_mutex);
  return impl_->stats;
}

bool AlsaAudioSource::has_capture_card() {
#ifndef DREAMSENSE_HAVE_ALSA
  return false;
#else
  int card = -1;
  while (snd_card_next(&card) == 0 && card >= 0) {
    snd_ctl_t* ctl = nullptr;
    if (snd_ctl_open(&ctl, fmt::format("hw:{}", card).c_str(), 0) < 0) continue;
    int device = -1;
    bool found = false;
    snd_pcm_info_t* info = nullptr;
    snd_pcm_info_alloca(&info);
    while (!found && snd_ctl_pcm_next_device(ctl, &device) == 0 && device >= 0) {
      snd_pcm_info_set_device(info, static_cast<unsigned>(device));
      snd_pcm_info_set_subdevice(info, 0);
      snd_pcm_info_set_stream(info, SND_PCM_STREAM_CAPTURE);
      found = snd_ctl_pcm_info(ctl, info) == 0;
    }
    snd_ctl_close(ctl);
    if (found) return true;
  }
  return false;
#endif
}

}  // namespace dreamsense::sources
