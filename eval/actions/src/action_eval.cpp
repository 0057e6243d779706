#include "dreamsense/eval/action_eval.hpp"

#include "dreamsense/eval/classification.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

namespace dreamsense::eval::actions {
namespace fs = std::filesystem;
using dreamsense::actions::ActionModel;
using dreamsense::actions::ActionModelOptions;
using dreamsense::actions::ClassifierKind;
using dreamsense::actions::FeatureMethod;

ActionMethod baseline_method() {
  ActionMethod m;
  m.name = "baseline";
  m.options.body.normalize_bones = false;
  m.options.features.method = FeatureMethod::kRelativePositions;
  m.options.features.joints = dreamsense::actions::JointSet::kAll;
  m.options.features.rjp_frames = 4;
  m.options.classifier.kind = ClassifierKind::kRbfSvm;
  m.options.classifier.c = 10;
  m.options.classifier.gamma = 0;  // 1 / dimension
  return m;
}

ActionMethod pyramid_method() {
  ActionMethod m;
  m.name = "pyramid";
  m.options.body.normalize_bones = true;
  m.options.features.method = FeatureMethod::kPyramid;
  m.options.features.joints = dreamsense::actions::JointSet::kUpperBody;
  m.options.features.pyramid_levels = 2;
  m.options.features.fourier = 4;
  m.options.classifier.kind = ClassifierKind::kLinearSvm;
  m.options.classifier.c = 1;
  return m;
}

ActionMethod pyramid_lda_method() {
  ActionMethod m = pyramid_method();
  m.name = "pyramid_lda";
  m.options.features.distances = true;
  m.options.classifier.kind = ClassifierKind::kShrinkageLda;
  return m;
}

Result<ActionMethod> method_by_name(const std::string& name) {
  if (name == "baseline") return baseline_method();
  if (name == "pyramid") return pyramid_method();
  if (name == "pyramid_lda") return pyramid_lda_method();
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown actions method '{}' (baseline, pyramid, pyramid_lda)", name);
}

Status ActionEvalOptions::check() const {
  if (dataset != "utkinect" && dataset != "msr-action3d")
    return make_error(ErrorCode::kInvalidArgument,
                      "eval actions: unknown dataset '{}' (utkinect, msr-action3d, demo-gestures)",
                      dataset);
  if (splits < 1 || splits > 1000)
    return make_error(ErrorCode::kInvalidArgument, "eval actions: --splits must be in [1, 1000]");
  if (methods.empty() && model.empty())
    return make_error(ErrorCode::kInvalidArgument, "eval actions: no method to evaluate");
  for (const auto& m : methods)
    if (auto s = m.options.check(); !s) return s;
  return ok_status();
}

namespace {

struct Split {
  std::set<std::string> train, test;
};

struct MethodResult {
  std::vector<double> accuracies;  // per split
  Stopwatch timing;
  std::unique_ptr<ConfusionMatrix> confusion;
  std::vector<double> loso;  // leave-one-subject-out accuracies (utkinect)
  // utkinect: the same random halves with train and test swapped (with 5 subjects: 3 train)
  std::vector<double> swapped;
};

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}
double stddev(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

// Trains on the split's training subjects and classifies its test items (no rejection).
Result<double> run_split(const ActionDataset& d, const Split& split, const ActionMethod& method,
                         MethodResult& r, bool record) {
  std::vector<dreamsense::actions::LabelledSequence> train;
  for (const auto& it : d.items)
    if (split.train.count(it.subject)) train.push_back(it);
  ActionModelOptions o = method.options;
  o.classifier.reject_folds = 0;  // closed-set protocol: no threshold needed
  auto model = ActionModel::train(train, o);
  if (!model) return tl::unexpected(model.error());
  size_t correct = 0, total = 0;
  for (const auto& it : d.items) {
    if (!split.test.count(it.subject)) continue;
    if (record) r.timing.start();
    const auto s = model->classify(it.frames, false);
    if (record) r.timing.stop();
    if (record) r.confusion->add(it.label, s.label);
    correct += s.label == it.label;
    ++total;
  }
  return total ? static_cast<double>(correct) / static_cast<double>(total) : 0.0;
}

nlohmann::json method_json(const MethodResult& r) {
  nlohmann::json j;
  j["accuracy"] = mean(r.accuracies);
  j["accuracy_std"] = stddev(r.accuracies);
  j["per_split"] = r.accuracies;
  if (!r.loso.empty()) {
    j["loso_accuracy"] = mean(r.loso);
    j["loso_per_subject"] = r.loso;
  }
  if (!r.swapped.empty()) j["swapped_halves_accuracy"] = mean(r.swapped);
  if (auto ms = r.timing.median_ms()) j["ms_per_window_median"] = *ms;
  j["per_class"] = r.confusion->per_class_json();
  return j;
}

}  // namespace

Result<EvalReport> run_action_eval(const ActionEvalOptions& o,
                                   const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto data = read_action_dataset(o.dataset, o.dir);
  if (!data) return tl::unexpected(data.error());
  const ActionDataset& d = *data;
  EvalReport report;
  report.task = "actions";
  report.dataset = o.dataset;
  report.items = d.items.size();
  report.extra["dataset_note"] = d.note;

  if (!o.model.empty()) {
    auto model = ActionModel::load(o.model);
    if (!model) return tl::unexpected(model.error());
    std::vector<std::string> labels = d.labels;
    for (const auto& l : model->labels())
      if (std::find(labels.begin(), labels.end(), l) == labels.end()) labels.push_back(l);
    ConfusionMatrix cm(labels, "none");
    Stopwatch sw;
    for (size_t i = 0; i < d.items.size(); ++i) {
      sw.start();
      const auto s = model->classify(d.items[i].frames, false);
      sw.stop();
      cm.add(d.items[i].label, s.label);
      if (progress) progress(static_cast<double>(i + 1) / d.items.size());
    }
    report.protocol = fmt::format(
        "model {} ({} classes, {} windows) applied to every segment of {} (train elsewhere, test "
        "here); one time-normalised window per segment, forced choice",
        o.model.filename().string(), model->labels().size(), model->training_examples(),
        o.dir.string());
    report.metrics["accuracy"] = cm.accuracy() ? nlohmann::json(*cm.accuracy()) : nlohmann::json();
    report.metrics["balanced_accuracy"] =
        cm.balanced_accuracy() ? nlohmann::json(*cm.balanced_accuracy()) : nlohmann::json();
    report.metrics["confusion"] = cm.confusion_json();
    report.per_class = cm.per_class_json();
    if (auto ms = sw.median_ms()) report.timing["ms_per_window_median"] = *ms;
    report.extra["model"] = {
        {"file", o.model.string()},
        {"method", std::string(to_string(model->options().features.method))},
        {"classifier", std::string(to_string(model->options().classifier.kind))},
        {"description", model->description}};
    return report;
  }

  std::set<std::string> subject_set;
  for (const auto& it : d.items) subject_set.insert(it.subject);
  const std::vector<std::string> subjects(subject_set.begin(), subject_set.end());
  if (subjects.size() < 2)
    return make_error(ErrorCode::kInvalidArgument,
                      "eval actions: {} has {} subject(s); subject-disjoint evaluation needs two",
                      o.dir.string(), subjects.size());
  std::vector<Split> splits, loso;
  for (const auto& s : subjects) {
    Split sp;
    sp.test = {s};
    for (const auto& t : subjects)
      if (t != s) sp.train.insert(t);
    loso.push_back(sp);
  }
  if (o.dataset == "utkinect") {
    for (const auto& half : random_half_splits(subjects, o.splits, o.seed)) {
      Split sp;
      sp.train.insert(half.begin(), half.end());
      for (const auto& s : subjects)
        if (!sp.train.count(s)) sp.test.insert(s);
      splits.push_back(sp);
    }
    report.protocol = fmt::format(
        "{} random half/half subject splits (seed {}; {} subjects: the first {} of each draw "
        "train, the other {} test), mean accuracy; one time-normalised window per segment, "
        "forced choice; plus leave-one-subject-out (loso_accuracy) and the same halves with "
        "train and test swapped (swapped_halves_accuracy)",
        splits.size(), o.seed, subjects.size(), subjects.size() / 2,
        subjects.size() - subjects.size() / 2);
    loso.clear();  // reported separately below
  } else {
    bool odd = false, even = false;
    for (const auto& s : subjects) {
      const int n = std::atoi(s.c_str() + 1);
      (n % 2 ? odd : even) = true;
    }
    if (odd && even) {
      Split sp;
      for (const auto& s : subjects) (std::atoi(s.c_str() + 1) % 2 ? sp.train : sp.test).insert(s);
      splits.push_back(sp);
      report.protocol =
          "cross-subject: odd subjects train, even subjects test (all 20 actions); one "
          "time-normalised window per sequence, forced choice";
    } else {
      splits = loso;
      report.protocol = fmt::format(
          "leave-one-subject-out over the {} subjects present (only {} subjects in this copy, so "
          "the standard odd/even cross-subject split is not possible); mean accuracy over "
          "folds; one time-normalised window per sequence, forced choice",
          subjects.size(), odd ? "odd" : "even");
    }
    loso.clear();
  }
  std::vector<Split> utk_loso, swapped;
  if (o.dataset == "utkinect") {
    for (const auto& s : subjects) {
      Split sp;
      sp.test = {s};
      for (const auto& t : subjects)
        if (t != s) sp.train.insert(t);
      utk_loso.push_back(sp);
    }
    for (const auto& sp : splits) swapped.push_back({sp.test, sp.train});
  }

  std::vector<MethodResult> results(o.methods.size());
  const size_t steps = o.methods.size() * (splits.size() + utk_loso.size() + swapped.size());
  size_t done = 0;
  for (size_t k = 0; k < o.methods.size(); ++k) {
    MethodResult& r = results[k];
    r.confusion = std::make_unique<ConfusionMatrix>(d.labels, "none");
    for (const auto& sp : splits) {
      auto acc = run_split(d, sp, o.methods[k], r, true);
      if (!acc) return tl::unexpected(acc.error());
      r.accuracies.push_back(*acc);
      if (progress) progress(static_cast<double>(++done) / steps);
    }
    for (auto [protocol, out] : {std::pair{&utk_loso, &r.loso}, std::pair{&swapped, &r.swapped}})
      for (const auto& sp : *protocol) {
        auto acc = run_split(d, sp, o.methods[k], r, false);
        if (!acc) return tl::unexpected(acc.error());
        out->push_back(*acc);
        if (progress) progress(static_cast<double>(++done) / steps);
      }
  }
  const MethodResult& main = results.back();
  report.metrics["accuracy"] = mean(main.accuracies);
  report.metrics["accuracy_std"] = stddev(main.accuracies);
  if (!main.loso.empty()) report.metrics["loso_accuracy"] = mean(main.loso);
  if (!main.swapped.empty()) report.metrics["swapped_halves_accuracy"] = mean(main.swapped);
  report.metrics["method"] = o.methods.back().name;
  report.metrics["confusion"] = main.confusion->confusion_json();
  nlohmann::json methods = nlohmann::json::object();
  for (size_t k = 0; k < o.methods.size(); ++k)
    methods[o.methods[k].name] = method_json(results[k]);
  report.metrics["methods"] = methods;
  report.per_class = main.confusion->per_class_json();
  if (auto ms = main.timing.median_ms()) report.timing["ms_per_window_median"] = *ms;
  for (size_t k = 0; k < o.methods.size(); ++k)
    if (auto ms = results[k].timing.median_ms())
      report.timing["ms_per_window_median_" + o.methods[k].name] = *ms;
  report.extra["subjects"] = subjects;
  return report;
}

Result<ActionModel> run_action_train(const ActionTrainOptions& o,
                                     const std::function<void(double)>& progress) {
  auto data = read_action_dataset(o.dataset, o.dir);
  if (!data) return tl::unexpected(data.error());
  auto m = ActionModel::train(data->items, o.method.options, progress);
  if (!m) return tl::unexpected(m.error());
  m->description = o.description.empty()
                       ? fmt::format("{} ({}), method {}", o.dataset, data->note, o.method.name)
                       : o.description;
  return m;
}

}  // namespace dreamsense::eval::actions
