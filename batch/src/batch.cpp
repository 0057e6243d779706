#include "dreamsense/batch/batch.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <sys/file.h>
#include <system_error>
#include <unistd.h>

namespace dreamsense::batch {
namespace fs = std::filesystem;

namespace {

constexpr const char* kPlanFormat = "dreamsense-batch 1";

fs::path log_path(const fs::path& out_dir, const std::string& name) {
  return out_dir / (name + ".log");
}

Status append_line(const fs::path& path, const std::string& line) {
  std::ofstream out(path, std::ios::app);
  if (!out) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
  out << line << "\n";
  if (!out) return make_error(ErrorCode::kIoError, "{}: write failed", path.string());
  return ok_status();
}

// The outcome line batch appended last to a log: "batch: ok after S s",
// "batch: failed after S s: REASON", "batch: interrupted after S s".
struct LoggedOutcome {
  std::string status;  // ok, failed, interrupted ("" when the log has none)
  std::string reason;
  std::optional<double> seconds;
};

LoggedOutcome logged_outcome(const fs::path& log) {
  const std::string text = read_tail(log, 16 * 1024);
  LoggedOutcome o;
  std::istringstream lines(text);
  std::string line, last;
  while (std::getline(lines, line))
    if (line.rfind("batch: ", 0) == 0) last = line;
  if (last.empty()) return o;
  std::string rest = last.substr(7);
  const auto sp = rest.find(' ');
  o.status = rest.substr(0, sp);
  if (sp == std::string::npos) return o;
  rest = rest.substr(sp + 1);
  double s = 0;
  char unit[4] = {};
  if (std::sscanf(rest.c_str(), "after %lf %3s", &s, unit) == 2) o.seconds = s;
  if (const auto colon = rest.find(": "); colon != std::string::npos)
    o.reason = rest.substr(colon + 2);
  return o;
}

nlohmann::json plan_to_json(const std::vector<PlannedInput>& plan,
                            const std::vector<std::string>& analyze_args) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& in : plan) {
    nlohmann::json j = {{"given", in.given},
                        {"path", in.path.string()},
                        {"kind", to_string(in.kind)},
                        {"plan", to_string(in.status)}};
    if (!in.name.empty()) j["name"] = in.name;
    if (!in.reason.empty()) j["reason"] = in.reason;
    inputs.push_back(std::move(j));
  }
  return {{"format", kPlanFormat},
          {"written_utc", utc_now()},
          {"analyze_args", analyze_args},
          {"inputs", inputs}};
}

struct StoredPlan {
  std::vector<PlannedInput> inputs;
  std::vector<std::string> analyze_args;
};

Result<StoredPlan> read_plan(const fs::path& out_dir) {
  const fs::path path = out_dir / kPlanFile;
  std::ifstream in(path);
  if (!in)
    return make_error(ErrorCode::kNotFound, "{}: cannot read (not a batch folder?)", path.string());
  std::stringstream text;
  text << in.rdbuf();
  auto j = nlohmann::json::parse(text.str(), nullptr, false);
  if (j.is_discarded() || !j.is_object() || j.value("format", "") != kPlanFormat)
    return make_error(ErrorCode::kCorruptData, "{}: not a dreamsense batch plan ({})",
                      path.string(), kPlanFormat);
  StoredPlan plan;
  try {
    plan.analyze_args = j.at("analyze_args").get<std::vector<std::string>>();
    for (const auto& e : j.at("inputs")) {
      PlannedInput p;
      p.given = e.at("given").get<std::string>();
      p.path = e.at("path").get<std::string>();
      p.kind = e.at("kind").get<std::string>() == "video" ? InputKind::kVideo : InputKind::kSession;
      const std::string status = e.at("plan").get<std::string>();
      p.status = status == "run"       ? PlanStatus::kRun
                 : status == "skipped" ? PlanStatus::kSkipped
                                       : PlanStatus::kFailed;
      p.name = e.value("name", "");
      p.reason = e.value("reason", "");
      if (p.status == PlanStatus::kRun && p.name.empty())
        return make_error(ErrorCode::kCorruptData, "{}: input {} has no name", path.string(),
                          p.path.string());
      plan.inputs.push_back(std::move(p));
    }
  } catch (const nlohmann::json::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), e.what());
  }
  return plan;
}

