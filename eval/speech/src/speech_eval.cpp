#include "dreamsense/eval/speech_eval.hpp"

#include "dreamsense/audio/audio_file.hpp"
#include "dreamsense/eval/speaker_batch.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <regex>
#include <sstream>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Clip {
  std::string name;
  std::vector<int16_t> samples;
  int rate = 16000;
};

Result<Clip> load_clip(const fs::path& p) {
  Clip c;
  c.name = p.filename().string();
  audio::ReadAudioOptions ro;
  ro.channel = 0;  // headerless .raw: s16le mono 16 kHz
  DS_ASSIGN_OR_RETURN(audio::AudioClip clip, audio::read_audio(p, ro));
  c.rate = clip.sample_rate;
  c.samples = audio::to_pcm16(clip.samples);
  return c;
}

Clip synthetic(const std::string& name, double rms, unsigned seed) {
  Clip c;
  c.name = name;
  c.samples.resize(48000);
  std::mt19937 gen(seed);
  std::normal_distribution<double> n(0, rms);
  for (auto& s : c.samples)
    s = static_cast<int16_t>(std::clamp(std::lround(n(gen)), -32768L, 32767L));
  return c;
}

std::string normalise(const std::string& s) {
  std::string out;
  for (const auto& w : split_words(s)) out += (out.empty() ? "" : " ") + w;
  return out;
}

struct GrammarSet {
  std::string name;
  fs::path grammar;
  std::vector<std::pair<fs::path, std::string>> utterances;  // file, reference
};

Result<eval::EvalReport> run_pocketsphinx(const SpeechEvalOptions& o,
                                          const std::function<void(double)>& progress) {
  RecognizerOptions ro = o.recognizer;
  if (o.garbage_phone_weight) ro.garbage_phone_weight = *o.garbage_phone_weight;
  if (o.min_confidence) ro.min_confidence = *o.min_confidence;
  const fs::path d = o.dir;
  for (const char* f :
       {"goforward.raw", "goforward.gram", "cards/cards.gram", "cards/cards.transcription"})
    if (!fs::exists(d / f))
      return make_error(ErrorCode::kNotFound,
                        "eval speech: {} is not a pocketsphinx test-data folder (missing {}; "
                        "Debian package pocketsphinx-testdata)",
                        d.string(), f);

  std::vector<GrammarSet> sets;
  {
    GrammarSet cards{"cards", d / "cards/cards.gram", {}};
    std::ifstream in(d / "cards/cards.transcription");
    std::string line;
    const std::regex re(R"(^\s*(?:<s>)?(.*?)(?:</s>)?\s*\((\w+)\)\s*$)");
    while (std::getline(in, line)) {
      std::smatch m;
      if (!std::regex_match(line, m, re)) continue;
      const fs::path wav = d / "cards" / (m[2].str() + ".wav");
      if (fs::exists(wav)) cards.utterances.push_back({wav, normalise(m[1].str())});
    }
    if (cards.utterances.empty())
      return make_error(ErrorCode::kCorruptData, "eval speech: no cards utterances found via {}",
                        (d / "cards/cards.transcription").string());
    sets.push_back(std::move(cards));
    // pocketsphinx's test_jsgf.c / test_fsg.c expect this hypothesis for goforward.raw.
    sets.push_back(
        {"goforward", d / "goforward.gram", {{d / "goforward.raw", "go forward ten meters"}}});
  }
  std::vector<fs::path> other_speech;
  for (const char* f : {"numbers.raw", "something.raw"})
    if (fs::exists(d / f)) other_speech.push_back(d / f);
  if (fs::is_directory(d / "librivox")) {
    std::vector<fs::path> lv;
    for (const auto& e : fs::directory_iterator(d / "librivox"))
      if (e.path().extension() == ".wav") lv.push_back(e.path());
    std::sort(lv.begin(), lv.end());
    other_speech.insert(other_speech.end(), lv.begin(), lv.end());
  }

  size_t total_steps = 0;
  for (size_t i = 0; i < sets.size(); ++i) {
    total_steps += sets[i].utterances.size() + other_speech.size() + 2;
    for (size_t j = 0; j < sets.size(); ++j)
      if (j != i) total_steps += sets[j].utterances.size();
  }
  size_t step = 0;
  auto tick = [&] {
    if (progress) progress(static_cast<double>(++step) / std::max<size_t>(1, total_steps));
  };

  double decode_s = 0, audio_s = 0;
  size_t in_items = 0, in_correct = 0, oog_items = 0, oog_accepted = 0;
  json per_class = json::object(), items = json::array();
  for (size_t i = 0; i < sets.size(); ++i) {
    const auto& set = sets[i];
    auto grammar = Grammar::from_file(set.grammar);
    if (!grammar) return tl::unexpected(grammar.error());
    auto rec = Recognizer::create(ro, *grammar);
    if (!rec) return tl::unexpected(rec.error());
    size_t s_in = 0, s_ok = 0, s_oog = 0, s_fa = 0;
    auto run = [&](const Clip& clip, const std::string& reference, bool in_grammar) -> Status {
      auto dec = (*rec)->decode(clip.samples, clip.rate);
      if (!dec) return tl::unexpected(dec.error());
      decode_s += dec->decode_seconds;
      audio_s += static_cast<double>(clip.samples.size()) / clip.rate;
      const std::string hyp = dec->accepted ? dec->grammar_hypothesis : "";
      bool ok;
      if (in_grammar) {
        ok = hyp == reference;
        ++s_in;
        s_ok += ok;
      } else {
        ok = hyp.empty();
        ++s_oog;
        s_fa += !ok;
      }
      if (o.list_items)
        items.push_back({{"grammar", set.name},
                         {"clip", clip.name},
                         {"in_grammar", in_grammar},
                         {"reference", reference},
                         {"hypothesis", hyp},
                         {"best_grammar_path", dec->grammar_hypothesis},
                         {"confidence", dec->confidence},
                         {"correct", ok}});
      tick();
      return ok_status();
    };
    for (const auto& [file, ref] : set.utterances) {
      auto c = load_clip(file);
      if (!c) return tl::unexpected(c.error());
      if (auto st = run(*c, ref, true); !st) return tl::unexpected(st.error());
    }
    std::vector<fs::path> oog = other_speech;
    for (size_t j = 0; j < sets.size(); ++j)
      if (j != i)
        for (const auto& u : sets[j].utterances) oog.push_back(u.first);
    for (const auto& f : oog) {
      auto c = load_clip(f);
      if (!c) return tl::unexpected(c.error());
      if (auto st = run(*c, "", false); !st) return tl::unexpected(st.error());
    }
    for (const auto& c :
         {synthetic("silence(3s)", 2.0, 1), synthetic("white_noise(3s,-30dBFS)", 1036.0, 2)})
      if (auto st = run(c, "", false); !st) return tl::unexpected(st.error());
    per_class[set.name] = {
        {"grammar_sentence_accuracy", s_in ? static_cast<double>(s_ok) / s_in : 0.0},
        {"in_grammar_items", s_in},
        {"false_accept_rate", s_oog ? static_cast<double>(s_fa) / s_oog : 0.0},
        {"out_of_grammar_items", s_oog}};
    in_items += s_in;
    in_correct += s_ok;
    oog_items += s_oog;
    oog_accepted += s_fa;
  }
  const size_t n = in_items + oog_items;
  eval::EvalReport j;
  j.task = "speech";
  j.dataset = "pocketsphinx";
  j.items = n;
  j.extra["dataset_dir"] = fs::absolute(d).string();
  j.protocol =
      "grammar recognition, PocketSphinx en-us + phone-loop garbage rejection; in-grammar: "
      "cards/*.wav under cards.gram, goforward.raw under goforward.gram; out-of-grammar per "
      "grammar: the other grammar's utterances, numbers.raw, something.raw, librivox/*.wav, 3 s "
      "silence, 3 s white noise";
  j.metrics = {
      {"grammar_sentence_accuracy", in_items ? static_cast<double>(in_correct) / in_items : 0.0},
      {"false_accept_rate", oog_items ? static_cast<double>(oog_accepted) / oog_items : 0.0},
      {"accuracy", n ? static_cast<double>(in_correct + oog_items - oog_accepted) / n : 0.0},
      {"in_grammar_items", in_items},
      {"out_of_grammar_items", oog_items}};
  j.timing = {{"rtf", audio_s > 0 ? decode_s / audio_s : 0.0}, {"audio_seconds", audio_s}};
  j.per_class = per_class;
  if (o.list_items) j.extra["items"] = items;
  return j;
}

