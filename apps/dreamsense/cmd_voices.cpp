// `dreamsense train voices --dataset fsdd|folders DIR --out MODEL [--speakers a,b] [--enroll N]
//                         [--background DIR]`
// `dreamsense eval voices --dataset fsdd|folders DIR [--enroll N] [--unknown a,b] [--model M]
//                        [--json FILE|-]`

#include "dreamsense/eval/voice_eval.hpp"

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {

const char* kVoicesDatasetHelp =
    "NAME DIR; NAME: fsdd (digit_speaker_index.wav, 8 kHz) or folders (DIR/<speaker>/*.wav)";

// Model flags shared by train and eval.
void add_model_flags(CLI::App& cmd, voice_id::VoiceTrainOptions& t) {
  cmd.add_option("--components", t.ubm.components,
                 "Gaussians of the background model (reduced when the data is scarce)")
      ->default_val(t.ubm.components);
  cmd.add_option("--relevance", t.map.relevance, "MAP relevance factor")
      ->default_val(t.map.relevance);
  cmd.add_option("--threshold", t.threshold,
                 "Open set: average log-likelihood ratio (nats/frame) below which a voice is "
                 "unknown")
      ->default_val(t.threshold);
}

struct TrainVoicesFlags {
  std::vector<std::string> dataset;
  std::string out;
  voice_id::VoiceTrainRunOptions options;
};

struct EvalVoicesFlags {
  std::vector<std::string> dataset;
  std::string json;
  voice_id::VoiceEvalOptions options;
};

}  // namespace

void add_train_voices(CLI::App& train, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<TrainVoicesFlags>();
  auto& o = flags->options;
  CLI::App* cmd = train.add_subcommand(
      "voices", "Speaker models (MFCC, GMM-UBM, MAP adaptation) for identifyVoice");
  cmd->add_option("--dataset", flags->dataset, kVoicesDatasetHelp)->expected(2)->required();
  cmd->add_option("--out", flags->out, "Model file to write (YAML)")->required();
  cmd->add_option("--speakers", o.speakers, "Enrol only these speakers (default: all)")
      ->delimiter(',');
  cmd->add_option("--enroll", o.enroll,
                  "Use the first N recordings of each speaker (0 = all of them)")
      ->default_val(o.enroll);
  cmd->add_option("--background", o.background,
                  "Folder of audio for the background model (default: the enrolment audio of "
                  "all speakers pooled)");
  add_model_flags(*cmd, o.train);
  cmd->callback([flags, &g, &exit_code] {
    flags->options.dataset = flags->dataset[0];
    flags->options.dir = flags->dataset[1];
    auto m = with_progress("train voices", g.quiet, [&](const auto& progress) {
      return voice_id::run_voice_train(flags->options, progress);
    });
    if (!m) {
      exit_code = fail(m.error());
      return;
    }
    if (auto s = m->save(flags->out); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (!g.quiet) {
      std::string who;
      for (const auto& s : m->speakers)
        who += fmt::format("{}{} ({} recordings, {:.1f} s of speech)", who.empty() ? "" : ", ",
                           s.id, s.utterances, s.frames * m->features.hop_s);
      std::fprintf(stderr,
                   "voices: %zu speakers enrolled: %s; background model %d Gaussians on "
                   "%s; wrote %s\n",
                   m->speakers.size(), who.c_str(), m->ubm.components(), m->background.c_str(),
                   flags->out.c_str());
    }
  });
}

void add_eval_voices(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalVoicesFlags>();
  auto& o = flags->options;
  CLI::App* cmd = eval.add_subcommand(
      "voices",
      "Speaker identification (GMM-UBM): accuracy (closed set), unknown_reject_rate (--unknown)");
  cmd->add_option("--dataset", flags->dataset, kVoicesDatasetHelp)->expected(2)->required();
  cmd->add_option("--enroll", o.enroll,
                  "First N recordings of each speaker enrol, the rest are tests (with --model: "
                  "skipped)")
      ->default_val(o.enroll);
  cmd->add_option("--speakers", o.speakers, "Only these speakers (default: all)")->delimiter(',');
  cmd->add_option("--unknown", o.unknown,
                  "Speakers held out of enrolment; their recordings should be called unknown")
      ->delimiter(',');
  cmd->add_option("--model", o.model, "Evaluate this model (train voices) instead of enrolling");
  cmd->add_option("--background", o.background,
                  "Folder of audio for the background model (default: the enrolment audio "
                  "pooled)");
  add_model_flags(*cmd, o.train);
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    flags->options.dataset = flags->dataset[0];
    flags->options.dir = flags->dataset[1];
    auto r = with_progress("eval voices", g.quiet, [&](const auto& progress) {
      return voice_id::run_voice_eval(flags->options, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      const auto& m = r->metrics;
      std::string line = fmt::format(
          "voices: {} tests, accuracy {:.4f}, open-set accuracy {:.4f}", r->items,
          m["accuracy"].is_null() ? 0.0 : m["accuracy"].get<double>(),
          m["open_set_accuracy"].is_null() ? 0.0 : m["open_set_accuracy"].get<double>());
      if (m.contains("unknown_reject_rate"))
        line += fmt::format(", unknown_reject_rate {:.4f}", m["unknown_reject_rate"].get<double>());
      std::fprintf(stderr, "%s\n", line.c_str());
    }
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