// The batch.csv row of one input, from the state of its folder and log.
TableRow row_for(const fs::path& out_dir, const PlannedInput& in,
                 const std::vector<std::string>& analyze_args) {
  TableRow row;
  row.input = in.path.string();
  if (in.status == PlanStatus::kSkipped || in.status == PlanStatus::kFailed) {
    row.status = in.status == PlanStatus::kSkipped ? "skipped" : "failed";
    row.reason = in.reason;
    return row;
  }
  row.output = in.name;
  const fs::path dir = out_dir / in.name;
  const auto state = check_output(dir, row.input, analyze_args);
  if (state.state == OutputState::kFinished) {
    row.status = "ok";
    if (auto done = read_done_record(dir)) row.seconds = done->seconds;
    std::ifstream f(dir / kSummaryFile);
    std::stringstream text;
    text << f.rdbuf();
    flatten_json(nlohmann::json::parse(text.str(), nullptr, false), row.figures);
    return row;
  }
  row.status = "failed";
  if (state.state == OutputState::kNotAFolder) {
    row.reason = state.why;
    return row;
  }
  const auto logged = logged_outcome(log_path(out_dir, in.name));
  row.seconds = logged.seconds;
  if (logged.status == "failed")
    row.reason = logged.reason;
  else if (logged.status == "interrupted")
    row.reason = "interrupted (partial output; rerun the batch to redo it)";
  else if (state.state == OutputState::kPartial)
    row.reason = "unfinished (partial output: " + state.why + "; rerun the batch to redo it)";
  else
    row.reason = "not run";
  return row;
}

Result<BatchReport> build_report(const fs::path& out_dir, const std::vector<PlannedInput>& plan,
                                 const std::vector<std::string>& analyze_args) {
  BatchReport report;
  for (const auto& in : plan) {
    report.rows.push_back(row_for(out_dir, in, analyze_args));
    const auto& s = report.rows.back().status;
    (s == "ok" ? report.ok : s == "skipped" ? report.skipped : report.failed)++;
  }
  report.table = out_dir / kTableFile;
  if (auto s = write_file_atomically(report.table, format_table(report.rows)); !s)
    return tl::unexpected(s.error());
  return report;
}

// A folder with nothing in it but (maybe) batch.lock.
bool empty_but_lock(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().filename() != kLockFile) return false;
  return !ec;
}

}  // namespace

Result<FolderLock> lock_batch_folder(const fs::path& out_dir) {
  const fs::path path = out_dir / kLockFile;
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0)
    return make_error(ErrorCode::kIoError, "{}: cannot open: {}", path.string(),
                      std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return make_error(ErrorCode::kFailedPrecondition,
                      "{}: another dreamsense batch is running on this folder", out_dir.string());
  }
  return FolderLock(fd);
}

FolderLock::FolderLock(FolderLock&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}
FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);
}

Status BatchOptions::check() const {
  if (inputs.empty()) return make_error(ErrorCode::kInvalidArgument, "batch: no inputs given");
  if (out_dir.empty()) return make_error(ErrorCode::kInvalidArgument, "batch: --out is required");
  if (jobs < 1)
    return make_error(ErrorCode::kInvalidArgument, "batch: --jobs must be at least 1 (got {})",
                      jobs);
  if (executable.empty())
    return make_error(ErrorCode::kInvalidArgument, "batch: no dreamsense executable to run");
  for (const auto& a : analyze_args)
    if (a == "--out" || a.rfind("--out=", 0) == 0)
      return make_error(ErrorCode::kInvalidArgument,
                        "batch: --out after -- is not an analyze flag here (each analysis writes "
                        "into the batch folder's <name>/)");
  if (kill_grace_s < 0)
    return make_error(ErrorCode::kInvalidArgument, "batch: kill_grace_s must be >= 0");
  return input_options.check();
}

std::vector<std::string> analyze_command(const fs::path& executable, const fs::path& input,
                                         const fs::path& out,
                                         const std::vector<std::string>& analyze_args) {
  std::vector<std::string> argv = {executable.string(), "analyze", input.string(), "--out",
                                   out.string(),        "-q"};
  // The batch's parallelism is its jobs (one per core, or Slurm's allocations): one thread per
  // analysis unless the flags say otherwise.
  const bool threads_given = std::any_of(
      analyze_args.begin(), analyze_args.end(),
      [](const std::string& a) { return a == "--threads" || a.rfind("--threads=", 0) == 0; });
  if (!threads_given) argv.insert(argv.end(), {"--threads", "1"});
  argv.insert(argv.end(), analyze_args.begin(), analyze_args.end());
  return argv;
}