double ratio(size_t a, size_t b) { return b ? static_cast<double>(a) / b : 0.0; }

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// timing of a protocol: real-time factor over all clips and the median time per clip.
json timing_json(double decode_s, double audio_s, const std::vector<double>& ms) {
  return {{"rtf", audio_s > 0 ? decode_s / audio_s : 0.0},
          {"audio_seconds", audio_s},
          {"ms_per_clip_median", median(ms)}};
}

// per_class.<label>.recall (null without items) from (correct, total) counts.
json per_class_json(const std::vector<std::string>& labels,
                    const std::map<std::string, std::pair<size_t, size_t>>& counts) {
  json pc = json::object();
  for (const auto& l : labels) {
    const auto it = counts.find(l);
    const auto c = it == counts.end() ? std::pair<size_t, size_t>{0, 0} : it->second;
    pc[l] = {{"recall", c.second ? json(ratio(c.first, c.second)) : json(nullptr)},
             {"items", c.second}};
  }
  return pc;
}

json confusion_json(const std::vector<std::string>& labels,
                    const std::map<std::string, std::map<std::string, size_t>>& conf) {
  json c = json::object();
  for (const auto& t : labels) {
    json row = json::object();
    const auto it = conf.find(t);
    for (const auto& h : labels) {
      size_t n = 0;
      if (it != conf.end())
        if (const auto jt = it->second.find(h); jt != it->second.end()) n = jt->second;
      row[h] = n;
    }
    // Hypotheses outside the label set (e.g. "none": no result in a closed-set decode).
    if (it != conf.end())
      for (const auto& [h, n] : it->second)
        if (std::find(labels.begin(), labels.end(), h) == labels.end()) row[h] = n;
    c[t] = row;
  }
  return c;
}

