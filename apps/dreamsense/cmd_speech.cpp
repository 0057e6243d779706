// `dreamsense eval speech --dataset pocketsphinx|fsdd|speech-commands DIR [--json FILE|-]`
// (flags -> speech::SpeechEvalOptions; protocols in modalities/speech/README.md).
// `dreamsense train speech --dataset fsdd|list PATH --out DIR`: a talker's acoustic model
// (MAP adaptation, speech/acoustic_adaptation.hpp).

#include "dreamsense/eval/speech_eval.hpp"
#include "dreamsense/speech/acoustic_adaptation.hpp"

#include <cstdio>
#include <sstream>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {
struct EvalSpeechFlags {
  std::vector<std::string> dataset;  // NAME DIR
  speech::SpeechEvalOptions options;
  std::string json, resampler = "soxr", speakers, indices, decoys;
  double garbage_weight = 0, min_confidence = -1, pad = -1, warp = 0;
};

Status parse_indices(const std::string& s, speech::FsddSelection& sel) {
  const size_t dash = s.find('-');
  try {
    if (dash == std::string::npos) {
      sel.first_index = sel.last_index = std::stoi(s);
    } else {
      sel.first_index = std::stoi(s.substr(0, dash));
      sel.last_index = std::stoi(s.substr(dash + 1));
    }
  } catch (const std::exception&) {
    return make_error(ErrorCode::kInvalidArgument, "--indices must be N or A-B (got '{}')", s);
  }
  if (sel.first_index < 0 || sel.last_index < sel.first_index)
    return make_error(ErrorCode::kInvalidArgument, "--indices must be N or A-B, A <= B (got '{}')",
                      s);
  return ok_status();
}

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

void print_summary(const eval::EvalReport& r) {
  const auto& m = r.metrics;
  std::fprintf(stderr, "speech %s: %zu items, accuracy %.3f", r.dataset.c_str(), r.items,
               m["accuracy"].get<double>());
  if (m.contains("false_accept_rate") && m["false_accept_rate"].is_number())
    std::fprintf(stderr, ", false_accept_rate %.3f", m["false_accept_rate"].get<double>());
  if (m.contains("false_reject_rate") && m["false_reject_rate"].is_number())
    std::fprintf(stderr, ", false_reject_rate %.3f", m["false_reject_rate"].get<double>());
  if (m.contains("grammar_sentence_accuracy") && m["grammar_sentence_accuracy"].is_number())
    std::fprintf(stderr, ", grammar_sentence_accuracy %.3f",
                 m["grammar_sentence_accuracy"].get<double>());
  if (m.contains("per_speaker"))
    for (const auto& [spk, v] : m["per_speaker"].items())
      std::fprintf(stderr, ", %s %.3f", spk.c_str(), v["accuracy"].get<double>());
  if (m.contains("per_utterance")) {
    std::fprintf(stderr, "; per utterance %.3f", m["per_utterance"]["accuracy"].get<double>());
    for (const auto& [spk, v] : m["per_utterance"]["per_speaker"].items())
      std::fprintf(stderr, ", %s %.3f", spk.c_str(), v["accuracy"].get<double>());
  }
  std::fprintf(stderr, ", rtf %.3f\n", r.timing["rtf"].get<double>());
}
}  // namespace