Status open_batch_folder(const BatchOptions& options) {
  if (auto s = options.check(); !s) return s;
  const fs::path& out = options.out_dir;
  std::error_code ec;
  const auto st = fs::status(out, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st))
      return make_error(ErrorCode::kInvalidArgument, "{}: --out exists and is not a folder",
                        out.string());
    // Never clear "partial" folders in a folder that batch did not make.
    if (!fs::exists(out / kPlanFile, ec) && !empty_but_lock(out))
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: --out is a non-empty folder without {} (not a batch folder); choose "
                        "a new or empty folder",
                        out.string(), kPlanFile);
  } else {
    fs::create_directories(out, ec);
    if (ec)
      return make_error(ErrorCode::kIoError, "{}: cannot create: {}", out.string(), ec.message());
  }
  return ok_status();
}

Result<std::vector<PlannedInput>> plan_batch(const BatchOptions& options) {
  if (auto s = open_batch_folder(options); !s) return tl::unexpected(s.error());
  const fs::path& out = options.out_dir;
  auto plan = expand_inputs(options.inputs, options.input_options);
  if (auto s = write_file_atomically(out / kPlanFile,
                                     plan_to_json(plan, options.analyze_args).dump(2) + "\n");
      !s)
    return tl::unexpected(s.error());
  return plan;
}

Result<Preparation> prepare_output(const fs::path& out_dir, const PlannedInput& in,
                                   const std::vector<std::string>& analyze_args, bool force,
                                   std::string* note) {
  const fs::path dir = out_dir / in.name;
  const auto state = check_output(dir, in.path.string(), analyze_args);
  switch (state.state) {
    case OutputState::kAbsent:
      return Preparation::kRun;
    case OutputState::kNotAFolder:
      return make_error(ErrorCode::kFailedPrecondition, "{}", state.why);
    case OutputState::kFinished:
      if (!force) return Preparation::kKeep;
      if (note) *note = fmt::format("{}: redoing a finished analysis (--force)", in.name);
      break;
    case OutputState::kPartial:
      if (note) *note = fmt::format("{}: redoing a partial analysis ({})", in.name, state.why);
      break;
  }
  if (auto s = remove_output(dir); !s) return tl::unexpected(s.error());
  return Preparation::kRun;
}

bool record_outcome(const fs::path& out_dir, const PlannedInput& in,
                    const std::vector<std::string>& analyze_args, const ChildOutcome& o,
                    std::string* reason_out) {
  const fs::path dir = out_dir / in.name;
  const fs::path log = log_path(out_dir, in.name);
  std::string reason = o.reason;
  if (o.ok) {
    std::error_code ec;
    if (!fs::is_regular_file(dir / kSummaryFile, ec)) {
      reason = fmt::format("analyze exited with success but wrote no {}", kSummaryFile);
    } else if (auto s =
                   write_done_record(dir, {in.path.string(), analyze_args, o.seconds, utc_now()});
               !s) {
      reason = s.error().message;
    } else {
      (void)append_line(log, fmt::format("batch: ok after {:.3f} s", o.seconds));
      return true;
    }
  }
  if (reason.empty()) reason = "failed";
  if (reason_out) *reason_out = reason;
  if (o.interrupted || !o.started)
    (void)append_line(log, fmt::format("batch: interrupted after {:.3f} s", o.seconds));
  else
    (void)append_line(log, fmt::format("batch: failed after {:.3f} s: {}", o.seconds, reason));
  return false;
}

