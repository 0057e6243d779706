#include "ps_backend.hpp"

#include <array>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <pocketsphinx.h>
#include <regex>
#include <sphinxbase/err.h>
#include <sphinxbase/fsg_model.h>
#include <sphinxbase/jsgf.h>
#include <sphinxbase/logmath.h>
#include <sstream>
#include <vector>

namespace dreamsense::speech::detail {
namespace {

// The 39 phones of the CMU dictionary (the en-us model's context-independent units).
constexpr std::array<const char*, 39> kPhones = {
    "AA", "AE", "AH", "AO", "AW", "AY", "B",  "CH", "D", "DH", "EH", "ER", "EY",
    "F",  "G",  "HH", "IH", "IY", "JH", "K",  "L",  "M", "N",  "NG", "OW", "OY",
    "P",  "R",  "S",  "SH", "T",  "TH", "UH", "UW", "V", "W",  "Y",  "Z",  "ZH"};
constexpr const char* kGarbagePrefix = "__garbage_";

std::string garbage_word(const char* phone) {
  std::string w = kGarbagePrefix;
  for (const char* p = phone; *p; ++p) w += static_cast<char>(std::tolower(*p));
  return w;
}
bool is_garbage(const std::string& w) { return w.rfind(kGarbagePrefix, 0) == 0; }
bool is_filler(const std::string& w) {
  return w.empty() || w[0] == '<' || w[0] == '[' || w == "(NULL)";
}

// Compiles JSGF to sphinxbase FSG text (sphinxbase's own compiler), capturing its error lines.
Result<std::string> jsgf_to_fsg_text(const std::string& jsgf, const std::string& source,
                                     logmath_t* lmath, float lw) {
  FILE* log = std::tmpfile();
  err_set_logfp(log);
  jsgf_t* j = jsgf_parse_string(jsgf.c_str(), nullptr);
  jsgf_rule_t* rule = j ? jsgf_get_public_rule(j) : nullptr;
  fsg_model_t* fsg = rule ? jsgf_build_fsg(j, rule, lmath, lw) : nullptr;
  err_set_logfp(nullptr);
  std::string messages;
  if (log) {
    std::rewind(log);
    char buf[512];
    while (std::fgets(buf, sizeof buf, log)) {
      std::string l(buf);
      if (l.find("ERROR") != std::string::npos && messages.empty()) {
        while (!l.empty() && (l.back() == '\n' || l.back() == '\r')) l.pop_back();
        // 'ERROR: "jsgf_parser.y", line 155: syntax error at line 1634168176 current token ...':
        // drop the source-file prefix; sphinxbase's own "at line N" is not reliable, drop it.
        if (const size_t at = l.find("\", line "); at != std::string::npos) {
          const size_t colon = l.find(": ", at);
          if (colon != std::string::npos) l = l.substr(colon + 2);
        }
        static const std::regex bogus_line(R"( at line -?[0-9]+)");
        messages = std::regex_replace(l, bogus_line, "");
        messages.insert(messages.begin(),
                        ' ');  // (not " " + ...: GCC 12 -Wrestrict false positive)
      }
    }
    std::fclose(log);
  }
  if (fsg && !messages.empty()) {  // e.g. an undefined rule: sphinxbase logs it, builds anyway
    fsg_model_free(fsg);
    fsg = nullptr;
  }
  if (!fsg) {
    if (j) jsgf_grammar_free(j);
    if (!j || !rule)
      return make_error(ErrorCode::kCorruptData, "{}: invalid JSGF grammar{}{}", source,
                        messages.empty() ? "" : ":", messages);
    return make_error(ErrorCode::kCorruptData, "{}: cannot compile JSGF grammar{}{}", source,
                      messages.empty() ? "" : ":", messages);
  }
  char* buf = nullptr;
  size_t len = 0;
  FILE* ms = open_memstream(&buf, &len);
  fsg_model_write(fsg, ms);
  std::fclose(ms);
  std::string text(buf, len);
  std::free(buf);
  fsg_model_free(fsg);
  jsgf_grammar_free(j);
  return text;
}

// Adds a garbage state looping over all phones between the start and the final state.
// With grammar == false the grammar's transitions are dropped (garbage branch alone).
std::string add_garbage(const std::string& fsg_text, double phone_weight, bool keep_grammar) {
  std::istringstream in(fsg_text);
  std::string line, out;
  int n = 0, start = 0, final_state = 0;
  while (std::getline(in, line)) {
    if (line.rfind("NUM_STATES", 0) == 0) {
      n = std::stoi(line.substr(10));
      out += fmt::format("NUM_STATES {}\n", n + 1);
      continue;
    }
    if (line.rfind("START_STATE", 0) == 0) start = std::stoi(line.substr(11));
    if (line.rfind("FINAL_STATE", 0) == 0) final_state = std::stoi(line.substr(11));
    if (line.rfind("TRANSITION", 0) == 0 && !keep_grammar) continue;
    if (line.rfind("FSG_END", 0) == 0) {
      for (const char* p : kPhones) {
        const std::string w = garbage_word(p);
        out += fmt::format("TRANSITION {} {} {} {}\n", start, n, phone_weight, w);
        out += fmt::format("TRANSITION {} {} {} {}\n", n, n, phone_weight, w);
      }
      out += fmt::format("TRANSITION {} {} 1.0\n", n, final_state);
    }
    out += line + "\n";
  }
  return out;
}

fsg_model_t* read_fsg(const std::string& text, logmath_t* lmath, float lw) {
  FILE* f = fmemopen(const_cast<char*>(text.data()), text.size(), "r");
  if (!f) return nullptr;
  fsg_model_t* fsg = fsg_model_read(f, lmath, lw);
  std::fclose(f);
  return fsg;
}

}  // namespace

PsDecoder::~PsDecoder() {
  if (ps_) ps_free(static_cast<ps_decoder_t*>(ps_));
}

Result<std::unique_ptr<PsDecoder>> PsDecoder::create(const PsConfig& c) {
  const std::string rate = std::to_string(c.rate_hz);
  cmd_ln_t* config =
      cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", c.model_dir.c_str(), "-dict",
                  c.dictionary.c_str(), "-samprate", rate.c_str(), "-logfn", "/dev/null", nullptr);
  if (!config) return make_error(ErrorCode::kInternal, "pocketsphinx: bad configuration");
  std::unique_ptr<PsDecoder> d(new PsDecoder());
  ps_decoder_t* ps = ps_init(config);
  cmd_ln_free_r(config);  // the decoder keeps its own reference
  if (!ps)
    return make_error(ErrorCode::kCorruptData,
                      "pocketsphinx could not load the model {} / {} (Debian package "
                      "pocketsphinx-en-us)",
                      c.model_dir, c.dictionary);
  d->ps_ = ps;
  logmath_t* lmath = ps_get_logmath(ps);
  const float lw = cmd_ln_float32_r(ps_get_config(ps), "-lw");

