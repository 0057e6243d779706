#pragma once
// `dreamsense eval doa`: direction finding on speech simulated in shoebox rooms (image-source
// method, dreamsense::sim) over a grid of azimuths, at one RT60 and SNR. Links dreamsense::sim,
// so it is a separate library from the analyser (which never depends on the simulator).
//
// Protocol (also written into the JSON): for every azimuth of the grid, `placements` items, each
// with its own seeded room (one of three shoebox sizes), array position, source distance
// (horizontal, distance_min_m..distance_max_m) and source height (array height +- height_m), and
// a speech clip from pocketsphinx-testdata. Pink noise is added at `snr_db` relative to the
// speech-active power (as the demo session). The DirectionFinder runs over the whole clip in
// 100 ms chunks; the utterance estimate is the peak of the SRP-PHAT map averaged over the voiced
// frames (VAD of the finder). Frame-level numbers use the smoothed per-frame estimate of voiced
// frames inside the clip's speech extent. cpu_fraction = thread CPU time spent in the finder /
// seconds of multichannel audio given to it (simulation excluded).

#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/report.hpp"
#include "dreamsense/sound_direction/direction_finder.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

namespace dreamsense::sound_direction {

struct DoaEvalOptions {
  std::string geometry = "kinect1";
  double rt60_s = 0.3;  // 0 = anechoic
  double snr_db = 10;
  double azimuth_from_deg = -60, azimuth_to_deg = 60, azimuth_step_deg = 10;
  int placements = 3;  // items per azimuth
  double distance_min_m = 1.0, distance_max_m = 2.2;
  double height_m = 0.2;  // source height offset from the array, uniform in [-h, h]
  uint64_t seed = 1;
  std::filesystem::path clips_dir = "/usr/share/pocketsphinx/test/data";  // pocketsphinx-testdata
  DirectionFinderOptions finder;
  Status check() const;
};

// Parses "FROM:TO:STEP" (degrees) into the options.
Status parse_azimuth_grid(const std::string& text, DoaEvalOptions& options);

// The eval JSON of docs (cli.md): task, dataset, protocol, metrics (mae_deg, within_10deg,
// frame_mae_deg, frame_within_10deg, voiced_fraction), timing (cpu_fraction, ...), per_class
// (per azimuth), and extra keys confidence_calibration (per confidence bin: frames,
// within_10deg) and items.
Result<eval::EvalReport> run_doa_eval(const DoaEvalOptions& options,
                                      const std::function<void(double)>& progress = nullptr);

}  // namespace dreamsense::sound_direction
