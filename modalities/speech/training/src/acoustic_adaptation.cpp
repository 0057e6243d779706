#include "dreamsense/speech/acoustic_adaptation.hpp"

#include "dreamsense/speech/srgs.hpp"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <fcntl.h>
#include <fstream>
#include <map>
#include <set>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

#include "sendump.hpp"

extern char** environ;

namespace dreamsense::speech {
namespace fs = std::filesystem;

Status AcousticAdaptationOptions::check() const {
  if (auto st = recognizer.check(); !st) return st;
  if (min_utterances < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "acoustic adaptation: min_utterances must be >= 1 (got {})", min_utterances);
  return ok_status();
}

namespace {

// Runs a program (no shell) with stdout and stderr appended to `log`; returns its exit status.
Result<int> run_program(const std::vector<std::string>& argv, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0)
    return make_error(ErrorCode::kIoError, "cannot start {}: {}", argv[0], std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return make_error(ErrorCode::kIoError, "waitpid {} failed", argv[0]);
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string log_tail(const fs::path& log, size_t lines = 3) {
  std::ifstream in(log);
  std::deque<std::string> last;
  std::string l;
  while (std::getline(in, l)) {
    if (l.empty()) continue;
    last.push_back(l);
    if (last.size() > lines) last.pop_front();
  }
  std::string out;
  for (const auto& s : last) out += (out.empty() ? "" : " | ") + s;
  return out;
}

Status run_tool(const std::vector<std::string>& argv, const fs::path& log,
                const std::string& must_log = {}) {
  auto rc = run_program(argv, log);
  if (!rc) return tl::unexpected(rc.error());
  bool logged = must_log.empty();
  if (!logged) {
    std::ifstream in(log);
    std::string l;
    while (!logged && std::getline(in, l)) logged = l.find(must_log) != std::string::npos;
  }
  if (*rc != 0 || !logged)
    return make_error(ErrorCode::kInternal, "acoustic adaptation: {} failed (exit {}); {}: {}",
                      fs::path(argv[0]).filename().string(), *rc, log.string(), log_tail(log));
  return ok_status();
}

// feat.params: "-key value" per line.
std::map<std::string, std::string> read_feat_params(const fs::path& path) {
  std::map<std::string, std::string> p;
  std::ifstream in(path);
  std::string key, value;
  while (in >> key >> value) p[key] = value;
  return p;
}

// bw's feature and model-type flags from the model's feat.params (the decoder's settings), and
// the Gaussian tying map_adapt needs as well.
struct BwFeatures {
  std::vector<std::string> flags;
  std::string tying;  // -ts2cbfn: .semi. | .ptm. | .cont.
};

Result<BwFeatures> bw_features(const std::map<std::string, std::string>& p,
                               const fs::path& model_dir) {
  auto get = [&](const std::string& k, const std::string& def) {
    auto it = p.find(k);
    return it == p.end() ? def : it->second;
  };
  if (p.count("-lda"))
    return make_error(ErrorCode::kUnsupported,
                      "acoustic adaptation: {} uses an LDA/MLLT transform, not supported",
                      model_dir.string());
  BwFeatures b;
  b.flags = {"-feat", get("-feat", "1s_c_d_dd"), "-ceplen",  get("-ncep", "13"),
             "-agc",  get("-agc", "none"),       "-varnorm", get("-varnorm", "no")};
  // The decoder normalises a whole utterance at once (batch = SphinxTrain's "current"); live
  // CMN starts from a prior.
  std::string cmn = get("-cmn", "current");
  if (cmn == "batch") cmn = "current";
  if (cmn == "live") cmn = "prior";
  b.flags.insert(b.flags.end(), {"-cmn", cmn});
  if (p.count("-svspec")) b.flags.insert(b.flags.end(), {"-svspec", p.at("-svspec")});
  const std::string model = get("-model", get("-feat", "") == "s2_4x" ? "semi" : "cont");
  b.tying = model == "semi" ? ".semi." : model == "ptm" ? ".ptm." : ".cont.";
  b.flags.insert(b.flags.end(), {"-ts2cbfn", b.tying});
  if (model == "semi" || model == "ptm") b.flags.insert(b.flags.end(), {"-topn", "4"});
  return b;
}

// The first pronunciation of every word of `words` from the dictionary; missing words listed.
Result<std::string> dictionary_subset(const fs::path& dictionary,
                                      const std::set<std::string>& words) {
  std::ifstream in(dictionary);
  if (!in)
    return make_error(ErrorCode::kNotFound, "pronunciation dictionary not found at {}",
                      dictionary.string());
  std::map<std::string, std::string> found;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string w;
    if (!(ls >> w) || !words.count(w) || found.count(w)) continue;  // also skips "w(2)"
    std::string pron, phone;
    while (ls >> phone && phone[0] != '#') pron += (pron.empty() ? "" : " ") + phone;
    if (!pron.empty()) found[w] = pron;
  }
  std::string missing;
  for (const auto& w : words)
    if (!found.count(w)) missing += (missing.empty() ? "" : ", ") + w;
  if (!missing.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "acoustic adaptation: words not in the dictionary {}: {}",
                      dictionary.string(), missing);
  std::string text;
  for (const auto& [w, pron] : found) text += w + " " + pron + "\n";
  return text;
}

bool valid_id(const std::string& id) {
  if (id.empty() || id.size() > 200) return false;
  for (char c : id)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      return false;
  return true;
}

Status write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) return make_error(ErrorCode::kIoError, "cannot write {}", path.string());
  return ok_status();
}