// FSDD clips are trimmed to the word, often into its first consonant; the decoder needs some
// silence on both sides to place its silence model. Low-level noise rather than digital zero
// (log-energy floor). Deterministic per clip.
std::vector<int16_t> padded(const std::vector<int16_t>& s, size_t n, double rms, size_t seed) {
  std::mt19937 gen(static_cast<unsigned>(seed * 7919 + 1));
  std::normal_distribution<double> nd(0, rms);
  std::vector<int16_t> out;
  out.reserve(s.size() + 2 * n);
  auto noise = [&] {
    for (size_t i = 0; i < n; ++i) out.push_back(static_cast<int16_t>(std::lround(nd(gen))));
  };
  noise();
  out.insert(out.end(), s.begin(), s.end());
  noise();
  return out;
}

// The ten digit words as FSDD's speakers say them; with SpeechEvalOptions::fsdd_oh also "oh",
// a second spelling of 0 (TIDIGITS' convention, not FSDD's).
constexpr const char* kDigitWords[] = {"zero", "one", "two",   "three", "four",
                                       "five", "six", "seven", "eight", "nine"};

std::string digit_of(const std::string& word) {
  if (word == "oh") return "0";
  for (size_t d = 0; d < std::size(kDigitWords); ++d)
    if (word == kDigitWords[d]) return std::to_string(d);
  return "none";
}

}  // namespace

Result<FsddRecognizer> fsdd_recognizer(const SpeechEvalOptions& o) {
  FsddRecognizer f;
  RecognizerOptions& ro = f.options;
  ro = o.recognizer;
  // Closed set: every clip is a digit, so the best grammar path is the answer (a rejection
  // could only turn a right answer into a wrong one).
  ro.reject_out_of_grammar = false;
  if (o.garbage_phone_weight) ro.garbage_phone_weight = *o.garbage_phone_weight;
  // A folder is a TIDIGITS-family model (same units and 8 kHz front end), e.g. one adapted by
  // `dreamsense train speech`.
  const bool tidigits_family =
      o.fsdd_model == "tidigits" || (o.fsdd_model != "en-us" && fs::is_directory(o.fsdd_model));
  if (tidigits_family) {
    ro.model_dir = o.fsdd_model == "tidigits" ? kTidigitsModel : fs::path(o.fsdd_model);
    ro.dictionary = kTidigitsDictionary;
    ro.model_rate_hz = 8000;  // its filters end at 4 kHz: FSDD is decoded at its own rate
    ro.front_end_rate_hz = 0;
    ro.front_end_upper_hz = 0;
    ro.frequency_warp = kFsddTidigitsWarp;
    if (!fs::exists(ro.model_dir / "mdef"))
      return make_error(ErrorCode::kNotFound,
                        "eval speech: TIDIGITS model not found at {} (Debian package "
                        "pocketsphinx-testdata; or --fsdd-model en-us)",
                        ro.model_dir.string());
    // A folder from `train speech` brings the front end it was adapted with.
    if (auto st = use_acoustic_model(ro, ro.model_dir); !st) return tl::unexpected(st.error());
    if (o.frequency_warp) ro.frequency_warp = *o.frequency_warp;
    f.description = fmt::format(
        "PocketSphinx TIDIGITS digit model ({}; filters 1-4000 Hz) at 8 kHz, frequency warp {}",
        o.fsdd_model == "tidigits" ? "pocketsphinx-testdata" : ro.model_dir.string(),
        ro.frequency_warp);
  } else if (o.fsdd_model == "en-us") {
    if (o.frequency_warp) ro.frequency_warp = *o.frequency_warp;
    f.description =
        ro.front_end_rate_hz == 8000
            ? fmt::format("PocketSphinx en-us through an 8 kHz front end (filters to {} Hz)",
                          ro.front_end_upper_hz)
            : fmt::format("PocketSphinx en-us, audio resampled to {} Hz ({})", ro.model_rate_hz,
                          to_string(ro.resampler));
  } else {
    return make_error(
        ErrorCode::kInvalidArgument,
        "eval speech: --fsdd-model must be tidigits, en-us or a TIDIGITS-family model "
        "folder (got {})",
        o.fsdd_model);
  }
  f.words.assign(std::begin(kDigitWords), std::end(kDigitWords));
  if (o.fsdd_oh) f.words.push_back("oh");
  return f;
}

Result<Audio> fsdd_clip(const AudioItem& item, double pad_seconds, size_t seed) {
  auto a = read_mono_wav(item.path, 8000, "fsdd");
  if (!a) return tl::unexpected(a.error());
  const size_t pad_samples = static_cast<size_t>(std::lround(pad_seconds * 8000));
  if (pad_samples > 0) a->samples = padded(a->samples, pad_samples, kFsddPadRms, seed);
  return a;
}

std::string fsdd_digit_word(const std::string& label) {
  const int d =
      label.size() == 1 && std::isdigit(static_cast<unsigned char>(label[0])) ? label[0] - '0' : -1;
  return d >= 0 ? kDigitWords[d] : std::string();
}

