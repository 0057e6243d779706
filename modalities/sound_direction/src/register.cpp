// Declared pipeline entry of the sound-direction analyser (perception/analyzer_registry.hpp).

#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/sound_direction/sound_direction_analyzer.hpp"

#include <fmt/format.h>

namespace dreamsense::sound_direction {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "sound_direction";
  f.summary = "direction of the dominant voice (GCC-PHAT / SRP-PHAT over the array geometry)";
  f.roles = {roles::kMicArray};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    SoundDirectionAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("smoothing_s", o.finder.smoothing_s));
    DS_RETURN_IF_ERROR(options.get("hop", o.finder.hop));
    const StreamDescription* s = ctx.first_with_role(roles::kMicArray);
    if (s == nullptr) return PlannedAnalyzers::skip("no stream with role mic_array");
    PlannedAnalyzers p;
    o.audio_sensor = s->id;
    // The robot's own voice (role robot_audio): no direction while it speaks.
    bool robot_gate = true;
    DS_RETURN_IF_ERROR(options.get("robot_gate", robot_gate));
    DS_RETURN_IF_ERROR(options.get("robot_offset_s", o.robot_gate.offset_s));
    if (const StreamDescription* r = ctx.first_with_role(roles::kRobotAudio); r && robot_gate) {
      o.reference_sensor = r->id;
      p.notes.push_back(fmt::format("robot voice gated with the reference stream '{}'", r->id));
    }
    // Array geometry from the stream's calibration (calib/<id>.yaml: mic positions, rate,
    // extrinsics); Kinect v1 when it has none.
    if (!s->calibration_file.empty()) {
      DS_ASSIGN_OR_RETURN(o.geometry, read_mic_array(s->calibration_file));
    } else {
      o.geometry.sample_rate = s->sample_rate;
      p.notes.push_back(
          fmt::format("audio stream '{}' has no calibration: assuming the Kinect v1 array", s->id));
    }
    if (s->channels != static_cast<int>(o.geometry.mics_m.size()) ||
        s->sample_rate != o.geometry.sample_rate)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: audio stream '{}' has {} channel(s) at {} Hz but its microphone "
                        "array{} has {} microphones at {} Hz",
                        ctx.manifest_path.string(), s->id, s->channels, s->sample_rate,
                        s->calibration_file.empty()
                            ? " (Kinect v1 default)"
                            : " (" + s->calibration_file.filename().string() + ")",
                        o.geometry.mics_m.size(), o.geometry.sample_rate);
    DS_ASSIGN_OR_RETURN(auto analyzer, make_sound_direction_analyzer(o));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::sound_direction