Result<AdaptationReport> adapt_into(std::span<const AdaptationUtterance> utterances,
                                    const AcousticAdaptationOptions& options,
                                    const fs::path& out_dir, bool& created_out_dir,
                                    const std::function<void(double)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  const RecognizerOptions& ro = options.recognizer;
  const fs::path model = ro.model_dir;

  // Inputs first, so nothing is written for a request that cannot succeed.
  if (static_cast<int>(utterances.size()) < options.min_utterances)
    return make_error(ErrorCode::kInvalidArgument,
                      "acoustic adaptation needs at least {} utterances (got {})",
                      options.min_utterances, utterances.size());
  std::set<std::string> ids, vocabulary;
  std::string fileids, transcription;  // bw's control and transcript files
  double audio_seconds = 0;
  for (const auto& u : utterances) {
    if (!valid_id(u.id))
      return make_error(ErrorCode::kInvalidArgument,
                        "acoustic adaptation: utterance id '{}' must be letters, digits, '_', "
                        "'-' or '.'",
                        u.id);
    if (!ids.insert(u.id).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "acoustic adaptation: utterance id '{}' is used twice", u.id);
    if (u.sample_rate_hz <= 0 || u.samples.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "acoustic adaptation: utterance '{}' has no audio", u.id);
    const auto words = split_words(u.words);
    if (words.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "acoustic adaptation: utterance '{}' has no words", u.id);
    vocabulary.insert(words.begin(), words.end());
    fileids += u.id + "\n";
    transcription += "<s>";
    for (const auto& w : words) transcription += " " + w;
    transcription += fmt::format(" </s> ({})\n", u.id);
    audio_seconds += static_cast<double>(u.samples.size()) / u.sample_rate_hz;
  }
  const fs::path bw = options.sphinxtrain_dir / "bw",
                 map_adapt = options.sphinxtrain_dir / "map_adapt";
  for (const auto& tool : {bw, map_adapt})
    if (access(tool.c_str(), X_OK) != 0)
      return make_error(ErrorCode::kNotFound,
                        "acoustic adaptation: {} not found (install the Debian package "
                        "sphinxtrain)",
                        tool.string());
  if (access(options.mdef_convert.c_str(), X_OK) != 0)
    return make_error(ErrorCode::kNotFound,
                      "acoustic adaptation: {} not found (install the Debian package pocketsphinx)",
                      options.mdef_convert.string());
  for (const char* f : {"mdef", "means", "variances", "transition_matrices", "feat.params"})
    if (!fs::exists(model / f))
      return make_error(ErrorCode::kNotFound, "acoustic adaptation: {} has no {}", model.string(),
                        f);
  if (!fs::exists(model / "sendump") && !fs::exists(model / "mixture_weights"))
    return make_error(ErrorCode::kNotFound,
                      "acoustic adaptation: {} has neither sendump nor mixture_weights",
                      model.string());
  const auto feat_params = read_feat_params(model / "feat.params");
  auto features = bw_features(feat_params, model);
  if (!features) return tl::unexpected(features.error());
  auto dictionary = dictionary_subset(ro.dictionary, vocabulary);
  if (!dictionary) return tl::unexpected(dictionary.error());
  std::error_code ec;
  if (fs::exists(out_dir) && !fs::is_empty(out_dir, ec))
    return make_error(ErrorCode::kInvalidArgument,
                      "acoustic adaptation: {} exists and is not empty (choose a new folder)",
                      out_dir.string());
  created_out_dir = fs::create_directories(out_dir, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "cannot create {}: {}", out_dir.string(), ec.message());
  const fs::path work = out_dir / "work", feat = work / "feat", base = work / "base",
                 accum = work / "accum", mapped = work / "map";
  for (const auto& d : {feat, base, accum, mapped})
    if (fs::create_directories(d, ec); ec)
      return make_error(ErrorCode::kIoError, "cannot create {}: {}", d.string(), ec.message());
  auto report_progress = [&](double p) {
    if (progress) progress(p);
  };

  // 1. Features through the decoder's own front end. Any grammar over the vocabulary will do:
  //    only the logged cepstra are used.
  {
    RecognizerOptions fo = ro;
    fo.reject_out_of_grammar = false;
    fo.confidence_pass = false;  // one pass per utterance: one feature file each
    fo.min_confidence = 0;
    fo.feature_log_dir = feat;
    std::string jsgf = "#JSGF V1.0;\ngrammar enrol;\npublic <word> = ";
    bool first = true;
    for (const auto& w : vocabulary) jsgf += (first ? "" : " | ") + w, first = false;
    auto grammar = Grammar::from_jsgf(jsgf + ";\n", "<enrolment vocabulary>");
    if (!grammar) return tl::unexpected(grammar.error());
    auto recognizer = Recognizer::create(fo, *grammar);
    if (!recognizer) return tl::unexpected(recognizer.error());
    for (size_t k = 0; k < utterances.size(); ++k) {
      const auto& u = utterances[k];
      auto d = (*recognizer)->decode(u.samples, u.sample_rate_hz);
      if (!d) return tl::unexpected(d.error());
      const fs::path logged = feat / fmt::format("{:09}.mfc", k);
      if (!fs::exists(logged))
        return make_error(ErrorCode::kInternal,
                          "acoustic adaptation: PocketSphinx logged no features for '{}' ({})",
                          u.id, logged.string());
      fs::rename(logged, feat / (u.id + ".mfc"), ec);
      if (ec) return make_error(ErrorCode::kIoError, "cannot rename {}", logged.string());
      report_progress(0.6 * static_cast<double>(k + 1) / utterances.size());
    }
  }
  std::string fillers = "<s> SIL\n</s> SIL\n<sil> SIL\n";
  if (fs::exists(model / "noisedict")) {
    std::ifstream in(model / "noisedict");
    fillers.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  for (auto [name, text] :
       {std::pair{"train.fileids", &fileids}, std::pair{"train.transcription", &transcription},
        std::pair{"train.dic", &*dictionary}, std::pair{"fillers.dic", &fillers}})
    if (auto st = write_text(work / name, *text); !st) return tl::unexpected(st.error());

  // 2. The model in SphinxTrain form.
  if (auto st = run_tool({options.mdef_convert.string(), "-text", (model / "mdef").string(),
                          (base / "mdef").string()},
                         work / "mdef_convert.log");
      !st)
    return tl::unexpected(st.error());
  const bool has_mixture_weights = fs::exists(model / "mixture_weights");
  std::vector<std::string> copied = {"means", "variances", "transition_matrices", "feat.params"};
  if (has_mixture_weights) copied.push_back("mixture_weights");
  for (const auto& f : copied) {
    fs::copy_file(model / f, base / f, fs::copy_options::overwrite_existing, ec);
    if (ec)
      return make_error(ErrorCode::kIoError, "cannot copy {}: {}", (model / f).string(),
                        ec.message());
  }
  if (!has_mixture_weights) {
    auto mixw = detail::read_sendump(model / "sendump");
    if (!mixw) return tl::unexpected(mixw.error());
    if (auto st = detail::write_mixture_weights(*mixw, base / "mixture_weights"); !st)
      return tl::unexpected(st.error());
  }

  // 3. Baum-Welch statistics along the transcripts.
  std::vector<std::string> bw_args = {bw.string(),
                                      "-hmmdir",
                                      base.string(),
                                      "-moddeffn",
                                      (base / "mdef").string(),
                                      "-dictfn",
                                      (work / "train.dic").string(),
                                      "-fdictfn",
                                      (work / "fillers.dic").string(),
                                      "-ctlfn",
                                      (work / "train.fileids").string(),
                                      "-lsnfn",
                                      (work / "train.transcription").string(),
                                      "-cepdir",
                                      feat.string(),
                                      "-cepext",
                                      "mfc",
                                      "-accumdir",
                                      accum.string()};
  bw_args.insert(bw_args.end(), features->flags.begin(), features->flags.end());
  if (auto st = run_tool(bw_args, work / "bw.log", "Counts saved"); !st)
    return tl::unexpected(st.error());
  AdaptationReport report;
  {
    // bw reports an utterance it cannot align ("final state ... not reached") as
    // 'ERROR: "baum_welch.c", line N: <id> ignored', before that utterance's "utt>" line.
    std::ifstream in(work / "bw.log");
    std::string line;
    std::set<std::string> skipped;
    int seen = 0;
    while (std::getline(in, line)) {
      if (line.rfind("utt>", 0) == 0) ++seen;
      const std::string suffix = " ignored";
      if (line.rfind("ERROR:", 0) == 0 && line.size() > suffix.size() &&
          line.compare(line.size() - suffix.size(), suffix.size(), suffix) == 0) {
        const size_t colon = line.rfind(": ");
        if (colon != std::string::npos) {
          const std::string id = line.substr(colon + 2, line.size() - suffix.size() - colon - 2);
          if (ids.count(id)) skipped.insert(id);
        }
      }
    }
    report.skipped.assign(skipped.begin(), skipped.end());
    report.trained_utterances = seen - static_cast<int>(skipped.size());
  }
  if (report.trained_utterances <= 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "acoustic adaptation: no utterance could be aligned with its words (are "
                      "the transcripts right? {})",
                      (work / "bw.log").string());
  report_progress(0.9);

  // 4. MAP estimates; the means are kept.
  if (auto st = run_tool({map_adapt.string(),
                          "-moddeffn",
                          (base / "mdef").string(),
                          "-ts2cbfn",
                          features->tying,
                          "-meanfn",
                          (base / "means").string(),
                          "-varfn",
                          (base / "variances").string(),
                          "-mixwfn",
                          (base / "mixture_weights").string(),
                          "-tmatfn",
                          (base / "transition_matrices").string(),
                          "-accumdir",
                          accum.string(),
                          "-mapmeanfn",
                          (mapped / "means").string(),
                          "-mapvarfn",
                          (mapped / "variances").string(),
                          "-mapmixwfn",
                          (mapped / "mixture_weights").string(),
                          "-maptmatfn",
                          (mapped / "transition_matrices").string()},
                         work / "map_adapt.log");
      !st)
    return tl::unexpected(st.error());
  if (!fs::exists(mapped / "means"))
    return make_error(ErrorCode::kInternal, "acoustic adaptation: map_adapt wrote no means ({})",
                      (work / "map_adapt.log").string());

  // 5. The adapted model: the original files with the new means.
  for (const auto& entry : fs::directory_iterator(model)) {
    if (!entry.is_regular_file() || entry.path().filename() == "means") continue;
    fs::copy_file(entry.path(), out_dir / entry.path().filename(),
                  fs::copy_options::overwrite_existing, ec);
    if (ec) return make_error(ErrorCode::kIoError, "cannot copy {}", entry.path().string());
  }
  fs::copy_file(mapped / "means", out_dir / "means", fs::copy_options::overwrite_existing, ec);
  if (ec) return make_error(ErrorCode::kIoError, "cannot write {}", (out_dir / "means").string());

  report.utterances = static_cast<int>(utterances.size());
  report.audio_seconds = audio_seconds;
  report.model_dir = out_dir;
  {
    YAML::Emitter y;
    y.SetDoublePrecision(8);
    y << YAML::Comment("dreamsense acoustic adaptation (MAP of the means; modalities/speech)");
    y << YAML::BeginMap;
    y << YAML::Key << "method" << YAML::Value << "map_means";
    y << YAML::Key << "base_model" << YAML::Value << fs::absolute(model).string();
    y << YAML::Key << "dictionary" << YAML::Value << fs::absolute(ro.dictionary).string();
    y << YAML::Key << "front_end" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "rate_hz" << YAML::Value
      << (ro.front_end_rate_hz > 0 ? ro.front_end_rate_hz : ro.model_rate_hz);
    y << YAML::Key << "upper_hz" << YAML::Value << ro.front_end_upper_hz;
    y << YAML::Key << "frequency_warp" << YAML::Value << ro.frequency_warp;
    y << YAML::Key << "remove_noise" << YAML::Value << ro.remove_noise;
    y << YAML::Key << "remove_silence" << YAML::Value << ro.remove_silence;
    y << YAML::EndMap;
    y << YAML::Key << "utterances" << YAML::Value << report.utterances;
    y << YAML::Key << "trained_utterances" << YAML::Value << report.trained_utterances;
    y << YAML::Key << "not_aligned" << YAML::Value << YAML::Flow << report.skipped;
    y << YAML::Key << "audio_seconds" << YAML::Value << audio_seconds;
    y << YAML::Key << "vocabulary" << YAML::Value << YAML::Flow
      << std::vector<std::string>(vocabulary.begin(), vocabulary.end());
    y << YAML::EndMap;
    if (auto st = write_text(out_dir / kAdaptationFileName, std::string(y.c_str()) + "\n"); !st)
      return tl::unexpected(st.error());
  }
  if (!options.keep_work_dir) fs::remove_all(work, ec);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report_progress(1.0);
  return report;
}

}  // namespace

Result<AdaptationReport> adapt_acoustic_model(std::span<const AdaptationUtterance> utterances,
                                              const AcousticAdaptationOptions& options,
                                              const fs::path& out_dir,
                                              const std::function<void(double)>& progress) {
  bool created = false;
  auto r = adapt_into(utterances, options, out_dir, created, progress);
  // A failed adaptation leaves no half-written model behind (the logs stay when asked for).
  if (!r && created && !options.keep_work_dir) {
    std::error_code ec;
    fs::remove_all(out_dir, ec);
  }
  return r;
}

}  // namespace dreamsense::speech