Result<BatchReport> run_batch(const BatchOptions& options, const BatchEvents& events,
                              const std::function<bool()>& stop) {
  if (auto s = open_batch_folder(options); !s) return tl::unexpected(s.error());
  auto lock = lock_batch_folder(options.out_dir);
  if (!lock) return tl::unexpected(lock.error());
  auto plan = plan_batch(options);
  if (!plan) return tl::unexpected(plan.error());

  const auto say = [&](const std::string& line) {
    if (events.message) events.message(line);
  };
  size_t total = 0, done = 0;
  for (const auto& in : *plan)
    if (in.status == PlanStatus::kRun) ++total;
  const auto progress = [&] {
    if (events.progress) events.progress(done, total);
  };

  BatchReport counts;
  std::vector<const PlannedInput*> to_run;
  std::vector<ChildCommand> commands;
  for (const auto& in : *plan) {
    if (in.status == PlanStatus::kSkipped) {
      say(fmt::format("skipped {}: {}", in.given, in.reason));
      continue;
    }
    if (in.status == PlanStatus::kFailed) {
      say(fmt::format("failed {}: {}", in.given, in.reason));
      continue;
    }
    std::string note;
    auto prep = prepare_output(options.out_dir, in, options.analyze_args, options.force, &note);
    if (!note.empty()) say(note);
    if (!prep) {
      // Recorded in the log so that the table (and collect) shows the reason.
      ChildOutcome o;
      o.started = true;
      o.reason = prep.error().message;
      record_outcome(options.out_dir, in, options.analyze_args, o);
      say(fmt::format("failed {}: {}", in.given, o.reason));
      ++done;
      continue;
    }
    if (*prep == Preparation::kKeep) {
      ++counts.reused;
      ++done;
      say(fmt::format("kept {} (finished earlier)", in.name));
      continue;
    }
    if (!note.empty()) ++counts.redone;
    to_run.push_back(&in);
    commands.push_back({analyze_command(options.executable, in.path, options.out_dir / in.name,
                                        options.analyze_args),
                        log_path(options.out_dir, in.name)});
  }
  progress();

  bool interrupted = false;
  PoolOptions po;
  po.workers = options.jobs;
  po.kill_grace_s = options.kill_grace_s;
  po.stop_requested = stop;
  run_pool(
      commands, po, [&](size_t) { ++counts.started; },
      [&](size_t i, const ChildOutcome& o) {
        const PlannedInput& in = *to_run[i];
        if (o.interrupted || !o.started) interrupted = true;
        std::string reason;
        if (!o.started) {
          // Never started: its folder stays absent (or partial from before), nothing to record.
          say(fmt::format("not started {} (interrupted)", in.name));
        } else if (record_outcome(options.out_dir, in, options.analyze_args, o, &reason)) {
          say(fmt::format("ok {} ({:.1f} s)", in.name, o.seconds));
        } else {
          say(o.interrupted ? fmt::format("interrupted {}", in.name)
                            : fmt::format("failed {}: {}", in.given, reason));
        }
        ++done;
        progress();
      });
  if (stop && stop()) interrupted = true;

  auto report = build_report(options.out_dir, *plan, options.analyze_args);
  if (!report) return tl::unexpected(report.error());
  report->reused = counts.reused;
  report->redone = counts.redone;
  report->started = counts.started;
  report->interrupted = interrupted;
  return report;
}

Result<BatchReport> collect_batch(const fs::path& out_dir) {
  std::error_code ec;
  if (!fs::is_directory(out_dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: not a folder", out_dir.string());
  auto plan = read_plan(out_dir);
  if (!plan) return tl::unexpected(plan.error());
  return build_report(out_dir, plan->inputs, plan->analyze_args);
}

Result<bool> run_task(const fs::path& out_dir, size_t index,
                      const std::vector<std::string>& analyze_args, const fs::path& executable,
                      const std::function<bool()>& stop) {
  const fs::path list = out_dir / "slurm" / "inputs.txt";
  std::ifstream in(list);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot read", list.string());
  std::string line;
  size_t n = 0;
  bool found = false;
  while (std::getline(in, line))
    if (n++ == index) {
      found = true;
      break;
    }
  if (!found || line.empty())
    return make_error(ErrorCode::kInvalidArgument, "{}: no input on line {} (0-based; {} lines)",
                      list.string(), index, n);
  PlannedInput input;
  input.given = line;
  input.path = line;
  input.name = output_name(input.path);
  auto prep = prepare_output(out_dir, input, analyze_args, /*force=*/false);
  if (!prep) {
    ChildOutcome o;
    o.started = true;
    o.reason = prep.error().message;
    record_outcome(out_dir, input, analyze_args, o);
    return make_error(ErrorCode::kFailedPrecondition, "{}", o.reason);
  }
  if (*prep == Preparation::kKeep) return true;
  bool finished = false;
  std::string reason;
  PoolOptions po;
  po.stop_requested = stop;
  run_pool({{analyze_command(executable, input.path, out_dir / input.name, analyze_args),
             log_path(out_dir, input.name)}},
           po, nullptr, [&](size_t, const ChildOutcome& o) {
             if (o.started)
               finished = record_outcome(out_dir, input, analyze_args, o, &reason);
             else
               reason = "interrupted before it started";
           });
  if (!finished) return make_error(ErrorCode::kFailedPrecondition, "{}: {}", line, reason);
  return true;
}

}  // namespace dreamsense::batch
