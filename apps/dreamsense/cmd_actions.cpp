// `dreamsense train actions --dataset utkinect|msr-action3d DIR | demo-gestures SEEDS --out M
//                          [--method baseline|pyramid|pyramid_lda] [--window S]`
// `dreamsense eval actions [--model M] --dataset utkinect|msr-action3d DIR | demo-gestures SEEDS
//                         [--json FILE|-] [--splits N] [--seed N] [--train-seeds A-B]
//                         [--tolerance S] [--methods A,B,...]`
// `dreamsense train gestures --session DIR --segments FILE --out G [--stream ID]`
// Thin: flags -> options -> eval/actions library -> report. Method and numbers:
// modalities/actions/README.md.

#include "dreamsense/eval/action_eval.hpp"
#include "dreamsense/eval/dream_gestures.hpp"

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {

namespace ea = dreamsense::eval::actions;

const char* kActionsDatasetHelp =
    "NAME DIR: utkinect (joints_sSS_eEE.txt + actionLabel.txt), msr-action3d "
    "(aXX_sYY_eZZ_skeleton3D.txt), or demo-gestures SEEDS (the demo generator's DREAM gesture "
    "set, e.g. 300-399)";

struct TrainActionsFlags {
  std::vector<std::string> dataset;
  std::string out, method;  // empty: the dataset's default (below)
  double window_s = 1.0;
};

struct EvalActionsFlags {
  std::vector<std::string> dataset;
  std::string model, json, train_seeds = "300-399";
  int splits = 10;
  uint64_t seed = 1;
  double tolerance_s = 0.3;
  double train_hop_s = 0.2;
  std::vector<std::string> methods;  // empty: every method (the last one is reported)
};

// The named methods, in order (an unknown name is an error naming the known ones).
Result<std::vector<ea::ActionMethod>> methods_by_name(const std::vector<std::string>& names) {
  std::vector<ea::ActionMethod> out;
  for (const auto& n : names) {
    DS_ASSIGN_OR_RETURN(ea::ActionMethod m, ea::method_by_name(n));
    out.push_back(std::move(m));
  }
  return out;
}

struct TrainGesturesFlags {
  std::string session, segments, out, stream;
};

std::string command_line(const std::vector<std::string>& dataset, const std::string& out,
                         const std::string& method, double window_s) {
  std::string s = fmt::format("dreamsense train actions --dataset {} {} --method {}", dataset[0],
                              dataset[1], method);
  if (dataset[0] == "demo-gestures") s += fmt::format(" --window {}", window_s);
  return s + " --out " + out;
}

}  // namespace

