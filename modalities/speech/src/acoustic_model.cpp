#include "dreamsense/speech/acoustic_model.hpp"

#include <yaml-cpp/yaml.h>

namespace dreamsense::speech {
namespace fs = std::filesystem;

Status use_acoustic_model(RecognizerOptions& options, const fs::path& model_dir) {
  const fs::path dir = model_dir;  // a copy: callers pass options.model_dir, changed below
  const fs::path provenance = dir / kAdaptationFileName;
  const bool means_only = !fs::exists(dir / "mdef") && fs::exists(dir / "means");
  if (!fs::exists(dir / "mdef") && !(means_only && fs::exists(provenance)))
    return make_error(ErrorCode::kNotFound, "speech: no acoustic model (mdef) in {}", dir.string());
  options.model_dir = dir;
  options.means_file.clear();
  if (!fs::exists(provenance)) return ok_status();
  try {
    const YAML::Node y = YAML::LoadFile(provenance.string());
    if (means_only) {
      if (!y["base_model"])
        return make_error(ErrorCode::kCorruptData, "{}: a means-only model needs base_model",
                          provenance.string());
      const fs::path base = y["base_model"].as<std::string>();
      if (!fs::exists(base / "mdef"))
        return make_error(ErrorCode::kNotFound,
                          "{}: base model {} is not installed (Debian package "
                          "pocketsphinx-en-us)",
                          provenance.string(), base.string());
      options.model_dir = base;
      options.means_file = dir / "means";
    }
    const YAML::Node fe = y["front_end"];
    if (!fe) return ok_status();
    const int rate =
        options.front_end_rate_hz > 0 ? options.front_end_rate_hz : options.model_rate_hz;
    if (fe["rate_hz"] && fe["rate_hz"].as<int>() != rate)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: the model was adapted with a {} Hz front end, this recogniser runs "
                        "at {} Hz",
                        provenance.string(), fe["rate_hz"].as<int>(), rate);
    if (fe["frequency_warp"]) options.frequency_warp = fe["frequency_warp"].as<double>();
    if (fe["remove_noise"]) options.remove_noise = fe["remove_noise"].as<bool>();
    if (fe["remove_silence"]) options.remove_silence = fe["remove_silence"].as<bool>();
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", provenance.string(), e.what());
  }
  return options.check();
}

}  // namespace dreamsense::speech