Result<Audio> read_utterance_audio(const fs::path& path) {
  auto c = load_clip(path);
  if (!c) return tl::unexpected(c.error());
  return Audio{std::move(c->samples), c->rate};
}

Result<std::vector<AdaptationUtterance>> fsdd_enrolment(const std::vector<AudioItem>& items,
                                                        double pad_seconds) {
  std::vector<AdaptationUtterance> out;
  for (size_t i = 0; i < items.size(); ++i) {
    auto a = fsdd_clip(items[i], pad_seconds, i);
    if (!a) return tl::unexpected(a.error());
    out.push_back({items[i].path.stem().string(), std::move(a->samples), a->rate_hz,
                   fsdd_digit_word(items[i].label)});
  }
  return out;
}

Result<std::vector<AdaptationUtterance>> list_enrolment(const fs::path& list) {
  auto listed = load_utterance_list(list, false);
  if (!listed) return tl::unexpected(listed.error());
  std::vector<AdaptationUtterance> out;
  for (const auto& u : *listed) {
    auto a = load_clip(u.audio);
    if (!a)
      return make_error(a.error().code, "{}:{}: {}", list.string(), u.line, a.error().message);
    out.push_back({fmt::format("line{}", u.line), std::move(a->samples), a->rate, u.words});
  }
  return out;
}

