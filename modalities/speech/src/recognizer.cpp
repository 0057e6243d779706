#include "dreamsense/speech/recognizer.hpp"

#include "dreamsense/audio/audio_file.hpp"
#include "dreamsense/perception/speech.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>

#include "ps_backend.hpp"

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& p, bool& ok) {
  std::ifstream in(p, std::ios::binary);
  ok = static_cast<bool>(in);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

Result<Resampler> parse_resampler(std::string_view name) {
  if (name == "soxr") return Resampler::kSoxr;
  if (name == "sinc") return Resampler::kSinc;
  return make_error(ErrorCode::kInvalidArgument, "unknown resampler '{}' (soxr or sinc)", name);
}
std::string_view to_string(Resampler r) { return r == Resampler::kSoxr ? "soxr" : "sinc"; }

Status RecognizerOptions::check() const {
  std::vector<std::string> bad;
  if (model_rate_hz <= 0)
    bad.push_back(fmt::format("model_rate_hz must be > 0 (got {})", model_rate_hz));
  if (!(garbage_phone_weight > 0 && garbage_phone_weight <= 1))
    bad.push_back(
        fmt::format("garbage_phone_weight must be in (0, 1] (got {})", garbage_phone_weight));
  if (!(min_confidence >= 0 && min_confidence <= 1))
    bad.push_back(fmt::format("min_confidence must be in [0, 1] (got {})", min_confidence));
  if (front_end_rate_hz < 0)
    bad.push_back(fmt::format("front_end_rate_hz must be >= 0 (got {})", front_end_rate_hz));
  const int fe_rate = front_end_rate_hz > 0 ? front_end_rate_hz : model_rate_hz;
  if (front_end_upper_hz < 0 || (front_end_upper_hz > 0 && front_end_upper_hz >= fe_rate / 2.0))
    bad.push_back(
        fmt::format("front_end_upper_hz must be 0 (model default) or below {} Hz "
                    "(half the front-end rate; got {})",
                    fe_rate / 2.0, front_end_upper_hz));
  if (front_end_upper_hz == 0 && fe_rate < model_rate_hz)
    bad.push_back(
        fmt::format("a {} Hz front end needs front_end_upper_hz below {} Hz (the "
                    "model's filters reach 6800 Hz)",
                    fe_rate, fe_rate / 2.0));
  if (!(frequency_warp >= 0.5 && frequency_warp <= 2.0))
    bad.push_back(fmt::format("frequency_warp must be in [0.5, 2] (got {})", frequency_warp));
  if (!(confidence_scale > 0))
    bad.push_back(fmt::format("confidence_scale must be > 0 (got {})", confidence_scale));
  if (bad.empty()) return ok_status();
  std::string msg = "speech recognizer options: ";
  for (size_t i = 0; i < bad.size(); ++i) msg += (i ? "; " : "") + bad[i];
  return make_error(ErrorCode::kInvalidArgument, msg);
}

Result<Grammar> Grammar::from_jsgf(std::string jsgf, std::string source) {
  Grammar g;
  g.jsgf = std::move(jsgf);
  g.source = std::move(source);
  return g;
}
Result<Grammar> Grammar::from_jsgf_file(const fs::path& path) {
  bool ok = false;
  std::string text = read_text(path, ok);
  if (!ok) return make_error(ErrorCode::kNotFound, "cannot open JSGF grammar {}", path.string());
  return from_jsgf(std::move(text), path.string());
}
Result<Grammar> Grammar::from_srgs(const std::string& xml, std::string source) {
  auto s = SrgsGrammar::parse(xml, source);
  if (!s) return tl::unexpected(s.error());
  Grammar g;
  g.jsgf = s->to_jsgf();
  g.srgs = std::move(*s);
  g.source = std::move(source);
  return g;
}
Result<Grammar> Grammar::from_srgs_file(const fs::path& path) {
  bool ok = false;
  std::string text = read_text(path, ok);
  if (!ok) return make_error(ErrorCode::kNotFound, "cannot open SRGS grammar {}", path.string());
  return from_srgs(text, path.string());
}
Result<Grammar> Grammar::from_file(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".grxml" || ext == ".xml") return from_srgs_file(path);
  return from_jsgf_file(path);
}

struct Recognizer::Impl {
  RecognizerOptions options;
  Grammar grammar;
  std::unique_ptr<detail::PsDecoder> decoder;
};

Recognizer::Recognizer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Recognizer::~Recognizer() = default;

