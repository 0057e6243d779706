#include "dreamsense/runner/plan.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/core/pipeline.hpp"
#include "dreamsense/primitives/evaluator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

namespace dreamsense::runner {
namespace fs = std::filesystem;

fs::path default_subjects_dir() { return DREAMSENSE_SUBJECTS_DIR; }

Status PlanOptions::check() const {
  for (const auto& o : overrides)
    if (o.analyzer.empty() || o.key.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "option override '{}.{}': needs an analyser and a key", o.analyzer, o.key);
  return ok_status();
}

namespace {

// The calibration files in effect (explicit files, else the subject folder's).
Result<SubjectFiles> subject_files(const PlanOptions& options,
                                   const sources::SessionManifest& manifest) {
  SubjectFiles c;
  fs::path dir = options.subject_dir;
  if (auto it = manifest.metadata.find("subject"); it != manifest.metadata.end())
    c.subject_id = it->second;
  if (dir.empty() && options.subject_from_session && !c.subject_id.empty()) {
    // A subject id names a folder directly under subjects_dir, never a path.
    const fs::path id(c.subject_id);
    if (c.subject_id.find('/') != std::string::npos || c.subject_id == "." ||
        c.subject_id == ".." || id.is_absolute())
      return make_error(ErrorCode::kInvalidArgument,
                        "session.yaml: metadata subject '{}' must be an id, not a path",
                        c.subject_id);
    const fs::path candidate = options.subjects_dir / id;
    if (fs::is_directory(candidate))
      dir = candidate;
    else
      log::info("no calibration for subject '{}' in {}: generic face model", c.subject_id,
                options.subjects_dir.string());
  } else if (!dir.empty() && !fs::is_directory(dir)) {
    return make_error(ErrorCode::kNotFound, "{}: subject calibration folder not found",
                      dir.string());
  }
  if (!dir.empty()) {
    c.folder = dir;
    if (fs::exists(dir / "face_model.yaml")) c.face_model = dir / "face_model.yaml";
    if (fs::exists(dir / "gaze.yaml")) c.gaze_model = dir / "gaze.yaml";
    if (fs::is_directory(dir / "speech_model")) c.speech_model = dir / "speech_model";
    if (c.face_model.empty() && c.gaze_model.empty() && c.speech_model.empty())
      return make_error(ErrorCode::kNotFound,
                        "{}: a subject folder needs face_model.yaml, gaze.yaml and/or "
                        "speech_model/",
                        dir.string());
  }
  if (!options.face_model.empty()) c.face_model = options.face_model;
  if (!options.gaze_model.empty()) c.gaze_model = options.gaze_model;
  if (!options.speech_model.empty()) c.speech_model = options.speech_model;
  return c;
}

// The streams as the factories see them: roles, and camera models read from the calibrations.
Result<std::vector<StreamDescription>> describe_streams(const sources::SessionManifest& manifest,
                                                        const fs::path& dir,
                                                        const PlanOptions& options) {
  auto roles = sources::stream_roles(manifest);
  if (!roles) return tl::unexpected(roles.error());
  std::vector<StreamDescription> out;
  for (const auto& s : manifest.streams) {
    StreamDescription d;
    d.id = s.id;
    d.kind = s.kind;
    d.roles = (*roles)[s.id];
    d.rate_hz = s.rate_hz;
    d.width = s.width;
    d.height = s.height;
    d.sample_rate = s.sample_rate;
    d.channels = s.channels;
    if (!s.calibration.empty()) {
      d.calibration_file = dir / s.calibration;
      if (s.kind == SensorKind::kColor || s.kind == SensorKind::kSkeleton) {
        auto m = read_camera_model(d.calibration_file);
        if (!m) return tl::unexpected(m.error());
        d.camera = *m;
      } else if (s.kind == SensorKind::kDepth) {
        if (auto m = read_camera_model(d.calibration_file))
          d.camera = *m;
        else
          log::warn("depth stream '{}': {}", s.id, m.error().message);
      }
    } else if (auto a = options.assumed_cameras.find(s.id); a != options.assumed_cameras.end()) {
      d.camera = a->second;
      d.approximate_calibration = true;
    }
    out.push_back(std::move(d));
  }
  return out;
}

std::string known_names(const AnalyzerRegistry& registry) {
  std::string names;
  for (const auto& f : registry.factories()) names += (names.empty() ? "" : ", ") + f.name;
  return names;
}

}  // namespace

namespace {

// plan_pipeline; with subject_models_only, only the factories that use the child's face and gaze
// models are planned (replan_subject_analyzers) and nothing is dropped for reads without writer.
Result<PipelinePlan> plan_factories(const PlanOptions& options,
                                    const sources::SessionManifest& manifest_in,
                                    const fs::path& dir, bool subject_models_only) {
  DS_RETURN_IF_ERROR(options.check());
  const AnalyzerRegistry& registry = builtin_analyzers();
  PipelineConfig config;
  if (!options.pipeline_file.empty()) {
    DS_ASSIGN_OR_RETURN(config, PipelineConfig::read(options.pipeline_file));
  }
  for (const auto& [name, c] : config.analyzers)
    if (registry.find(name) == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "{}: unknown analyser (known: {})",
                        config.where("analyzers." + name), known_names(registry));
  for (const auto& o : options.overrides)
    if (registry.find(o.analyzer) == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "option {}.{}: unknown analyser (known: {})",
                        o.analyzer, o.key, known_names(registry));
  for (const auto& [name, on] : options.enable)
    if (registry.find(name) == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "analyser '{}' is unknown (known: {})", name,
                        known_names(registry));

  // Roles from pipeline.yaml replace the session's for the streams it names.
  sources::SessionManifest manifest = manifest_in;
  for (const auto& [id, roles] : config.roles) {
    auto it =
        std::find_if(manifest.streams.begin(), manifest.streams.end(),
                     [&wanted = id](const sources::StreamEntry& s) { return s.id == wanted; });
    if (it == manifest.streams.end())
      return make_error(ErrorCode::kInvalidArgument, "{}: the session has no stream '{}'",
                        config.where("roles." + id), id);
    it->roles = roles;
  }

  PipelinePlan plan;
  plan.config = config.file.empty() ? "defaults" : config.file.string();
  DS_ASSIGN_OR_RETURN(plan.streams, describe_streams(manifest, dir, options));
  DS_ASSIGN_OR_RETURN(plan.subject, subject_files(options, manifest));
  PlanContext ctx;
  ctx.streams = plan.streams;
  ctx.metadata = manifest.metadata;
  ctx.session_dir = dir;
  ctx.manifest_path = dir / sources::kManifestName;
  ctx.subject = plan.subject;
  ctx.frame_rate = manifest.frame_rate > 0 ? manifest.frame_rate : 25.0;
  ctx.absolute_paths_allowed = options.absolute_paths_allowed;
  ctx.include_names = options.include_names;
  ctx.live = options.live;

  std::vector<std::unique_ptr<Analyzer>> planned;
  std::vector<size_t> planned_by;  // factory index of each planned analyser
  for (const AnalyzerFactory& factory : registry.factories()) {
    if (subject_models_only && !factory.uses_subject_models) continue;
    FactoryOutcome outcome{factory.name, factory.summary, factory.roles, {}, {}, {}, {}};
    bool enabled = factory.enabled_by_default;
    const auto cfg = config.analyzers.find(factory.name);
    if (cfg != config.analyzers.end() && cfg->second.enabled) enabled = *cfg->second.enabled;
    if (auto e = options.enable.find(factory.name); e != options.enable.end()) enabled = e->second;
    OptionsNode node(
        config.where("analyzers." + factory.name + ".options"),
        cfg != config.analyzers.end() ? YAML::Clone(cfg->second.options) : YAML::Node());
    if (!config.file.empty()) node.set_base_dir(config.file.parent_path());
    for (const auto& o : options.overrides)
      if (o.analyzer == factory.name) DS_RETURN_IF_ERROR(node.set(o.key, o.value));
    if (!enabled) {
      outcome.skipped = "disabled";
      plan.factories.push_back(std::move(outcome));
      continue;
    }
    auto p = factory.plan(ctx, node);
    if (!p) return tl::unexpected(p.error());
    for (const auto& key : node.unread_keys())
      return make_error(ErrorCode::kInvalidArgument, "{}.{}: unknown option", node.where(), key);
    outcome.options = node.effective();
    outcome.notes = p->notes;
    for (const auto& n : p->notes) log::info("{}: {}", factory.name, n);
    outcome.skipped = p->skipped;
    for (auto& a : p->analyzers) {
      outcome.analyzers.emplace_back(a->name());
      planned_by.push_back(plan.factories.size());
      planned.push_back(std::move(a));
    }
    plan.factories.push_back(std::move(outcome));
  }

  // Analysers whose same-tick reads have no writer cannot run (e.g. their producer is disabled).
  for (bool changed = !subject_models_only; changed;) {
    changed = false;
    std::set<std::string> written;
    for (const auto& a : planned)
      for (const auto& k : a->contract().writes) written.insert(k);
    for (size_t i = 0; i < planned.size(); ++i) {
      for (const auto& k : planned[i]->contract().reads) {
        if (written.count(k) > 0) continue;
        FactoryOutcome& o = plan.factories[planned_by[i]];
        o.skipped = fmt::format("reads {}, which no planned analyser writes", k);
        log::warn("{} does not run: {}", o.name, o.skipped);
        o.analyzers.clear();
        planned.erase(planned.begin() + static_cast<std::ptrdiff_t>(i));
        planned_by.erase(planned_by.begin() + static_cast<std::ptrdiff_t>(i));
        changed = true;
        break;
      }
      if (changed) break;
    }
  }
  DS_ASSIGN_OR_RETURN(plan.analyzers, order_by_contracts(std::move(planned)));

  SourceInfo info;
  for (const auto& s : manifest.streams)
    info.sensors.push_back(SensorDescription{s.id, s.kind, s.rate_hz, s.width, s.height,
                                             s.sample_rate, s.channels, s.calibration, s.frame});
  std::set<SensorId> used;
  for (const auto& a : plan.analyzers) {
    const AnalyzerContract c = a->contract();
    used.insert(c.required_inputs.begin(), c.required_inputs.end());
    for (const auto& o : c.optional_inputs)
      if (info.find(o) != nullptr) used.insert(o);
  }
  for (const auto& s : manifest.streams)  // manifest order
    if (used.count(s.id) > 0) plan.used.push_back(s.id);
  plan.key_sensors = key_sensors(plan.analyzers, info);
  for (const auto& s : plan.streams)
    if (s.kind == SensorKind::kColor && s.camera) plan.cameras.emplace(s.id, *s.camera);
  return plan;
}

}  // namespace

Result<PipelinePlan> plan_pipeline(const PlanOptions& options,
                                   const sources::SessionManifest& manifest, const fs::path& dir) {
  return plan_factories(options, manifest, dir, false);
}

Result<std::vector<std::unique_ptr<Analyzer>>> replan_subject_analyzers(
    const PlanOptions& options, const sources::SessionManifest& manifest, const fs::path& dir,
    const fs::path& face_model, const fs::path& gaze_model) {
  PlanOptions o = options;
  o.face_model = face_model;
  o.gaze_model = gaze_model;
  DS_ASSIGN_OR_RETURN(PipelinePlan plan, plan_factories(o, manifest, dir, true));
  return std::move(plan.analyzers);
}

std::string PipelinePlan::describe() const {
  std::string out = fmt::format("pipeline ({})\n\nstreams:\n", config);
  for (const auto& s : streams) {
    std::string roles_text;
    for (const auto& r : s.roles) roles_text += (roles_text.empty() ? "" : ", ") + r;
    out += fmt::format(
        "  {:<16} {:<9} role {:<22} {}{}\n", s.id, to_string(s.kind),
        roles_text.empty() ? "-" : roles_text,
        s.approximate_calibration    ? "approximate intrinsics from the image size (no calibration)"
        : s.calibration_file.empty() ? "no calibration"
                                     : "calibration " + s.calibration_file.filename().string(),
        "");
  }
  out += "\nanalysers, in execution order:\n";
  int n = 0;
  auto join = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s.empty() ? std::string("-") : s;
  };
  for (const auto& a : analyzers) {
    const AnalyzerContract c = a->contract();
    std::vector<std::string> inputs = c.required_inputs;
    for (const auto& o : c.optional_inputs)
      if (std::find(used.begin(), used.end(), o) != used.end()) inputs.push_back(o);
    out +=
        fmt::format("  {}. {}\n     inputs: {}\n     reads: {}{}\n     writes: {}\n", ++n,
                    a->name(), join(inputs), join(c.reads),
                    c.reads_previous.empty() ? std::string()
                                             : " (previous tick: " + join(c.reads_previous) + ")",
                    join(c.writes));
    for (const auto& f : factories) {
      if (std::find(f.analyzers.begin(), f.analyzers.end(), std::string(a->name())) ==
          f.analyzers.end())
        continue;
      std::string opts;
      for (const auto& [k, v] : f.options)
        opts += fmt::format("{}{}={}", opts.empty() ? "" : ", ", k, v);
      if (!opts.empty()) out += "     options: " + opts + "\n";
      for (const auto& note : f.notes) out += "     note: " + note + "\n";
    }
  }
  if (analyzers.empty()) out += "  (none for this session's streams)\n";
  bool header = false;
  for (const auto& f : factories) {
    if (f.skipped.empty()) continue;
    if (!header) out += "\nnot running:\n";
    header = true;
    out += fmt::format("  {}: {}\n", f.name, f.skipped);
  }
  const primitives::Evaluator evaluator({}, key_sensors);
  std::string on, off;
  for (const auto& i : primitives::catalogue())
    (evaluator.enabled(i.id) ? on : off) += fmt::format(
        "{}{} {}", (evaluator.enabled(i.id) ? on : off).empty() ? "" : ", ", i.code, i.name);
  out += fmt::format("\nprimitives answered: {}\nprimitives disabled: {}\n",
                     on.empty() ? "none" : on, off.empty() ? "none" : off);
  return out;
}

nlohmann::json PipelinePlan::to_json() const {
  nlohmann::json j;
  j["config"] = config;
  nlohmann::json order = nlohmann::json::array();
  for (const auto& a : analyzers) order.push_back(std::string(a->name()));
  j["analyzers"] = order;
  nlohmann::json skipped = nlohmann::json::object();
  for (const auto& f : factories)
    if (!f.skipped.empty()) skipped[f.name] = f.skipped;
  j["not_running"] = skipped;
  nlohmann::json roles = nlohmann::json::object();
  for (const auto& s : streams) roles[s.id] = s.roles;
  j["roles"] = roles;
  nlohmann::json approximate = nlohmann::json::array();
  for (const auto& s : streams)
    if (s.approximate_calibration) approximate.push_back(s.id);
  if (!approximate.empty()) j["approximate_calibration"] = approximate;
  return j;
}

}  // namespace dreamsense::runner