  auto fsg_text = jsgf_to_fsg_text(c.jsgf, c.source, lmath, lw);
  if (!fsg_text) return tl::unexpected(fsg_text.error());

  // Every grammar word must be pronounceable.
  {
    fsg_model_t* plain = read_fsg(*fsg_text, lmath, lw);
    if (!plain)
      return make_error(ErrorCode::kInternal, "{}: cannot re-read compiled grammar", c.source);
    std::vector<std::string> missing;
    for (int i = 0; i < fsg_model_n_word(plain); ++i) {
      const char* w = fsg_model_word_str(plain, i);
      if (!w || is_filler(w)) continue;
      char* pron = ps_lookup_word(ps, w);
      if (!pron) missing.push_back(w);
      std::free(pron);
    }
    fsg_model_free(plain);
    if (!missing.empty()) {
      std::string list;
      for (size_t i = 0; i < missing.size(); ++i) list += (i ? ", " : "") + missing[i];
      return make_error(ErrorCode::kInvalidArgument, "{}: words not in the dictionary {}: {}",
                        c.source, c.dictionary, list);
    }
  }
  for (const char* p : kPhones)
    if (ps_add_word(ps, garbage_word(p).c_str(), p, TRUE) < 0)
      return make_error(ErrorCode::kInternal, "pocketsphinx: cannot add garbage word for {}", p);

  const std::string main_text =
      c.reject ? add_garbage(*fsg_text, c.garbage_phone_weight, true) : *fsg_text;
  const std::string garbage_text = add_garbage(*fsg_text, c.garbage_phone_weight, false);
  for (auto [name, text] :
       {std::pair{"grammar", &main_text}, std::pair{"garbage", &garbage_text}}) {
    fsg_model_t* fsg = read_fsg(*text, lmath, lw);
    if (!fsg || ps_set_fsg(ps, name, fsg) < 0) {
      if (fsg) fsg_model_free(fsg);
      return make_error(ErrorCode::kInternal, "{}: pocketsphinx rejected the compiled grammar",
                        c.source);
    }
    fsg_model_free(fsg);  // the search keeps its own reference
  }
  return d;
}

Result<PsPass> PsDecoder::run(bool garbage_only, std::span<const int16_t> s) {
  auto* ps = static_cast<ps_decoder_t*>(ps_);
  const char* search = garbage_only ? "garbage" : "grammar";
  if (ps_set_search(ps, search) < 0)
    return make_error(ErrorCode::kInternal, "pocketsphinx: cannot select search {}", search);
  if (ps_start_utt(ps) < 0)
    return make_error(ErrorCode::kInternal, "pocketsphinx: ps_start_utt failed");
  if (!s.empty() && ps_process_raw(ps, s.data(), s.size(), FALSE, TRUE) < 0) {
    ps_end_utt(ps);
    return make_error(ErrorCode::kInternal, "pocketsphinx: ps_process_raw failed");
  }
  if (ps_end_utt(ps) < 0)
    return make_error(ErrorCode::kInternal, "pocketsphinx: ps_end_utt failed");
  PsPass p;
  int32 score = 0;
  const char* hyp = ps_get_hyp(ps, &score);
  p.score = score;
  if (!hyp) return p;
  bool garbage = false;
  std::string words;
  for (ps_seg_t* seg = ps_seg_iter(ps); seg; seg = ps_seg_next(seg)) {
    const std::string w = ps_seg_word(seg);
    if (is_filler(w)) continue;
    p.any_word = true;
    if (is_garbage(w)) {
      garbage = true;
      continue;
    }
    int sf = 0, ef = 0;
    ps_seg_frames(seg, &sf, &ef);
    if (p.first < 0) p.first = sf;
    p.last = ef;
    words += (words.empty() ? "" : " ") + w;
  }
  if (!garbage) p.hyp = words;
  return p;
}

}  // namespace dreamsense::speech::detail
