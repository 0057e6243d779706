// `dreamsense eval speech --dataset pocketsphinx|fsdd|speech-commands DIR [--json FILE|-]`
// (flags -> speech::SpeechEvalOptions; protocols in modalities/speech/README.md).

#include <cstdio>
#include <sstream>

#include "commands.hpp"
#include "progress.hpp"
#include "speech_eval.hpp"

namespace dreamsense::app {
namespace {
struct EvalSpeechFlags {
  std::vector<std::string> dataset;  // NAME DIR
  speech::SpeechEvalOptions options;
  std::string json, resampler = "soxr", speakers, indices;
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

void print_summary(const nlohmann::json& r) {
  const auto& m = r["metrics"];
  const std::string name = r["dataset"]["name"];
  std::fprintf(stderr, "speech %s: %zu items, accuracy %.3f", name.c_str(),
               r["dataset"]["items"].get<size_t>(), m["accuracy"].get<double>());
  if (m.contains("false_accept_rate"))
    std::fprintf(stderr, ", false_accept_rate %.3f", m["false_accept_rate"].get<double>());
  if (m.contains("grammar_sentence_accuracy"))
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
  std::fprintf(stderr, ", rtf %.3f\n", r["timing"]["rtf"].get<double>());
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
                  "_silence_ of 16 kHz WAVs)")
      ->expected(2)
      ->required();
  auto& r = flags->options.recognizer;
  cmd->add_option("--model", r.model_dir,
                  "PocketSphinx acoustic model folder (pocketsphinx, speech-commands, and fsdd "
                  "with --fsdd-model en-us)")
      ->default_val(r.model_dir.string());
  cmd->add_option("--dict", r.dictionary, "Pronunciation dictionary")
      ->default_val(r.dictionary.string());
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
                  "folder of a TIDIGITS-family model (e.g. adapted by train digits)")
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
  cmd->callback([flags, &g, &exit_code] {
    auto& o = flags->options;
    o.dataset = flags->dataset[0];
    o.dir = flags->dataset[1];
    if (o.dataset != "pocketsphinx" && o.dataset != "fsdd" && o.dataset != "speech-commands") {
      exit_code = fail("eval speech: dataset " + o.dataset +
                       " is not supported (pocketsphinx, fsdd, speech-commands)");
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
    if (flags->pad >= 0) o.pad_seconds = flags->pad;
    if (flags->warp != 0) o.frequency_warp = flags->warp;
    if (!flags->speakers.empty()) {
      std::stringstream ss(flags->speakers);
      std::string s;
      while (std::getline(ss, s, ','))
        if (!s.empty()) o.fsdd.speakers.push_back(s);
    }
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
    if (auto s = write_json(flags->json, *res); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
