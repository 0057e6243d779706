#include "ps_backend.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <pocketsphinx.h>
#include <regex>
#include <set>
#include <sphinxbase/err.h>
#include <sphinxbase/fsg_model.h>
#include <sphinxbase/jsgf.h>
#include <sphinxbase/logmath.h>
#include <sstream>
#include <unistd.h>
#include <vector>

namespace dreamsense::speech::detail {
namespace {

// The garbage loop runs over every phone the dictionary uses (the 39 CMU phones for
// cmudict-en-us; the whole-word digit units for the TIDIGITS model).
Result<std::vector<std::string>> dictionary_phones(const std::string& dictionary) {
  static std::mutex mutex;
  static std::map<std::string, std::vector<std::string>> cache;
  std::lock_guard lock(mutex);
  if (auto it = cache.find(dictionary); it != cache.end()) return it->second;
  std::ifstream in(dictionary);
  if (!in)
    return make_error(ErrorCode::kNotFound, "pocketsphinx: cannot read dictionary {}", dictionary);
  std::set<std::string> phones;
  std::string line, word, phone;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == ';' || line[0] == '#') continue;
    std::istringstream ls(line);
    ls >> word;
    while (ls >> phone) {
      if (phone[0] == '#') break;  // trailing comment
      phones.insert(phone);
    }
  }
  if (phones.empty())
    return make_error(ErrorCode::kCorruptData, "pocketsphinx: no pronunciations in {}", dictionary);
  return cache[dictionary] = std::vector<std::string>(phones.begin(), phones.end());
}

constexpr const char* kGarbagePrefix = "__garbage_";

std::string garbage_word(const std::string& phone) {
  std::string w = kGarbagePrefix;
  for (char c : phone) w += static_cast<char>(std::tolower(c));
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
std::string add_garbage(const std::string& fsg_text, const std::vector<std::string>& phones,
                        double phone_weight, bool keep_grammar) {
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
      for (const auto& p : phones) {
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

// A copy of the model's feat.params with some values replaced, in a temporary file.
Result<std::string> featparams_with(const std::string& model_dir,
                                    const std::map<std::string, std::string>& values) {
  std::ifstream in(model_dir + "/feat.params");
  std::string text, line;
  std::set<std::string> done;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (auto it = values.find(key); it != values.end()) {
      line = key + " " + it->second;
      done.insert(key);
    }
    text += line + "\n";
  }
  for (const auto& [k, v] : values)
    if (!done.count(k)) text += k + " " + v + "\n";
  char path[] = "/tmp/dreamsense_featparams_XXXXXX";
  const int fd = mkstemp(path);
  if (fd < 0)
    return make_error(ErrorCode::kIoError, "pocketsphinx: cannot create a temporary feat.params");
  const bool ok = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  close(fd);
  if (!ok) {
    std::remove(path);
    return make_error(ErrorCode::kIoError, "pocketsphinx: cannot write {}", path);
  }
  return std::string(path);
}

fsg_model_t* read_fsg(const std::string& text, logmath_t* lmath, float lw) {
  FILE* f = fmemopen(const_cast<char*>(text.data()), text.size(), "r");
  if (!f) return nullptr;
  fsg_model_t* fsg = fsg_model_read(f, lmath, lw);
  std::fclose(f);
  return fsg;
}

}  // namespace

Result<std::string> compile_jsgf(const std::string& jsgf, const std::string& source,
                                 const std::vector<std::string>& garbage_phones) {
  // PocketSphinx's defaults (-logbase 1.0001, -lw 6.5): the decoder compiles with its own.
  logmath_t* lmath = logmath_init(1.0001, 0, 0);
  if (!lmath) return make_error(ErrorCode::kInternal, "sphinxbase: logmath_init failed");
  const float lw = 6.5f;
  auto text = jsgf_to_fsg_text(jsgf, source, lmath, lw);
  Result<std::string> out = text;
  if (text) {
    fsg_model_t* plain = read_fsg(*text, lmath, lw);
    if (!plain)
      out = make_error(ErrorCode::kInternal, "{}: cannot re-read compiled grammar", source);
    else
      fsg_model_free(plain);
    if (out && !garbage_phones.empty()) out = add_garbage(*text, garbage_phones, 1.0, true);
  }
  logmath_free(lmath);
  return out;
}

PsDecoder::~PsDecoder() {
  if (ps_) ps_free(static_cast<ps_decoder_t*>(ps_));
}

Result<std::unique_ptr<PsDecoder>> PsDecoder::create(const PsConfig& c) {
  const std::string rate = std::to_string(c.rate_hz);
  // ps_init() applies the model's feat.params (-upperf 6800 ...) over anything set here, so a
  // different upper filter edge (narrow-band front end) needs its own copy of feat.params.
  std::map<std::string, std::string> feat;
  if (c.upper_hz > 0) feat["-upperf"] = fmt::format("{}", c.upper_hz);
  std::string featparams;
  if (!feat.empty()) {
    auto f = featparams_with(c.model_dir, feat);
    if (!f) return tl::unexpected(f.error());
    featparams = *f;
  }
  struct Unlink {
    const std::string& p;
    ~Unlink() {
      if (!p.empty()) std::remove(p.c_str());
    }
  } unlink_featparams{featparams};
  cmd_ln_t* config = cmd_ln_init(
      nullptr, ps_args(), TRUE, "-hmm", c.model_dir.c_str(), "-dict", c.dictionary.c_str(),
      "-samprate", rate.c_str(), "-logfn", "/dev/null", "-remove_silence",
      c.remove_silence ? "yes" : "no", "-remove_noise", c.remove_noise ? "yes" : "no",
      featparams.empty() ? nullptr : "-featparams", featparams.c_str(), nullptr);
  if (!config) return make_error(ErrorCode::kInternal, "pocketsphinx: bad configuration");
  if (c.frequency_warp != 1.0) {
    const std::string warp = fmt::format("{}", c.frequency_warp);
    cmd_ln_set_str_r(config, "-warp_type", "inverse_linear");
    cmd_ln_set_str_r(config, "-warp_params", warp.c_str());
  }
  if (!c.mfc_log_dir.empty()) cmd_ln_set_str_r(config, "-mfclogdir", c.mfc_log_dir.c_str());
  if (!c.means_file.empty()) cmd_ln_set_str_r(config, "-mean", c.means_file.c_str());
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
  auto phones = dictionary_phones(c.dictionary);
  if (!phones) return tl::unexpected(phones.error());
  for (const auto& p : *phones)
    if (ps_add_word(ps, garbage_word(p).c_str(), p.c_str(), TRUE) < 0)
      return make_error(ErrorCode::kCorruptData,
                        "pocketsphinx: phone {} of {} is not in the acoustic model {}", p,
                        c.dictionary, c.model_dir);

  const std::string main_text =
      c.reject ? add_garbage(*fsg_text, *phones, c.garbage_phone_weight, true) : *fsg_text;
  const std::string garbage_text = add_garbage(*fsg_text, *phones, c.garbage_phone_weight, false);
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
    std::string w = ps_seg_word(seg);
    if (is_filler(w)) continue;
    // Alternative pronunciations come back as "one(2)": report the word.
    if (const size_t paren = w.find('(');
        paren != std::string::npos && paren > 0 && w.back() == ')')
      w.erase(paren);
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
