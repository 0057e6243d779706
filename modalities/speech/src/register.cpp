// Declared pipeline entry of the speech analyser (perception/analyzer_registry.hpp).

#include "dreamsense/audio/mic_array.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/speech/acoustic_model.hpp"
#include "dreamsense/speech/speech_analyzer.hpp"

#include <fmt/format.h>

namespace dreamsense::speech {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "speech";
  f.summary =
      "utterances recognised against the session's grammar (PocketSphinx, JSGF/SRGS, "
      "out-of-grammar rejection; beamformed at the sound direction)";
  f.roles = {roles::kMicArray};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    SpeechAnalyzerOptions o;
    std::filesystem::path grammar;
    DS_RETURN_IF_ERROR(options.get("grammar", grammar));
    DS_RETURN_IF_ERROR(options.get("steer_to_sound_direction", o.steer_to_sound_direction));
    const StreamDescription* s = ctx.first_with_role(roles::kMicArray);
    if (s == nullptr) return PlannedAnalyzers::skip("no stream with role mic_array");
    if (grammar.empty()) {
      DS_ASSIGN_OR_RETURN(auto from_session, ctx.metadata_file("speech_grammar"));
      if (!from_session)
        return PlannedAnalyzers::skip(
            "no grammar (session metadata speech_grammar, or option grammar / --grammar)");
      grammar = *from_session;
    }
    PlannedAnalyzers p;
    o.audio_sensor = s->id;
    // The robot's own voice (role robot_audio): gated out (audio/reference_gate.hpp).
    bool robot_gate = true;
    DS_RETURN_IF_ERROR(options.get("robot_gate", robot_gate));
    DS_RETURN_IF_ERROR(options.get("robot_offset_s", o.robot_gate.offset_s));
    DS_RETURN_IF_ERROR(options.get("noise_suppression", o.noise_suppression));
    DS_RETURN_IF_ERROR(options.get("fade_in_s", o.fade_in_s));
    DS_RETURN_IF_ERROR(options.get("garbage_phone_weight", o.recognizer.garbage_phone_weight));
    bool live_background_decode = true;
    DS_RETURN_IF_ERROR(options.get("live_background_decode", live_background_decode));
    o.background_decode = ctx.live && live_background_decode;
    if (const StreamDescription* r = ctx.first_with_role(roles::kRobotAudio); r && robot_gate) {
      o.reference_sensor = r->id;
      p.notes.push_back(fmt::format("robot voice gated with the reference stream '{}'", r->id));
    }
    o.grammar = grammar;
    if (!ctx.subject.speech_model.empty()) {
      DS_RETURN_IF_ERROR(use_acoustic_model(o.recognizer, ctx.subject.speech_model));
      p.notes.push_back("acoustic model " + ctx.subject.speech_model.string());
    }
    // The array's geometry steers the beam towards the sound direction (which runs first).
    audio::MicArrayGeometry geometry = audio::MicArrayGeometry::kinect_v1();
    if (!s->calibration_file.empty()) {
      DS_ASSIGN_OR_RETURN(geometry, audio::read_mic_array(s->calibration_file));
    }
    o.mic_positions_m = geometry.mics_m;
    DS_ASSIGN_OR_RETURN(auto analyzer, make_speech_analyzer(o));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::speech