namespace {

Result<eval::EvalReport> run_fsdd(const SpeechEvalOptions& o,
                                  const std::function<void(double)>& progress) {
  auto items = load_fsdd(o.dir, o.fsdd);
  if (!items) return tl::unexpected(items.error());
  auto setup = fsdd_recognizer(o);
  if (!setup) return tl::unexpected(setup.error());
  RecognizerOptions ro = setup->options;
  const std::string model_note = setup->description;
  if (o.fsdd_speaker_adapt && !(o.fsdd_vote.temperature > 0 && o.fsdd_vote.neighbours >= 0 &&
                                o.fsdd_vote.weight >= 0 && o.fsdd_vote.max_distance_ratio >= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "eval speech: the neighbour vote needs temperature > 0, neighbours >= 0, "
                      "weight >= 0, distance ratio >= 1");
  const double pad_s = o.pad_seconds.value_or(kFsddPadSeconds);
  const std::vector<std::string>& words = setup->words;

  // Per-utterance decoding. Without speaker adaptation: one decode under the digit grammar.
  // With it: one closed decode per word (the word's best-path score per frame; the grammar
  // decode would give only the winner's), the per-utterance answer being the best word.
  ro.confidence_pass = false;
  std::vector<std::unique_ptr<Recognizer>> recs;
  {
    std::vector<std::string> grammars;
    if (o.fsdd_speaker_adapt) {
      for (const auto& w : words)
        grammars.push_back("#JSGF V1.0;\ngrammar w;\npublic <w> = " + w + ";\n");
    } else {
      std::string g = "#JSGF V1.0;\ngrammar digits;\npublic <digit> = ";
      for (size_t i = 0; i < words.size(); ++i) g += (i ? " | " : "") + words[i];
      grammars.push_back(g + ";\n");
    }
    for (const auto& text : grammars) {
      auto grammar = Grammar::from_jsgf(text, "<fsdd digits>");
      if (!grammar) return tl::unexpected(grammar.error());
      auto rec = Recognizer::create(ro, *grammar);
      if (!rec) return tl::unexpected(rec.error());
      recs.push_back(std::move(*rec));
    }
  }
  const double decode_share = o.fsdd_speaker_adapt ? 0.8 : 1.0;  // of the progress bar

  const size_t n = items->size();
  std::vector<std::string> hyp(n), words_hyp(n);
  std::vector<std::vector<double>> digit_scores(n);  // per clip, per digit (adaptation only)
  std::vector<double> best_score(n, 0);
  double decode_s = 0, audio_s = 0;
  std::vector<double> ms;
  for (size_t i = 0; i < n; ++i) {
    const AudioItem& it = (*items)[i];
    auto a = fsdd_clip(it, pad_s, i);
    if (!a) return tl::unexpected(a.error());
    double sec = 0;
    if (o.fsdd_speaker_adapt) {
      digit_scores[i].assign(std::size(kDigitWords), -std::numeric_limits<double>::infinity());
      for (size_t w = 0; w < words.size(); ++w) {
        auto d = recs[w]->decode(a->samples, a->rate_hz);
        if (!d) return tl::unexpected(d.error());
        sec += d->decode_seconds;
        if (d->grammar_hypothesis.empty()) continue;  // no path through the word
        auto& s = digit_scores[i][static_cast<size_t>(std::stoi(digit_of(words[w])))];
        if (d->score_per_frame > s) s = d->score_per_frame;
        if (words_hyp[i].empty() || d->score_per_frame > best_score[i]) {
          best_score[i] = d->score_per_frame;
          words_hyp[i] = words[w];
        }
      }
    } else {
      auto d = recs[0]->decode(a->samples, a->rate_hz);
      if (!d) return tl::unexpected(d.error());
      sec = d->decode_seconds;
      words_hyp[i] = d->grammar_hypothesis;
      best_score[i] = d->score_per_frame;
    }
    hyp[i] = words_hyp[i].empty() ? "none" : digit_of(words_hyp[i]);
    decode_s += sec;
    audio_s += static_cast<double>(a->samples.size()) / a->rate_hz;
    ms.push_back(sec * 1000);
    if (progress) progress(decode_share * static_cast<double>(i + 1) / n);
  }

  // Batch speaker adaptation: neighbour vote within each speaker's clips (unpadded audio).
  std::vector<std::string> final_hyp = hyp;
  double adapt_s = 0;
  if (o.fsdd_speaker_adapt) {
    const auto t0 = std::chrono::steady_clock::now();
    std::map<std::string, std::vector<size_t>> by_speaker;
    for (size_t i = 0; i < n; ++i) by_speaker[(*items)[i].speaker].push_back(i);
    std::vector<DtwFeatures> feats(n);
    for (size_t i = 0; i < n; ++i) {
      auto a = read_mono_wav((*items)[i].path, 8000, "fsdd");
      if (!a) return tl::unexpected(a.error());
      feats[i] = dtw_features(a->samples, a->rate_hz);
    }
    size_t pairs_total = 0, pairs_done = 0;
    for (const auto& [_, idx] : by_speaker) pairs_total += idx.size() * (idx.size() - 1) / 2;
    for (const auto& [_, idx] : by_speaker) {
      const size_t m = idx.size();
      std::vector<std::vector<double>> dist(m, std::vector<double>(m, 0.0)), scores;
      for (size_t a = 0; a < m; ++a) {
        for (size_t b = a + 1; b < m; ++b)
          dist[a][b] = dist[b][a] = dtw_distance(feats[idx[a]], feats[idx[b]]);
        pairs_done += m - a - 1;
        if (progress && pairs_total)
          progress(decode_share + (1 - decode_share) * static_cast<double>(pairs_done) /
                                      static_cast<double>(pairs_total));
      }
      for (size_t i : idx) scores.push_back(digit_scores[i]);
      const auto votes = neighbour_vote(scores, dist, o.fsdd_vote);
      for (size_t a = 0; a < m; ++a)
        if (votes[a] >= 0) final_hyp[idx[a]] = std::to_string(votes[a]);
    }
    adapt_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  std::vector<std::string> labels;
  for (int i = 0; i < 10; ++i) labels.push_back(std::to_string(i));
  std::map<std::string, std::map<std::string, size_t>> conf;
  std::map<std::string, std::pair<size_t, size_t>> per_speaker, per_speaker_utt, per_digit;
  json records = json::array();
  size_t correct = 0, correct_utt = 0, no_result = 0;
  for (size_t i = 0; i < n; ++i) {
    const AudioItem& it = (*items)[i];
    const bool ok = final_hyp[i] == it.label, ok_utt = hyp[i] == it.label;
    correct += ok;
    correct_utt += ok_utt;
    no_result += final_hyp[i] == "none";
    ++conf[it.label][final_hyp[i]];
    auto& sp = per_speaker[it.speaker];
    sp.first += ok;
    ++sp.second;
    auto& su = per_speaker_utt[it.speaker];
    su.first += ok_utt;
    ++su.second;
    auto& dg = per_digit[it.label];
    dg.first += ok;
    ++dg.second;
    if (o.list_items) {
      json r = {{"clip", it.path.filename().string()},
                {"speaker", it.speaker},
                {"label", it.label},
                {"hypothesis", final_hyp[i]},
                {"words", words_hyp[i]},
                {"score_per_frame", best_score[i]},
                {"correct", ok}};
      if (o.fsdd_speaker_adapt) {
        r["hypothesis_per_utterance"] = hyp[i];
        json sc = json::array();
        for (double v : digit_scores[i]) sc.push_back(std::isfinite(v) ? json(v) : json(nullptr));
        r["digit_scores"] = sc;
      }
      records.push_back(std::move(r));
    }
  }
  eval::EvalReport j;
  j.task = "speech";
  j.dataset = "fsdd";
  j.items = n;
  j.extra["dataset_dir"] = fs::absolute(o.dir).string();
  std::string speakers, vocabulary;
  for (const auto& [s, _] : per_speaker) speakers += (speakers.empty() ? "" : ",") + s;
  for (const auto& w : words) vocabulary += (vocabulary.empty() ? "" : "|") + w;
  j.protocol = fmt::format(
      "isolated digits, closed set, no training on FSDD: {}; words {}; each trimmed clip padded "
      "with {} s of -70 dBFS noise at both ends; {}; speakers {}; take indices {}-{}",
      model_note, vocabulary, pad_s,
      o.fsdd_speaker_adapt
          ? fmt::format("unsupervised batch speaker adaptation: per-word scores, then a vote "
                        "of the <= {} nearest clips of the same speaker within {} x the nearest "
                        "distance (MFCC DTW; temperature {}, weight {}), no labels used",
                        o.fsdd_vote.neighbours, o.fsdd_vote.max_distance_ratio,
                        o.fsdd_vote.temperature, o.fsdd_vote.weight)
          : std::string("each clip decoded on its own"),
      speakers, o.fsdd.first_index, std::min(o.fsdd.last_index, 49));
  json spk = json::object(), spk_utt = json::object();
  for (const auto& [s, c] : per_speaker)
    spk[s] = {{"accuracy", ratio(c.first, c.second)}, {"items", c.second}};
  for (const auto& [s, c] : per_speaker_utt)
    spk_utt[s] = {{"accuracy", ratio(c.first, c.second)}, {"items", c.second}};
  j.metrics = {{"accuracy", ratio(correct, n)},
               {"no_result_rate", ratio(no_result, n)},
               {"per_speaker", spk},
               {"confusion", confusion_json(labels, conf)}};
  // Each clip decoded alone (before the speaker vote): the per-utterance recogniser.
  if (o.fsdd_speaker_adapt)
    j.metrics["per_utterance"] = {{"accuracy", ratio(correct_utt, n)}, {"per_speaker", spk_utt}};
  j.timing = timing_json(decode_s, audio_s, ms);
  j.timing["adaptation_seconds"] = adapt_s;
  j.timing["rtf_with_adaptation"] = audio_s > 0 ? (decode_s + adapt_s) / audio_s : 0.0;
  j.per_class = per_class_json(labels, per_digit);
  if (o.list_items) j.extra["items"] = records;
  return j;
}

}  // namespace

std::filesystem::path commands_model_dir() {
  return fs::path(DREAMSENSE_SPEECH_MODELS_DIR) / "speech_commands";
}

Result<std::vector<std::string>> read_decoy_words(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in)
    return make_error(ErrorCode::kNotFound, "{}: cannot read the decoy words", path.string());
  std::vector<std::string> words;
  for (std::string line; std::getline(in, line);) {
    if (auto h = line.find('#'); h != std::string::npos) line.erase(h);
    std::istringstream ls(line);
    for (std::string w; ls >> w;) words.push_back(w);
  }
  if (words.empty())
    return make_error(ErrorCode::kInvalidArgument, "{}: no decoy words", path.string());
  return words;
}

namespace {

Result<eval::EvalReport> run_speech_commands(const SpeechEvalOptions& o,
                                             const std::function<void(double)>& progress) {
  if (auto st = o.presence.check(); !st) return tl::unexpected(st.error());
  auto items = load_speech_commands(o.dir);
  if (!items) return tl::unexpected(items.error());
  RecognizerOptions ro = o.recognizer;
  // A means-only model decodes from its base model's folder; its decoys stay in its own.
  const fs::path model_folder = ro.means_file.empty() ? ro.model_dir : ro.means_file.parent_path();
  ro.garbage_phone_weight = o.garbage_phone_weight.value_or(kCommandsGarbageWeight);
  ro.min_confidence = o.min_confidence.value_or(kCommandsMinConfidence);
  std::vector<std::string> decoys;
  if (o.decoy_words) {
    decoys = *o.decoy_words;
  } else if (std::error_code ec; fs::exists(model_folder / "decoys.txt", ec)) {
    auto d = read_decoy_words(model_folder / "decoys.txt");
    if (!d) return tl::unexpected(d.error());
    decoys = std::move(*d);
  }
  std::erase_if(decoys, [](const std::string& w) {
    return std::find(std::begin(kCommandWords), std::end(kCommandWords), w) !=
           std::end(kCommandWords);
  });
  std::string jsgf = "#JSGF V1.0;\ngrammar commands;\npublic <command> = ";
  for (size_t i = 0; i < std::size(kCommandWords); ++i)
    jsgf += std::string(i ? " | " : "") + kCommandWords[i];
  for (const auto& w : decoys) jsgf += " | " + w;
  jsgf += ";\n";
  auto grammar = Grammar::from_jsgf(jsgf, "<speech-commands words>");
  if (!grammar) return tl::unexpected(grammar.error());
  auto rec = Recognizer::create(ro, *grammar);
  if (!rec) return tl::unexpected(rec.error());

  std::vector<std::string> labels(std::begin(kCommandWords), std::end(kCommandWords));
  labels.push_back(kUnknownLabel);
  labels.push_back(kSilenceLabel);
  std::map<std::string, std::map<std::string, size_t>> conf;
  std::map<std::string, std::pair<size_t, size_t>> per_label;
  json records = json::array();
  double decode_s = 0, audio_s = 0;
  std::vector<double> ms;
  size_t correct = 0, negatives = 0, false_accepts = 0;
  std::map<std::string, std::pair<size_t, size_t>> fa_by;  // negatives class -> (fa, total)
  // Per clip what a stricter confidence threshold would have decided (the operating curve).
  struct CurvePoint {
    std::string label, word;  // word: the accepted command (empty: silence/unknown/decoy)
    double confidence = 0;
    bool silent = false;  // the silence check's decision
  };
  std::vector<CurvePoint> curve_items;
  for (size_t i = 0; i < items->size(); ++i) {
    const AudioItem& it = (*items)[i];
    auto a = read_mono_wav(it.path, 16000, "speech-commands");
    if (!a) return tl::unexpected(a.error());
    const auto t0 = std::chrono::steady_clock::now();
    const audio::SpeechPresence presence = audio::detect_speech(a->samples, a->rate_hz, o.presence);
    std::string hyp = kSilenceLabel;
    Decoding d;
    if (presence.speech) {
      // Decode the active span plus a margin: the noise around the word is not the
      // recogniser's business (the garbage loop would otherwise have to explain it).
      std::span<const int16_t> span(a->samples);
      if (o.trim_margin_s >= 0) {
        const auto b =
            static_cast<size_t>(std::max(0.0, presence.start_s - o.trim_margin_s) * a->rate_hz);
        const auto e =
            std::min(a->samples.size(),
                     static_cast<size_t>((presence.end_s + o.trim_margin_s) * a->rate_hz));
        if (e > b) span = span.subspan(b, e - b);
      }
      auto r = (*rec)->decode(span, a->rate_hz);
      if (!r) return tl::unexpected(r.error());
      d = *r;
      hyp = d.accepted && !d.grammar_hypothesis.empty() ? d.grammar_hypothesis : kUnknownLabel;
      if (std::find(decoys.begin(), decoys.end(), hyp) != decoys.end()) hyp = kUnknownLabel;
    }
    curve_items.push_back({it.label, hyp == kUnknownLabel || hyp == kSilenceLabel ? "" : hyp,
                           d.confidence, hyp == kSilenceLabel});
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool ok = hyp == it.label;
    correct += ok;
    ++conf[it.label][hyp];
    auto& pl = per_label[it.label];
    pl.first += ok;
    ++pl.second;
    const bool negative = it.label == kUnknownLabel || it.label == kSilenceLabel;
    const bool accepted_word = hyp != kUnknownLabel && hyp != kSilenceLabel;
    if (negative) {
      ++negatives;
      false_accepts += accepted_word;
      fa_by[it.label].first += accepted_word;
      ++fa_by[it.label].second;
    }
    decode_s += sec;
    audio_s += static_cast<double>(a->samples.size()) / a->rate_hz;
    ms.push_back(sec * 1000);
    if (o.list_items)
      records.push_back({{"clip", (it.path.parent_path().filename() / it.path.filename()).string()},
                         {"label", it.label},
                         {"hypothesis", hyp},
                         {"best_grammar_path", d.grammar_hypothesis},
                         {"confidence", d.confidence},
                         {"word_frames", d.last_frame >= 0 ? d.last_frame - d.first_frame + 1 : 0},
                         {"margin_per_frame", d.margin_per_frame},
                         {"voiced_s", presence.voiced_s},
                         {"peak_dbfs", presence.peak_dbfs},
                         {"correct", ok}});
    if (progress) progress(static_cast<double>(i + 1) / items->size());
  }
  eval::EvalReport j;
  j.task = "speech";
  j.dataset = "speech-commands";
  j.items = items->size();
  j.extra["dataset_dir"] = fs::absolute(o.dir).string();
  j.protocol = fmt::format(
      "12 classes (10 words, _unknown_, _silence_): voiced-energy silence check, then "
      "PocketSphinx ({}) under the 10-word grammar{} with phone-loop rejection (garbage weight "
      "{}) and confidence >= {}; rejected{} -> _unknown_",
      model_folder.string(),
      decoys.empty() ? std::string() : fmt::format(" plus {} decoy words", decoys.size()),
      ro.garbage_phone_weight, ro.min_confidence, decoys.empty() ? "" : " or a decoy");
  j.extra["model"] = model_folder.string();
  j.extra["decoy_words"] = decoys;
  j.metrics = {
      {"accuracy", ratio(correct, items->size())},
      {"false_accept_rate", ratio(false_accepts, negatives)},
      {"unknown_false_accept_rate", ratio(fa_by[kUnknownLabel].first, fa_by[kUnknownLabel].second)},
      {"silence_false_accept_rate", ratio(fa_by[kSilenceLabel].first, fa_by[kSilenceLabel].second)},
      {"confusion", confusion_json(labels, conf)}};
  // Accuracy against false accepts for confidence thresholds from the one used upwards (a lower
  // threshold would need a new decode: the joint search already rejected those clips).
  json curve = json::array();
  for (int step = 0; step <= 20; ++step) {
    const double threshold = step * 0.05;
    if (threshold + 1e-9 < ro.min_confidence) continue;
    size_t ok = 0, fa = 0;
    for (const auto& c : curve_items) {
      const bool accept = !c.word.empty() && c.confidence >= threshold;
      const std::string h = accept ? c.word : std::string(c.silent ? kSilenceLabel : kUnknownLabel);
      ok += h == c.label;
      fa += accept && (c.label == kUnknownLabel || c.label == kSilenceLabel);
    }
    curve.push_back({{"min_confidence", threshold},
                     {"accuracy", ratio(ok, curve_items.size())},
                     {"false_accept_rate", ratio(fa, negatives)}});
  }
  j.metrics["operating_curve"] = curve;
  j.timing = timing_json(decode_s, audio_s, ms);
  j.per_class = per_class_json(labels, per_label);
  if (o.list_items) j.extra["items"] = records;
  return j;
}

// Own recordings: a list of utterances with their words (or "-" = must be rejected), all
// decoded under one grammar, with the out-of-grammar rejection as in the session pipeline.
Result<eval::EvalReport> run_list(const SpeechEvalOptions& o,
                                  const std::function<void(double)>& progress) {
  if (o.grammar.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "eval speech: --dataset list needs --grammar FILE (JSGF or SRGS)");
  auto list = load_utterance_list(o.dir, true);
  if (!list) return tl::unexpected(list.error());
  RecognizerOptions ro = o.recognizer;
  if (o.garbage_phone_weight) ro.garbage_phone_weight = *o.garbage_phone_weight;
  if (o.min_confidence) ro.min_confidence = *o.min_confidence;
  auto grammar = Grammar::from_file(o.grammar);
  if (!grammar) return tl::unexpected(grammar.error());
  auto rec = Recognizer::create(ro, *grammar);
  if (!rec) return tl::unexpected(rec.error());
  size_t in_items = 0, in_correct = 0, in_rejected = 0, oog_items = 0, oog_accepted = 0;
  double decode_s = 0, audio_s = 0;
  json items = json::array();
  for (size_t i = 0; i < list->size(); ++i) {
    const ListedUtterance& u = (*list)[i];
    auto a = load_clip(u.audio);
    if (!a)
      return make_error(a.error().code, "{}:{}: {}", o.dir.string(), u.line, a.error().message);
    auto d = (*rec)->decode(a->samples, a->rate);
    if (!d) return tl::unexpected(d.error());
    decode_s += d->decode_seconds;
    audio_s += static_cast<double>(a->samples.size()) / a->rate;
    const std::string hyp = d->accepted ? d->grammar_hypothesis : "";
    const std::string& reference = u.words;  // the loader joins words by single spaces
    bool ok;
    if (u.reject) {
      ok = hyp.empty();
      ++oog_items;
      oog_accepted += !ok;
    } else {
      ok = hyp == reference;
      ++in_items;
      in_correct += ok;
      in_rejected += hyp.empty();
    }
    if (o.list_items) {
      json item = {{"clip", u.audio.string()},    {"line", u.line},
                   {"in_grammar", !u.reject},     {"reference", reference},
                   {"hypothesis", hyp},           {"best_grammar_path", d->grammar_hypothesis},
                   {"confidence", d->confidence}, {"correct", ok}};
      if (hyp.empty() && !d->grammar_hypothesis.empty()) item["rejected"] = true;
      if (!hyp.empty() && grammar->srgs)
        item["tag"] = grammar->srgs->tag_for(split_words(hyp)).value_or("");
      items.push_back(std::move(item));
    }
    if (progress) progress(static_cast<double>(i + 1) / list->size());
  }
  auto rate = [](size_t num, size_t den) -> json {
    return den ? json(static_cast<double>(num) / den) : json(nullptr);
  };
  eval::EvalReport r;
  r.task = "speech";
  r.dataset = "list";
  r.items = list->size();
  r.extra["dataset_path"] = o.dir.string();
  r.protocol = fmt::format(
      "each listed utterance decoded once under {} with out-of-grammar rejection (phone-loop "
      "weight {}, min confidence {}); model {}; in-grammar items must give exactly their words, "
      "'-' items must give nothing",
      o.grammar.string(), ro.garbage_phone_weight, ro.min_confidence, ro.model_dir.string());
  r.metrics = {{"accuracy", rate(in_correct + oog_items - oog_accepted, list->size())},
               {"grammar_sentence_accuracy", rate(in_correct, in_items)},
               {"false_reject_rate", rate(in_rejected, in_items)},
               {"false_accept_rate", rate(oog_accepted, oog_items)},
               {"in_grammar_items", in_items},
               {"out_of_grammar_items", oog_items}};
  r.timing = {{"rtf", audio_s > 0 ? decode_s / audio_s : 0.0}, {"audio_seconds", audio_s}};
  r.per_class = json::object();
  if (o.list_items) r.extra["items"] = std::move(items);
  return r;
}

}  // namespace

Result<eval::EvalReport> run_speech_eval(const SpeechEvalOptions& options,
                                         const std::function<void(double)>& progress) {
  SpeechEvalOptions o = options;
  if (o.dataset == "speech-commands" && o.commands_shipped_model &&
      o.recognizer.model_dir == RecognizerOptions{}.model_dir)
    o.recognizer.model_dir = commands_model_dir();
  // A model folder from `train speech` is decoded with the front end it was adapted with
  // (fsdd: its --fsdd-model folder, handled by fsdd_recognizer).
  if (o.dataset != "fsdd" && fs::exists(o.recognizer.model_dir / kAdaptationFileName))
    if (auto st = use_acoustic_model(o.recognizer, o.recognizer.model_dir); !st)
      return tl::unexpected(st.error());
  if (auto st = o.recognizer.check(); !st) return tl::unexpected(st.error());
  if (o.dataset == "pocketsphinx") return run_pocketsphinx(o, progress);
  if (o.dataset == "fsdd") return run_fsdd(o, progress);
  if (o.dataset == "speech-commands") return run_speech_commands(o, progress);
  if (o.dataset == "list") return run_list(o, progress);
  return make_error(ErrorCode::kUnsupported,
                    "eval speech: dataset layout {} is not supported (pocketsphinx, fsdd, "
                    "speech-commands, list)",
                    o.dataset);
}

}  // namespace dreamsense::speech
