#include "dreamsense/speech/recognizer.hpp"

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

Status RecognizerOptions::check() const {
  std::vector<std::string> bad;
  if (model_rate_hz <= 0)
    bad.push_back(fmt::format("model_rate_hz must be > 0 (got {})", model_rate_hz));
  if (!(garbage_phone_weight > 0 && garbage_phone_weight <= 1))
    bad.push_back(
        fmt::format("garbage_phone_weight must be in (0, 1] (got {})", garbage_phone_weight));
  if (!(min_confidence >= 0 && min_confidence <= 1))
    bad.push_back(fmt::format("min_confidence must be in [0, 1] (got {})", min_confidence));
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
  c.dictionary = options.dictionary.string();
  c.rate_hz = options.model_rate_hz;
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
  std::vector<int16_t> resampled;
  if (sample_rate_hz != impl_->options.model_rate_hz) {
    resampled = resample(samples, sample_rate_hz, impl_->options.model_rate_hz);
    samples = resampled;
  }
  Decoding d;
  auto main = impl_->decoder->run(false, samples);
  if (!main) return tl::unexpected(main.error());
  d.heard_speech = main->any_word;
  d.grammar_hypothesis = main->hyp;
  if (!main->hyp.empty()) {
    d.first_frame = main->first;
    d.last_frame = main->last;
    auto garbage = impl_->decoder->run(true, samples);
    if (!garbage) return tl::unexpected(garbage.error());
    const double frames = std::max<double>(
        1.0, static_cast<double>(samples.size()) * 100.0 / impl_->options.model_rate_hz);
    // No garbage path survived the beam: the grammar wins by a wide margin.
    const double margin = garbage->any_word
                              ? (static_cast<double>(main->score) - garbage->score) / frames
                              : 10.0 * impl_->options.confidence_scale;
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

std::vector<int16_t> resample(std::span<const int16_t> in, int from_hz, int to_hz) {
  if (from_hz == to_hz || in.empty()) return {in.begin(), in.end()};
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

}  // namespace dreamsense::speech
