// Declared pipeline entry of the voice identification analyser (perception/analyzer_registry.hpp).

#include "dreamsense/audio/mic_array.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/voice_id/audio_files.hpp"
#include "dreamsense/voice_id/voice_id_analyzer.hpp"

#include <fmt/format.h>

namespace dreamsense::voice_id {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "voice_id";
  f.summary =
      "who spoke (GMM-UBM speaker models from the session's enrolment audio, or DREAM's "
      "direction rule)";
  f.roles = {roles::kMicArray};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    // method: gmm_ubm (speaker models: `model`, or trained here from the session's enrolment
    // audio, metadata voice_enroll) or direction_rule (DREAM's rule on the sound direction).
    std::string method_name = to_string(VoiceIdMethod::kGmmUbm);
    std::filesystem::path model_file;
    DS_RETURN_IF_ERROR(options.get("method", method_name));
    DS_RETURN_IF_ERROR(options.get("model", model_file));
    // Noise suppression in the speaker models trained here from the enrolment (a model file
    // says itself whether it was trained with it).
    bool noise_suppression = VoiceTrainOptions{}.features.noise_suppression;
    DS_RETURN_IF_ERROR(options.get("noise_suppression", noise_suppression));
    DS_ASSIGN_OR_RETURN(const VoiceIdMethod method, parse_voice_id_method(method_name));
    const StreamDescription* s = ctx.first_with_role(roles::kMicArray);
    if (s == nullptr) return PlannedAnalyzers::skip("no stream with role mic_array");
    VoiceIdAnalyzerOptions o;
    o.audio_sensor = s->id;
    o.method = method;
    o.include_names = ctx.include_names;
    PlannedAnalyzers p;
    // The robot's own voice (role robot_audio): gated out (audio/reference_gate.hpp).
    bool robot_gate = true;
    DS_RETURN_IF_ERROR(options.get("robot_gate", robot_gate));
    DS_RETURN_IF_ERROR(options.get("robot_offset_s", o.robot_gate.offset_s));
    DS_RETURN_IF_ERROR(options.get("vad_on_channel_mean", o.vad_on_channel_mean));
    // Issue 16: utterance (each alone, the baseline) or tracks (speaker_tracks.hpp).
    std::string decision = to_string(o.decision);
    DS_RETURN_IF_ERROR(options.get("decision", decision));
    DS_ASSIGN_OR_RETURN(o.decision, parse_voice_decision(decision));
    DS_RETURN_IF_ERROR(options.get("track_angle_deg", o.tracks.angle_tolerance_deg));
    DS_RETURN_IF_ERROR(options.get("track_memory_s", o.tracks.memory_s));
    DS_RETURN_IF_ERROR(options.get("track_max_frames", o.tracks.max_track_frames));
    DS_RETURN_IF_ERROR(options.get("track_exclusive", o.tracks.exclusive));
    // The child seen by the cameras (head pose) as a cue: needs the array's extrinsics.
    DS_RETURN_IF_ERROR(options.get("seen_child", o.use_seen_child));
    DS_RETURN_IF_ERROR(options.get("seen_child_tolerance_deg", o.tracks.child_place_tolerance_deg));
    if (o.use_seen_child && !s->calibration_file.empty()) {
      DS_ASSIGN_OR_RETURN(const audio::MicArrayGeometry g,
                          audio::read_mic_array(s->calibration_file));
      o.array_from_world_R = g.array_from_world_R;
      o.array_from_world_t = g.array_from_world_t;
      o.array_is_linear = g.rank() == 1;
    }
    if (const StreamDescription* r = ctx.first_with_role(roles::kRobotAudio); r && robot_gate) {
      o.reference_sensor = r->id;
      p.notes.push_back(fmt::format("robot voice gated with the reference stream '{}'", r->id));
    }
    if (method == VoiceIdMethod::kGmmUbm) {
      if (!model_file.empty()) {
        o.model_file = model_file;
      } else {
        DS_ASSIGN_OR_RETURN(auto enroll, ctx.metadata_file("voice_enroll"));
        if (!enroll)
          return PlannedAnalyzers::skip(
              "no voice model (option model / --voice-model) and the session has no enrolment "
              "audio (metadata voice_enroll)");
        auto audio_files = read_speaker_folders(*enroll);
        if (!audio_files) return tl::unexpected(audio_files.error());
        VoiceTrainOptions train;
        train.features.noise_suppression = noise_suppression;
        auto m = train_voice_model(*audio_files, {}, train);
        if (!m) return make_error(m.error().code, "{}: {}", enroll->string(), m.error().message);
        std::string who;
        for (const auto& sp : m->speakers)
          who += fmt::format("{}{} ({:.1f} s)", who.empty() ? "" : ", ",
                             ctx.include_names ? sp.id : public_speaker_id(*m, sp.id),
                             sp.frames * m->features.hop_s);
        p.notes.push_back("voice models from the session's enrolment: " + who);
        o.model = std::make_shared<const VoiceModel>(std::move(*m));
      }
    }
    DS_ASSIGN_OR_RETURN(auto analyzer, make_voice_id_analyzer(o));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::voice_id
