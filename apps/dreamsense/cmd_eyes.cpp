// `dreamsense eval eyes --dataset bioid|synthetic-eyes DIR [--method
// improved|daugman|timm_barth|all]
//                      [--count N] [--seed S] [--json FILE|-]`

#include <cstdio>

#include "commands.hpp"
#include "eye_eval.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {
struct EvalEyesFlags {
  std::vector<std::string> dataset;  // NAME DIR
  std::string method = "improved";
  int count = 200;
  uint64_t seed = 1;
  std::string json;
};
}  // namespace

void add_eval_eyes(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalEyesFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "eyes",
      "Eye-centre localisation, BioID protocol (Haar face, dlib landmarks, eye centres; "
      "e = max eye error / inter-ocular distance): acc_e005, acc_e010, acc_e025, "
      "ms_per_face_median");
  cmd->add_option("--dataset", flags->dataset,
                  "NAME DIR; NAME: bioid (BioID_NNNN.pgm + .eye), or synthetic-eyes (first "
                  "writes a synthetic BioID-layout set made from the skimage astronaut portrait "
                  "into DIR, see --count/--seed)")
      ->expected(2)
      ->required();
  cmd->add_option("--method", flags->method,
                  "improved (D4.2 improved integro-differential), daugman, timm_barth, or all "
                  "(the three plus the landmark-centroid reference, in one run)")
      ->default_val("improved")
      ->check(CLI::IsMember(
          {"improved", "improved_integro_differential", "daugman", "timm_barth", "all"}));
  cmd->add_option("--count", flags->count, "synthetic-eyes: number of images")
      ->default_val(200)
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", flags->seed, "synthetic-eyes: seed of the set")->default_val(1);
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    const std::string& name = flags->dataset[0];
    if (name != "bioid" && name != "synthetic-eyes") {
      exit_code = fail("eval eyes: dataset " + name +
                       " is not supported (supported: bioid, synthetic-eyes)");
      return;
    }
    eye_centers::EyeEvalOptions o;
    o.dataset = name;
    o.dir = flags->dataset[1];
    o.methods = {flags->method};
    if (name == "synthetic-eyes") {
      o.generate = eye_centers::SyntheticEyeSetOptions{};
      o.generate->count = flags->count;
      o.generate->seed = flags->seed;
    }
    auto r = with_progress("eval eyes", g.quiet, [&](const auto& progress) {
      return eye_centers::run_eye_eval(o, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      std::fprintf(stderr, "eyes: %zu images (%s), face detection %.3f\n",
                   (*r)["dataset"]["items"].get<size_t>(), name.c_str(),
                   (*r)["metrics"]["face_detection_rate"].get<double>());
      std::fprintf(stderr, "  %-30s %8s %8s %8s %10s %10s\n", "method", "e<=0.05", "e<=0.10",
                   "e<=0.25", "ms/eye", "ms/face");
      auto num = [](const nlohmann::json& v) { return v.is_null() ? -1.0 : v.get<double>(); };
      for (const auto& jm : (*r)["methods"]) {
        const std::string m = jm.get<std::string>();
        const auto& x = (*r)["metrics"][m];
        const auto& t = (*r)["timing"][m];
        std::fprintf(stderr, "  %-30s %8.3f %8.3f %8.3f %10.3f %10.2f\n", m.c_str(),
                     num(x["acc_e005"]), num(x["acc_e010"]), num(x["acc_e025"]),
                     num(t["ms_per_eye_median"]), num(t["ms_per_face_median"]));
      }
    }
    if (auto s = write_json(flags->json, *r); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