Result<std::unique_ptr<Recognizer>> Recognizer::create(const RecognizerOptions& options,
                                                       const Grammar& grammar) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  if (!fs::exists(options.model_dir / "mdef"))
    return make_error(ErrorCode::kNotFound,
                      "acoustic model not found at {} (install the Debian package "
                      "pocketsphinx-en-us)",
                      options.model_dir.string());
  if (!fs::exists(options.dictionary))
    return make_error(ErrorCode::kNotFound,
                      "pronunciation dictionary not found at {} (install the Debian package "
                      "pocketsphinx-en-us)",
                      options.dictionary.string());
  detail::PsConfig c;
  c.model_dir = options.model_dir.string();
  c.means_file = options.means_file.string();
  c.dictionary = options.dictionary.string();
  c.rate_hz = options.front_end_rate_hz > 0 ? options.front_end_rate_hz : options.model_rate_hz;
  c.upper_hz = options.front_end_upper_hz;
  c.remove_silence = options.remove_silence;
  c.remove_noise = options.remove_noise;
  c.frequency_warp = options.frequency_warp;
  c.mfc_log_dir = options.feature_log_dir.string();
  c.jsgf = grammar.jsgf;
  c.source = grammar.source;
  c.reject = options.reject_out_of_grammar;
  c.garbage_phone_weight = options.garbage_phone_weight;
  auto decoder = detail::PsDecoder::create(c);
  if (!decoder) return tl::unexpected(decoder.error());
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->grammar = grammar;
  impl->decoder = std::move(*decoder);
  return std::unique_ptr<Recognizer>(new Recognizer(std::move(impl)));
}

Result<Decoding> Recognizer::decode(std::span<const int16_t> samples, int sample_rate_hz) {
  if (sample_rate_hz <= 0)
    return make_error(ErrorCode::kInvalidArgument, "speech: sample rate must be > 0 (got {})",
                      sample_rate_hz);
  const auto t0 = std::chrono::steady_clock::now();
  const int fe_rate = impl_->options.front_end_rate_hz > 0 ? impl_->options.front_end_rate_hz
                                                           : impl_->options.model_rate_hz;
  std::vector<int16_t> resampled;
  if (sample_rate_hz != fe_rate) {
    resampled = resample(samples, sample_rate_hz, fe_rate, impl_->options.resampler);
    samples = resampled;
  }
  Decoding d;
  auto main = impl_->decoder->run(false, samples);
  if (!main) return tl::unexpected(main.error());
  const double frames =
      std::max<double>(1.0, static_cast<double>(samples.size()) * 100.0 / fe_rate);
  d.score_per_frame = static_cast<double>(main->score) / frames;
  d.heard_speech = main->any_word;
  d.grammar_hypothesis = main->hyp;
  if (!main->hyp.empty()) {
    d.first_frame = main->first;
    d.last_frame = main->last;
    if (!impl_->options.confidence_pass && !impl_->options.reject_out_of_grammar) {
      d.confidence = 1.0;
      d.accepted = true;
      d.decode_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return d;
    }
    auto garbage = impl_->decoder->run(true, samples);
    if (!garbage) return tl::unexpected(garbage.error());
    // No garbage path survived the beam: the grammar wins by a wide margin.
    const double margin = garbage->any_word
                              ? (static_cast<double>(main->score) - garbage->score) / frames
                              : 10.0 * impl_->options.confidence_scale;
    d.margin_per_frame = margin;
    d.confidence = 1.0 / (1.0 + std::exp(-margin / impl_->options.confidence_scale));
    d.accepted =
        !impl_->options.reject_out_of_grammar || d.confidence >= impl_->options.min_confidence;
    if (!impl_->options.reject_out_of_grammar && !garbage->any_word) d.confidence = 1.0;
  }
  d.decode_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

Result<std::optional<RecognizedSpeech>> Recognizer::recognize(std::span<const int16_t> samples,
                                                              int sample_rate_hz, Timestamp start) {
  auto d = decode(samples, sample_rate_hz);
  if (!d) return tl::unexpected(d.error());
  if (!d->accepted) return std::optional<RecognizedSpeech>{};
  RecognizedSpeech r;
  r.text = d->grammar_hypothesis;
  r.tag = r.text;
  if (impl_->grammar.srgs) {
    auto tag = impl_->grammar.srgs->tag_for(split_words(r.text));
    if (tag && !tag->empty()) r.tag = *tag;
  }
  r.confidence = d->confidence;
  r.start = start + Duration::from_seconds(d->first_frame * 0.01);
  r.end = start + Duration::from_seconds((d->last_frame + 1) * 0.01);
  return std::optional<RecognizedSpeech>(std::move(r));
}

Result<std::optional<RecognizedSpeech>> Recognizer::recognize(std::span<const float> samples,
                                                              int sample_rate_hz, Timestamp start) {
  std::vector<int16_t> s(samples.size());
  std::transform(samples.begin(), samples.end(), s.begin(), [](float x) {
    return static_cast<int16_t>(std::lround(std::clamp(x, -1.0f, 1.0f) * 32767.0f));
  });
  return recognize(std::span<const int16_t>(s), sample_rate_hz, start);
}

std::vector<int16_t> resample(std::span<const int16_t> in, int from_hz, int to_hz,
                              Resampler method) {
  return audio::resample_pcm16(
      in, from_hz, to_hz,
      method == Resampler::kSoxr ? audio::Pcm16Resampler::kSoxr : audio::Pcm16Resampler::kSinc);
}

}  // namespace dreamsense::speech
