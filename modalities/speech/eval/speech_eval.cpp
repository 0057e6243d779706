#include "speech_eval.hpp"

#include <sndfile.h>

#include <cmath>
#include <fstream>
#include <random>
#include <regex>

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
  if (p.extension() == ".raw") {  // headerless s16le mono 16 kHz
    std::ifstream in(p, std::ios::binary);
    if (!in) return make_error(ErrorCode::kNotFound, "cannot open {}", p.string());
    in.seekg(0, std::ios::end);
    const auto bytes = static_cast<size_t>(in.tellg());
    in.seekg(0);
    c.samples.resize(bytes / 2);
    in.read(reinterpret_cast<char*>(c.samples.data()),
            static_cast<std::streamsize>(c.samples.size() * 2));
    return c;
  }
  SF_INFO info{};
  SNDFILE* sf = sf_open(p.string().c_str(), SFM_READ, &info);
  if (!sf)
    return make_error(ErrorCode::kCorruptData, "cannot read audio {}: {}", p.string(),
                      sf_strerror(nullptr));
  std::vector<int16_t> all(static_cast<size_t>(info.frames) * info.channels);
  sf_read_short(sf, all.data(), static_cast<sf_count_t>(all.size()));
  sf_close(sf);
  c.rate = info.samplerate;
  c.samples.resize(static_cast<size_t>(info.frames));
  for (size_t i = 0; i < c.samples.size(); ++i) c.samples[i] = all[i * info.channels];  // channel 0
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

}  // namespace

Result<json> run_speech_eval(const SpeechEvalOptions& o,
                             const std::function<void(double)>& progress) {
  if (o.dataset != "pocketsphinx")
    return make_error(ErrorCode::kUnsupported,
                      "eval speech: dataset layout {} is not supported (use pocketsphinx)",
                      o.dataset);
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
    auto rec = Recognizer::create(o.recognizer, *grammar);
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
  json j;
  j["task"] = "speech";
  j["dataset"] = {{"name", "pocketsphinx"}, {"items", n}, {"dir", fs::absolute(d).string()}};
  j["protocol"] =
      "grammar recognition, PocketSphinx en-us + phone-loop garbage rejection; in-grammar: "
      "cards/*.wav under cards.gram, goforward.raw under goforward.gram; out-of-grammar per "
      "grammar: the other grammar's utterances, numbers.raw, something.raw, librivox/*.wav, 3 s "
      "silence, 3 s white noise";
  j["metrics"] = {
      {"grammar_sentence_accuracy", in_items ? static_cast<double>(in_correct) / in_items : 0.0},
      {"false_accept_rate", oog_items ? static_cast<double>(oog_accepted) / oog_items : 0.0},
      {"accuracy", n ? static_cast<double>(in_correct + oog_items - oog_accepted) / n : 0.0},
      {"in_grammar_items", in_items},
      {"out_of_grammar_items", oog_items}};
  j["timing"] = {{"rtf", audio_s > 0 ? decode_s / audio_s : 0.0}, {"audio_seconds", audio_s}};
  j["per_class"] = per_class;
  j["items"] = items;
  return j;
}

}  // namespace dreamsense::speech