void add_eval_speech(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalSpeechFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "speech",
      "Speech recognition against a grammar (PocketSphinx, phone-loop rejection): accuracy, "
      "false_accept_rate, per_class recall, rtf");
  cmd->add_option("--dataset", flags->dataset,
                  "NAME DIR; NAME: pocketsphinx (pocketsphinx-testdata layout, e.g. "
                  "/usr/share/pocketsphinx/test/data), fsdd (DIGIT_SPEAKER_INDEX.wav, 8 kHz, in "
                  "DIR or DIR/recordings), speech-commands (class folders yes..go, _unknown_, "
                  "_silence_ of 16 kHz WAVs), list (a text file of your own recordings, one per "
                  "line: AUDIO WORDS... or AUDIO - for speech that must be rejected; needs "
                  "--grammar)")
      ->expected(2)
      ->required();
  auto& r = flags->options.recognizer;
  cmd->add_option("--model", r.model_dir,
                  "PocketSphinx acoustic model folder, also one adapted by train speech "
                  "(pocketsphinx, speech-commands, list, and fsdd with --fsdd-model en-us); "
                  "speech-commands without --model: the shipped model adapted on the "
                  "development clips (modalities/speech/models/speech_commands)")
      ->default_val(r.model_dir.string());
  cmd->add_option("--decoys", flags->decoys,
                  "speech-commands: decoy words decoded beside the commands (a decoy heard = "
                  "_unknown_): FILE (one word per line) or none (default: the model folder's "
                  "decoys.txt)");
  cmd->add_option("--dict", r.dictionary, "Pronunciation dictionary")
      ->default_val(r.dictionary.string());
  cmd->add_option("--grammar", flags->options.grammar,
                  "list: the grammar (JSGF, or SRGS .grxml) the utterances are decoded under")
      ->check(CLI::ExistingFile);
  cmd->add_option("--garbage-weight", flags->garbage_weight,
                  "Phone-loop weight of the rejection branch, (0, 1]; higher rejects more "
                  "(default per layout: pocketsphinx 1, speech-commands " +
                      fmt::format("{}", speech::kCommandsGarbageWeight) + ")");
  cmd->add_option("--min-confidence", flags->min_confidence,
                  "Confidence threshold on accepted words, [0, 1] (default per layout: "
                  "pocketsphinx 0, speech-commands " +
                      fmt::format("{}", speech::kCommandsMinConfidence) + ")");
  cmd->add_flag("!--no-reject", r.reject_out_of_grammar,
                "Grammar only: no out-of-grammar rejection");
  cmd->add_option("--fsdd-model", flags->options.fsdd_model,
                  "fsdd: tidigits (PocketSphinx's TIDIGITS digit model from "
                  "pocketsphinx-testdata, 8 kHz front end), en-us (--model, resampled) or the "
                  "folder of a TIDIGITS-family model (e.g. adapted by train speech)")
      ->default_val(flags->options.fsdd_model);
  cmd->add_option("--speakers", flags->speakers, "fsdd: comma-separated speakers (default all)");
  cmd->add_option("--indices", flags->indices,
                  "fsdd: take indices N or A-B (official split: 0-4 test, 5-49 train)");
  cmd->add_option("--pad", flags->pad,
                  "fsdd: seconds of quiet noise added at both ends of each clip (default " +
                      fmt::format("{}", speech::kFsddPadSeconds) + ")");
  cmd->add_option("--warp", flags->warp,
                  "fsdd: frequency warp of the filter bank (default tidigits " +
                      fmt::format("{}", speech::kFsddTidigitsWarp) + ", en-us 1)");
  cmd->add_flag("--digit-oh", flags->options.fsdd_oh,
                "fsdd: also accept \"oh\" for 0 (FSDD's speakers say \"zero\")");
  cmd->add_flag("--speaker-adapt", flags->options.fsdd_speaker_adapt,
                "fsdd: unsupervised batch speaker adaptation, a vote among the nearest clips of "
                "the same speaker in the evaluated set (transductive, so off by default; both "
                "results are then reported, metrics.per_utterance = before the vote)");
  cmd->add_option("--vote-neighbours", flags->options.fsdd_vote.neighbours,
                  "fsdd: clips of the same speaker in the vote")
      ->default_val(flags->options.fsdd_vote.neighbours);
  cmd->add_option("--vote-ratio", flags->options.fsdd_vote.max_distance_ratio,
                  "fsdd: only neighbours within this factor of the nearest one's DTW distance")
      ->default_val(flags->options.fsdd_vote.max_distance_ratio);
  cmd->add_option("--vote-weight", flags->options.fsdd_vote.weight,
                  "fsdd: weight of the neighbours' evidence (the clip's own: 1)")
      ->default_val(flags->options.fsdd_vote.weight);
  cmd->add_option("--vote-temperature", flags->options.fsdd_vote.temperature,
                  "fsdd: softmax temperature of the per-frame word scores")
      ->default_val(flags->options.fsdd_vote.temperature);
  cmd->add_option("--resampler", flags->resampler,
                  "Rate conversion to the model's rate: soxr (libsoxr VHQ) or sinc (ours)")
      ->default_val(flags->resampler);
  cmd->add_option("--front-end-rate", r.front_end_rate_hz,
                  "MFCC front-end rate in Hz (0 = the model's; 8000 decodes 8 kHz audio without "
                  "upsampling, needs --front-end-upper)");
  cmd->add_option("--front-end-upper", r.front_end_upper_hz,
                  "Upper edge of the mel filters in Hz (0 = the model's)");
  cmd->add_flag("!--no-remove-noise", r.remove_noise,
                "Switch off PocketSphinx's spectral noise subtraction");
  cmd->add_flag("!--no-items", flags->options.list_items,
                "Leave the per-item list out of the JSON");
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([cmd, flags, &g, &exit_code] {
    auto& o = flags->options;
    o.dataset = flags->dataset[0];
    o.dir = flags->dataset[1];
    if (o.dataset != "pocketsphinx" && o.dataset != "fsdd" && o.dataset != "speech-commands" &&
        o.dataset != "list") {
      exit_code = fail("eval speech: dataset " + o.dataset +
                       " is not supported (pocketsphinx, fsdd, speech-commands, list)");
      return;
    }
    auto resampler = speech::parse_resampler(flags->resampler);
    if (!resampler) {
      exit_code = fail(resampler.error());
      return;
    }
    o.recognizer.resampler = *resampler;
    if (flags->garbage_weight != 0) o.garbage_phone_weight = flags->garbage_weight;
    if (flags->min_confidence >= 0) o.min_confidence = flags->min_confidence;
    // speech-commands decodes with the shipped adapted model unless --model names one.
    o.commands_shipped_model = cmd->count("--model") == 0;
    if (flags->decoys == "none") {
      o.decoy_words = std::vector<std::string>{};
    } else if (!flags->decoys.empty()) {
      auto d = speech::read_decoy_words(flags->decoys);
      if (!d) {
        exit_code = fail(d.error());
        return;
      }
      o.decoy_words = std::move(*d);
    }
    if (flags->pad >= 0) o.pad_seconds = flags->pad;
    if (flags->warp != 0) o.frequency_warp = flags->warp;
    o.fsdd.speakers = split_commas(flags->speakers);
    if (!flags->indices.empty())
      if (auto st = parse_indices(flags->indices, o.fsdd); !st) {
        exit_code = fail(st.error());
        return;
      }
    auto res = with_progress("eval speech", g.quiet, [&](const auto& progress) {
      return speech::run_speech_eval(o, progress);
    });
    if (!res) {
      exit_code = fail(res.error());
      return;
    }
    if (!g.quiet) print_summary(*res);
    if (auto s = eval::write_report(*res, flags->json); !s) exit_code = fail(s.error());
  });
}

