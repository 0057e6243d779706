// `dreamsense eval doa [--geometry kinect1] [--rt60 S] [--snr DB] [--azimuths FROM:TO:STEP]
//                      [--placements N] [--seed N] [--json FILE|-]`

#include "dreamsense/eval/doa_eval.hpp"
#include "dreamsense/sound_direction/direction_finder.hpp"

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {
struct EvalDoaFlags {
  sound_direction::DoaEvalOptions options;
  std::string azimuths = "-60:60:10";
  std::string json;
};
}  // namespace

void add_eval_doa(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalDoaFlags>();
  CLI::App* cmd = eval.add_subcommand(
      "doa",
      "Sound direction finding on speech simulated in shoebox rooms (image-source method) over "
      "a grid of azimuths: mae_deg, within_10deg, cpu_fraction");
  auto& o = flags->options;
  cmd->add_option("--geometry", o.geometry, "Microphone array geometry")
      ->default_val("kinect1")
      ->check(CLI::IsMember({"kinect1"}));
  cmd->add_option("--rt60", o.rt60_s, "Room reverberation time RT60 (s; 0 = anechoic)")
      ->default_val(0.3);
  cmd->add_option("--snr", o.snr_db, "Speech-to-noise ratio (dB, pink noise)")->default_val(10.0);
  cmd->add_option("--azimuths", flags->azimuths, "Azimuth grid FROM:TO:STEP (degrees)")
      ->default_val("-60:60:10");
  cmd->add_option("--placements", o.placements, "Seeded rooms/placements per azimuth")
      ->default_val(3);
  cmd->add_option("--seed", o.seed, "Seed of the placements and noise")->default_val(1);
  cmd->add_option("--clips", o.clips_dir, "pocketsphinx-testdata folder with the speech clips")
      ->default_val(o.clips_dir.string());
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    if (auto s = sound_direction::parse_azimuth_grid(flags->azimuths, flags->options); !s) {
      exit_code = fail(s.error());
      return;
    }
    auto r = with_progress("eval doa", g.quiet, [&](const auto& progress) {
      return sound_direction::run_doa_eval(flags->options, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    const auto& m = r->metrics;
    if (!g.quiet)
      std::fprintf(stderr,
                   "doa: %zu items, mae %.2f deg, within 10 deg %.3f, frame mae %.2f deg, "
                   "cpu_fraction %.4f\n",
                   r->items, m["mae_deg"].is_null() ? -1.0 : m["mae_deg"].get<double>(),
                   m["within_10deg"].get<double>(), m["frame_mae_deg"].get<double>(),
                   r->timing["cpu_fraction"].get<double>());
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
