// `dreamsense eval speech --dataset pocketsphinx DIR [--garbage-weight W] [--json FILE|-]`

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"
#include "speech_eval.hpp"

namespace dreamsense::app {
namespace {
struct EvalSpeechFlags {
  std::vector<std::string> dataset;  // NAME DIR
  speech::SpeechEvalOptions options;
  std::string json;
};
}  // namespace

void add_eval_speech(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalSpeechFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "speech",
      "Speech recognition against a grammar (PocketSphinx, phone-loop rejection): "
      "grammar_sentence_accuracy, false_accept_rate, accuracy, rtf");
  cmd->add_option("--dataset", flags->dataset,
                  "NAME DIR; NAME: pocketsphinx (pocketsphinx-testdata layout, e.g. "
                  "/usr/share/pocketsphinx/test/data)")
      ->expected(2)
      ->required();
  auto& r = flags->options.recognizer;
  cmd->add_option("--model", r.model_dir, "PocketSphinx acoustic model folder")
      ->default_val(r.model_dir.string());
  cmd->add_option("--dict", r.dictionary, "Pronunciation dictionary")
      ->default_val(r.dictionary.string());
  cmd->add_option("--garbage-weight", r.garbage_phone_weight,
                  "Phone-loop weight of the rejection branch, (0, 1]; higher rejects more")
      ->default_val(r.garbage_phone_weight);
  cmd->add_flag("!--no-reject", r.reject_out_of_grammar,
                "Grammar only: no out-of-grammar rejection");
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    if (flags->dataset[0] != "pocketsphinx") {
      exit_code = fail("eval speech: dataset " + flags->dataset[0] +
                       " is not supported yet (supported: pocketsphinx)");
      return;
    }
    flags->options.dataset = flags->dataset[0];
    flags->options.dir = flags->dataset[1];
    auto r = with_progress("eval speech", g.quiet, [&](const auto& progress) {
      return speech::run_speech_eval(flags->options, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    const auto& m = (*r)["metrics"];
    if (!g.quiet)
      std::fprintf(stderr,
                   "speech: %zu items, grammar_sentence_accuracy %.3f (cards %.3f, goforward "
                   "%.3f), false_accept_rate %.3f, accuracy %.3f, rtf %.3f\n",
                   (*r)["dataset"]["items"].get<size_t>(),
                   m["grammar_sentence_accuracy"].get<double>(),
                   (*r)["per_class"]["cards"]["grammar_sentence_accuracy"].get<double>(),
                   (*r)["per_class"]["goforward"]["grammar_sentence_accuracy"].get<double>(),
                   m["false_accept_rate"].get<double>(), m["accuracy"].get<double>(),
                   (*r)["timing"]["rtf"].get<double>());
    if (auto s = write_json(flags->json, *r); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
