#include "dreamsense/primitives/audio.hpp"

#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/speech.hpp"
#include "dreamsense/perception/voice_id.hpp"
#include "dreamsense/primitives/registry.hpp"

namespace dreamsense::primitives {

Status AudioPrimitiveOptions::check() const {
  if (!(sound_direction.threshold >= 0 && sound_direction.threshold <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "AudioPrimitiveOptions: sound_direction threshold must be in [0, 1]");
  return ok_status();
}

namespace {

// The first sensor behind `key` (the audio stream), reported with every status.
template <typename V, typename T>
Answer<V> start(const PrimitiveContext& ctx, const Observation<T>& o, Key<T> key) {
  auto a = Answer<V>::from(o);
  const auto& sensors = ctx.sensors_of(key.name);
  if (!sensors.empty()) a.source = sensors.front();
  return a;
}

// An utterance's result is reported once, at the tick it was written.
template <typename V, typename T>
void once_per_utterance(const PrimitiveContext& ctx, const Observation<T>& o, Answer<V>& a) {
  if (a.status == PrimitiveStatus::kStale ||
      (a.status == PrimitiveStatus::kOk && o.entry->stamp != ctx.tick()))
    a.status = PrimitiveStatus::kNoData;
}

}  // namespace

Answer<SoundDirectionValue> get_sound_direction(const PrimitiveContext& ctx,
                                                const ThresholdQuery& query) {
  const auto o = ctx.observe(keys::kSoundDirection);  // absent entry = silence
  auto a = start<SoundDirectionValue>(ctx, o, keys::kSoundDirection);
  if (a.status == PrimitiveStatus::kDisabled) return a;
  a.query = query;
  if (a.status != PrimitiveStatus::kOk) return a;
  a.confidence = o.entry->confidence;
  if (o.entry->confidence < query.threshold) {
    a.status = PrimitiveStatus::kNoData;
    return a;
  }
  const SoundDirection& d = o.value();
  a.value =
      SoundDirectionValue{d.azimuth_deg, d.elevation_deg, o.entry->confidence, d.direction_world};
  return a;
}

Answer<VoiceValue> identify_voice(const PrimitiveContext& ctx) {
  const auto o = ctx.observe(keys::kSpeakerIdentity);
  auto a = start<VoiceValue>(ctx, o, keys::kSpeakerIdentity);
  once_per_utterance(ctx, o, a);
  if (a.status != PrimitiveStatus::kOk) return a;
  const SpeakerIdentity& s = o.value();
  a.confidence = o.entry->confidence;
  a.value = VoiceValue{s.speaker_id, s.name, s.score, s.start.ns(), s.end.ns(), s.method};
  return a;
}

Answer<SpeechValue> recognize_speech(const PrimitiveContext& ctx) {
  const auto o = ctx.observe(keys::kRecognizedSpeech);
  auto a = start<SpeechValue>(ctx, o, keys::kRecognizedSpeech);
  once_per_utterance(ctx, o, a);
  if (a.status != PrimitiveStatus::kOk) return a;
  const RecognizedSpeech& s = o.value();
  a.confidence = o.entry->confidence;
  a.value = SpeechValue{s.text, s.tag, s.confidence, s.start.ns(), s.end.ns()};
  return a;
}

// The rows of the audio family (the microphone array's analysers).
void register_audio_primitives(PrimitiveRegistry& r) {
  using P = PrimitiveId;
  r.add(P::kGetSoundDirection, {keys::kSoundDirection.name}, [](const PrimitiveContext& c) {
    return get_sound_direction(c, c.family_options<AudioPrimitiveOptions>().sound_direction);
  });
  r.add(P::kIdentifyVoice, {keys::kSpeakerIdentity.name}, identify_voice);
  r.add(P::kRecognizeSpeech, {keys::kRecognizedSpeech.name}, recognize_speech);
}

}  // namespace dreamsense::primitives
