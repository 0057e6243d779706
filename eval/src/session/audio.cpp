// Speech and speaker identification against the truth utterances.

#include "dreamsense/eval/session_metrics.hpp"

#include <algorithm>

namespace dreamsense::eval {
using primitives::PrimitiveId;

// An in-grammar utterance is right when exactly its text is recognised (an ok recognizeSpeech
// whose words overlap it); an out-of-grammar one is right when nothing is recognised during it.
// speech_false_accept_rate: out-of-grammar utterances with a recognition / out-of-grammar ones.
MetricGroup speech_metrics() {
  MetricGroup g;
  g.name = "speech";
  g.metrics = {{"speech_accuracy", PrimitiveId::kRecognizeSpeech},
               {"speech_false_accept_rate", PrimitiveId::kRecognizeSpeech}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::vector<const primitives::SpeechValue*> heard;
    for (const auto* r : d.of(PrimitiveId::kRecognizeSpeech))
      if (const auto* s = r->value_as<primitives::SpeechValue>()) heard.push_back(s);
    int total = 0, right = 0, oog = 0, oog_accepted = 0;
    for (const auto* t : d.truth_of("speech")) {
      if (!t->contains("in_grammar")) continue;
      const int64_t s = t->value("start_ns", int64_t{0}), e = t->value("end_ns", int64_t{0});
      std::vector<std::string> said;
      for (const auto* h : heard)
        if (h->start_ns < e && h->end_ns > s) said.push_back(h->text);
      ++total;
      if (t->value("in_grammar", false)) {
        if (said.size() == 1 && said[0] == t->value("text", "")) ++right;
      } else {
        ++oog;
        if (said.empty())
          ++right;
        else
          ++oog_accepted;
      }
    }
    if (total == 0) {
      not_evaluated["speech_accuracy"] = "the truth has no speech records with in_grammar";
      return;
    }
    metrics["speech_accuracy"] = static_cast<double>(right) / total;
    if (oog > 0) metrics["speech_false_accept_rate"] = static_cast<double>(oog_accepted) / oog;
  };
  return g;
}

// Each truth utterance with a `speaker` against the ok identifyVoice record whose utterance
// [start_ns, end_ns] overlaps it most; right when its speaker_id (or, in an analysis made with
// --include-names, its name) is the truth speaker (child / therapist, or an enrolled name). A truth
// utterance no identity overlaps counts as wrong (missed).
MetricGroup speaker_metrics() {
  MetricGroup g;
  g.name = "speaker";
  g.metrics = {{"speaker_accuracy", PrimitiveId::kIdentifyVoice}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::vector<const primitives::VoiceValue*> decided;
    for (const auto* r : d.of(PrimitiveId::kIdentifyVoice))
      if (const auto* v = r->value_as<primitives::VoiceValue>()) decided.push_back(v);
    int total = 0, right = 0;
    for (const auto* t : d.truth_of("speech")) {
      if (!t->contains("speaker")) continue;
      const int64_t s = t->value("start_ns", int64_t{0}), e = t->value("end_ns", int64_t{0});
      int64_t best = 0;
      const primitives::VoiceValue* said = nullptr;
      for (const auto* v : decided) {
        const int64_t overlap = std::min(e, v->end_ns) - std::max(s, v->start_ns);
        if (overlap > best) best = overlap, said = v;
      }
      ++total;
      // The truth names a role (child / therapist) or an enrolled speaker: speaker_id is the
      // public id (a role word, or speaker_<k> for a name), name the enrolled name when the
      // analysis included names (privacy, docs/outputs.md).
      const std::string want = t->value("speaker", "");
      right += said != nullptr && !want.empty() && (said->speaker_id == want || said->name == want);
    }
    if (total == 0) {
      not_evaluated["speaker_accuracy"] = "the truth has no speech records with a speaker";
      return;
    }
    metrics["speaker_accuracy"] = static_cast<double>(right) / total;
  };
  return g;
}

}  // namespace dreamsense::eval
