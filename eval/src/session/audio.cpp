// Speech and speaker identification against the truth utterances.

#include "dreamsense/eval/session_metrics.hpp"

#include <algorithm>
#include <set>

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

// The robot's own voice (truth records robot_speech, issue 16): robot_speech_false_reports = the
// recognizeSpeech and identifyVoice results (one per utterance) lying mostly (more than half of
// their [start_ns, end_ns]) inside a robot utterance; robot_direction_reports = ok
// getSoundDirection records stamped inside a robot utterance (and inside no human one).
MetricGroup robot_voice_metrics() {
  MetricGroup g;
  g.name = "robot_voice";
  g.metrics = {{"robot_speech_false_reports", PrimitiveId::kRecognizeSpeech},
               {"robot_direction_reports", PrimitiveId::kGetSoundDirection}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::vector<std::pair<int64_t, int64_t>> robot, human;
    for (const auto* t : d.truth_of("robot_speech"))
      robot.emplace_back(t->value("start_ns", int64_t{0}), t->value("end_ns", int64_t{0}));
    for (const auto* t : d.truth_of("speech"))
      human.emplace_back(t->value("start_ns", int64_t{0}), t->value("end_ns", int64_t{0}));
    if (robot.empty()) {
      not_evaluated["robot_speech_false_reports"] = "the truth has no robot_speech records";
      not_evaluated["robot_direction_reports"] = "the truth has no robot_speech records";
      return;
    }
    auto mostly_robot = [&](int64_t s, int64_t e) {
      int64_t inside = 0;
      for (const auto& [a, b] : robot)
        if (e > s)
          inside += std::max<int64_t>(0, std::min(e, b) - std::max(s, a));
        else if (s >= a && s <= b)
          return true;
      return 2 * inside > e - s && e > s;
    };
    std::set<std::pair<int64_t, int64_t>> seen_speech, seen_voice;
    int reports = 0;
    for (const auto* r : d.of(PrimitiveId::kRecognizeSpeech))
      if (const auto* s = r->value_as<primitives::SpeechValue>())
        if (seen_speech.insert({s->start_ns, s->end_ns}).second &&
            mostly_robot(s->start_ns, s->end_ns))
          ++reports;
    for (const auto* r : d.of(PrimitiveId::kIdentifyVoice))
      if (const auto* v = r->value_as<primitives::VoiceValue>())
        if (seen_voice.insert({v->start_ns, v->end_ns}).second &&
            mostly_robot(v->start_ns, v->end_ns))
          ++reports;
    metrics["robot_speech_false_reports"] = reports;
    int directions = 0;
    for (const auto* r : d.of(PrimitiveId::kGetSoundDirection)) {
      if (r->value_as<primitives::SoundDirectionValue>() == nullptr) continue;
      const int64_t t = r->stamp.ns();
      auto in = [t](const auto& spans) {
        for (const auto& [a, b] : spans)
          if (t >= a && t <= b) return true;
        return false;
      };
      if (in(robot) && !in(human)) ++directions;
    }
    metrics["robot_direction_reports"] = directions;
  };
  return g;
}

}  // namespace dreamsense::eval