void add_train_actions(CLI::App& train, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<TrainActionsFlags>();
  CLI::App* cmd = train.add_subcommand(
      "actions", "Skeleton action classifier (identifyTrajectory) from a dataset or demo seeds");
  cmd->add_option("--dataset", flags->dataset, kActionsDatasetHelp)->expected(2)->required();
  cmd->add_option("--out", flags->out, "Model file to write (YAML)")->required();
  cmd->add_option("--method", flags->method,
                  "pyramid_lda (ours: body-frame joints, temporal pyramid, joint distances, "
                  "shrinkage LDA; the default for utkinect and msr-action3d), pyramid (the same "
                  "without distances, linear SVM; the default for demo-gestures, where it measured "
                  "better) or baseline (the seed's relative joint positions + RBF SVM)");
  cmd->add_option("--window", flags->window_s,
                  "demo-gestures: the online window in seconds (datasets: one window per "
                  "segment)")
      ->default_val(flags->window_s);
  cmd->callback([flags, &g, &exit_code] {
    // modalities/actions/README.md "Measured": LDA wins on the datasets (UTKinect, MSR), the
    // SVM on the DREAM gestures with their rest class.
    if (flags->method.empty())
      flags->method = flags->dataset[0] == "demo-gestures" ? "pyramid" : "pyramid_lda";
    auto method = ea::method_by_name(flags->method);
    if (!method) {
      exit_code = fail(method.error());
      return;
    }
    const std::string description =
        command_line(flags->dataset, flags->out, flags->method, flags->window_s);
    Result<actions::ActionModel> m = make_error(ErrorCode::kInternal, "not run");
    if (flags->dataset[0] == "demo-gestures") {
      auto seeds = ea::parse_seeds(flags->dataset[1]);
      if (!seeds) {
        exit_code = fail(seeds.error());
        return;
      }
      ea::DreamTrainOptions o;
      o.seeds = *seeds;
      o.method = *method;
      o.window_s = flags->window_s;
      m = with_progress("train actions", g.quiet,
                        [&](const auto& progress) { return ea::train_dream_model(o, progress); });
      if (m) m->description = description + " (" + m->description + ")";
    } else {
      ea::ActionTrainOptions o;
      o.dataset = flags->dataset[0];
      o.dir = flags->dataset[1];
      o.method = *method;
      m = with_progress("train actions", g.quiet,
                        [&](const auto& progress) { return ea::run_action_train(o, progress); });
      if (m) m->description = description;
    }
    if (!m) {
      exit_code = fail(m.error());
      return;
    }
    if (auto s = m->save(flags->out); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (!g.quiet) {
      std::string labels;
      for (const auto& l : m->labels()) labels += (labels.empty() ? "" : ", ") + l;
      std::fprintf(stderr,
                   "actions: %d windows (%d skipped), classes %s; window %.2f s; wrote %s\n",
                   m->training_examples(), m->skipped_examples(), labels.c_str(), m->window_s(),
                   flags->out.c_str());
    }
  });
}

void add_eval_actions(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalActionsFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "actions", "Skeleton actions: accuracy, per-class recall, ms_per_window_median");
  cmd->add_option("--dataset", flags->dataset, kActionsDatasetHelp)->expected(2)->required();
  cmd->add_option("--model", flags->model,
                  "Evaluate this model (train actions) on every item instead of the dataset's "
                  "cross-validation");
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->add_option("--splits", flags->splits, "utkinect: random half/half subject splits")
      ->default_val(flags->splits);
  cmd->add_option("--seed", flags->seed, "utkinect: seed of the subject splits")
      ->default_val(flags->seed);
  cmd->add_option("--train-seeds", flags->train_seeds,
                  "demo-gestures without --model: seeds the compared methods train on")
      ->default_val(flags->train_seeds);
  cmd->add_option("--train-hop", flags->train_hop_s,
                  "demo-gestures without --model: seconds between training windows")
      ->default_val(flags->train_hop_s);
  cmd->add_option("--tolerance", flags->tolerance_s,
                  "demo-gestures: seconds around a segment boundary where either label counts")
      ->default_val(flags->tolerance_s);
  cmd->add_option("--methods", flags->methods,
                  "Without --model: the methods compared in one run, the last one reported "
                  "(default: baseline,pyramid,pyramid_lda)")
      ->delimiter(',');
  cmd->callback([flags, &g, &exit_code] {
    Result<eval::EvalReport> r = make_error(ErrorCode::kInternal, "not run");
    auto methods = methods_by_name(flags->methods);
    if (!methods) {
      exit_code = fail(methods.error());
      return;
    }
    if (flags->dataset[0] == "demo-gestures") {
      ea::DreamEvalOptions o;
      auto seeds = ea::parse_seeds(flags->dataset[1]);
      if (!seeds) {
        exit_code = fail(seeds.error());
        return;
      }
      o.seeds = *seeds;
      o.model = flags->model;
      o.tolerance_s = flags->tolerance_s;
      if (flags->model.empty()) {
        auto train = ea::parse_seeds(flags->train_seeds);
        if (!train) {
          exit_code = fail(train.error());
          return;
        }
        o.train_seeds = *train;
        o.train_hop_s = flags->train_hop_s;
        if (!methods->empty()) o.methods = *methods;
      }
      r = with_progress("eval actions", g.quiet,
                        [&](const auto& progress) { return ea::run_dream_eval(o, progress); });
    } else {
      ea::ActionEvalOptions o;
      o.dataset = flags->dataset[0];
      o.dir = flags->dataset[1];
      o.model = flags->model;
      o.splits = flags->splits;
      o.seed = flags->seed;
      if (!methods->empty()) o.methods = *methods;
      r = with_progress("eval actions", g.quiet,
                        [&](const auto& progress) { return ea::run_action_eval(o, progress); });
    }
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      const auto& m = r->metrics;
      std::string line = fmt::format("actions ({}): {} items, accuracy {:.4f}", r->dataset,
                                     r->items, m.value("accuracy", 0.0));
      if (m.contains("loso_accuracy"))
        line += fmt::format(", leave-one-subject-out {:.4f}", m["loso_accuracy"].get<double>());
      if (m.contains("rest_false_positive_rate"))
        line += fmt::format(", rest reported as a gesture {:.4f}",
                            m["rest_false_positive_rate"].get<double>());
      if (m.contains("methods"))
        for (const auto& [name, v] : m["methods"].items())
          line += fmt::format("; {} {:.4f}", name,
                              v.contains("accuracy") ? v["accuracy"].get<double>()
                                                     : v["action_accuracy"].get<double>());
      if (r->timing.contains("ms_per_window_median"))
        line +=
            fmt::format("; {:.3f} ms per window", r->timing["ms_per_window_median"].get<double>());
      std::fprintf(stderr, "%s\n", line.c_str());
    }
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

void add_train_gestures(CLI::App& train, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<TrainGesturesFlags>();
  CLI::App* cmd = train.add_subcommand(
      "gestures",
      "Custom gestures by demonstration (few-shot DTW templates with rejection) from a session");
  cmd->add_option("--session", flags->session, "Session folder with a skeleton stream")->required();
  cmd->add_option("--segments", flags->segments,
                  "Text file, one demonstration per line: start_s end_s label (session clock; "
                  "'#' comments)")
      ->required();
  cmd->add_option("--out", flags->out, "Gestures model to write (YAML)")->required();
  cmd->add_option("--stream", flags->stream, "Skeleton stream id (default: the first)");
  cmd->callback([flags, &g, &exit_code] {
    auto r = ea::train_gestures_from_session(flags->session, flags->segments, {}, flags->stream);
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (auto s = r->model.save(flags->out); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (!g.quiet) {
      for (const auto& l : r->lines) std::fprintf(stderr, "gestures: %s\n", l.c_str());
      std::fprintf(stderr, "gestures: wrote %s\n", flags->out.c_str());
    }
  });
}

}  // namespace dreamsense::app
