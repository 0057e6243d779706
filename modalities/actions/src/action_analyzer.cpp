#include "dreamsense/actions/action_analyzer.hpp"

#include <algorithm>

namespace dreamsense::actions {
namespace {

class ActionAnalyzer : public Analyzer {
 public:
  explicit ActionAnalyzer(OnlineActionClassifier classifier) : classifier_(std::move(classifier)) {}
  std::string_view name() const override { return "actions"; }
  AnalyzerContract contract() const override {
    return {{}, {}, {keys::kChildBody.name}, {keys::kChildAction.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto body = prior.get(keys::kChildBody);
    SkeletonFrame frame;  // no body at this tick: all joints missing, time still advances
    frame.stamp_ns = in.stamp.ns();
    if (body && body->stamp.is_set() && body->stamp <= in.stamp) {
      // The body entry of this tick (or the last one): its own stamp is the skeleton frame's.
      frame.stamp_ns = body->stamp.ns();
      if (body->present()) frame.joints = body->value->body.joints;
    }
    if (frame.stamp_ns <= last_stamp_ns_) return ok_status();  // that skeleton frame was seen
    last_stamp_ns_ = frame.stamp_ns;
    const ActionResult r = classifier_.push(frame);
    ActionState s;
    s.label = r.label;
    s.dream_id = r.dream_id;
    s.scores = r.scores;
    s.ready = r.ready;
    s.custom = r.custom;
    s.window_s = classifier_.window_s();
    double confidence = 0;
    for (const auto& [label, score] : r.scores)
      if (label == r.label) confidence = std::max(confidence, score);
    out.set(keys::kChildAction, std::move(s), Timestamp::from_ns(frame.stamp_ns),
            static_cast<float>(confidence));
    return ok_status();
  }
  void reset() override {
    classifier_.reset();
    last_stamp_ns_ = INT64_MIN;
  }

 private:
  OnlineActionClassifier classifier_;
  int64_t last_stamp_ns_ = INT64_MIN;
};

}  // namespace

std::filesystem::path default_action_model_path() {
  return std::filesystem::path(DREAMSENSE_ACTIONS_MODELS_DIR) / "dream_gestures.yaml";
}

Status ActionAnalyzerOptions::check() const {
  if (model.empty() && gestures.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "actions analyser: neither an action model nor a gestures model given");
  return online.check();
}

Result<std::unique_ptr<Analyzer>> make_action_analyzer(const ActionAnalyzerOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  std::shared_ptr<const ActionModel> model;
  std::shared_ptr<const GestureModel> gestures;
  if (!o.model.empty()) {
    auto m = ActionModel::load(o.model);
    if (!m) return tl::unexpected(m.error());
    model = std::make_shared<const ActionModel>(std::move(*m));
  }
  if (!o.gestures.empty()) {
    auto g = GestureModel::load(o.gestures);
    if (!g) return tl::unexpected(g.error());
    gestures = std::make_shared<const GestureModel>(std::move(*g));
  }
  return make_action_analyzer(std::move(model), std::move(gestures), o.online);
}

Result<std::unique_ptr<Analyzer>> make_action_analyzer(std::shared_ptr<const ActionModel> model,
                                                       std::shared_ptr<const GestureModel> gestures,
                                                       const OnlineOptions& online) {
  auto c = OnlineActionClassifier::create(std::move(model), std::move(gestures), online);
  if (!c) return tl::unexpected(c.error());
  return std::unique_ptr<Analyzer>(new ActionAnalyzer(std::move(*c)));
}

}  // namespace dreamsense::actions