namespace {
struct TrainSpeechFlags {
  std::vector<std::string> dataset;  // NAME PATH
  std::string out, speakers, indices, fsdd_model = "tidigits";
  std::filesystem::path model = speech::RecognizerOptions{}.model_dir,
                        dict = speech::RecognizerOptions{}.dictionary;
  double warp = 0;
  speech::AcousticAdaptationOptions options;
};
}  // namespace

void add_train_speech(CLI::App& train, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<TrainSpeechFlags>();
  CLI::App* cmd = train.add_subcommand(
      "speech",
      "Adapt a speech recogniser's acoustic model to one talker (MAP of the means with "
      "sphinxtrain) from their utterances with known words; decode with the written folder");
  cmd->add_option("--dataset", flags->dataset,
                  "NAME PATH; NAME: list (a text file, one utterance per line: AUDIO WORDS..., "
                  "AUDIO relative to the file; base model --model/--dict, default en-us) or fsdd "
                  "(a FSDD folder; TIDIGITS model and front end of eval speech --dataset fsdd)")
      ->expected(2)
      ->required();
  cmd->add_option("--out", flags->out, "Folder for the adapted model (new or empty)")->required();
  cmd->add_option("--model", flags->model, "list: base acoustic model folder")
      ->default_val(flags->model.string());
  cmd->add_option("--dict", flags->dict, "list: pronunciation dictionary")
      ->default_val(flags->dict.string());
  cmd->add_option("--speakers", flags->speakers, "fsdd: comma-separated speakers (default all)");
  cmd->add_option("--indices", flags->indices, "fsdd: take indices N or A-B");
  cmd->add_option("--fsdd-model", flags->fsdd_model,
                  "fsdd: base model, tidigits or a TIDIGITS-family folder")
      ->default_val(flags->fsdd_model);
  cmd->add_option("--warp", flags->warp,
                  "fsdd: frequency warp of the front end (default " +
                      fmt::format("{}", speech::kFsddTidigitsWarp) +
                      "); decode the adapted model with the same");
  cmd->add_option("--min-utterances", flags->options.min_utterances, "Fewer utterances is an error")
      ->default_val(flags->options.min_utterances);
  cmd->add_flag("--keep-work", flags->options.keep_work_dir,
                "Keep OUT/work (features, Baum-Welch statistics, tool logs)");
  cmd->callback([flags, &g, &exit_code] {
    const std::string& name = flags->dataset[0];
    const std::filesystem::path path = flags->dataset[1];
    std::vector<speech::AdaptationUtterance> utterances;
    auto& o = flags->options;
    if (name == "fsdd") {
      speech::SpeechEvalOptions eo;
      eo.fsdd_model = flags->fsdd_model;
      if (flags->warp != 0) eo.frequency_warp = flags->warp;
      eo.fsdd.speakers = split_commas(flags->speakers);
      if (!flags->indices.empty())
        if (auto st = parse_indices(flags->indices, eo.fsdd); !st) {
          exit_code = fail(st.error());
          return;
        }
      auto setup = speech::fsdd_recognizer(eo);
      auto items = setup ? speech::load_fsdd(path, eo.fsdd)
                         : Result<std::vector<speech::AudioItem>>(tl::unexpected(setup.error()));
      if (!items) {
        exit_code = fail(items.error());
        return;
      }
      o.recognizer = setup->options;
      auto enrolment = speech::fsdd_enrolment(*items);
      if (!enrolment) {
        exit_code = fail(enrolment.error());
        return;
      }
      utterances = std::move(*enrolment);
    } else if (name == "list") {
      o.recognizer.model_dir = flags->model;
      o.recognizer.dictionary = flags->dict;
      auto list = speech::list_enrolment(path);
      if (!list) {
        exit_code = fail(list.error());
        return;
      }
      utterances = std::move(*list);
    } else {
      exit_code = fail("train speech: dataset " + name + " is not supported (list, fsdd)");
      return;
    }
    auto r = with_progress("train speech", g.quiet, [&](const auto& progress) {
      return speech::adapt_acoustic_model(utterances, o, flags->out, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      std::fprintf(stderr,
                   "train speech: %d utterances (%.1f s of audio, %d aligned) adapted %s in "
                   "%.1f s -> %s\n",
                   r->utterances, r->audio_seconds, r->trained_utterances,
                   o.recognizer.model_dir.c_str(), r->seconds, flags->out.c_str());
      for (const auto& s : r->skipped)
        std::fprintf(stderr, "  not aligned with its words (left out): %s\n", s.c_str());
    }
  });
}

}  // namespace dreamsense::app
