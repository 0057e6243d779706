#include "dreamsense/batch/slurm.hpp"

#include <nlohmann/json.hpp>

#include <system_error>

namespace dreamsense::batch {
namespace fs = std::filesystem;

Status SlurmOptions::check() const {
  if (sbatch.empty()) return make_error(ErrorCode::kInvalidArgument, "batch: sbatch is empty");
  if (max_running < 0)
    return make_error(ErrorCode::kInvalidArgument, "batch: the Slurm throttle must be >= 0");
  for (const auto& d : directives)
    if (d.empty() || d[0] != '-' || d.find('\n') != std::string::npos)
      return make_error(ErrorCode::kInvalidArgument,
                        "batch: --slurm-option \"{}\" must be one sbatch option like "
                        "--partition=short",
                        d);
  return ok_status();
}

std::string shell_quote(const std::string& word) {
  std::string q = "'";
  for (char c : word) {
    if (c == '\'')
      q += "'\\''";
    else
      q += c;
  }
  return q + "'";
}

std::string slurm_script(const BatchOptions& options, const SlurmOptions& slurm, size_t tasks) {
  const fs::path out = fs::absolute(options.out_dir).lexically_normal();
  const fs::path dir = out / "slurm";
  std::string array = fmt::format("0-{}", tasks == 0 ? 0 : tasks - 1);
  if (slurm.max_running > 0) array += fmt::format("%{}", slurm.max_running);
  std::string s = "#!/bin/bash\n";
  s += "# Written by `dreamsense batch --slurm` (docs/batch.md). Array task i analyses line i\n";
  s += "# (0-based) of inputs.txt into " + out.string() + "/<name>; then\n";
  s += "# `dreamsense batch collect " + out.string() + "` writes batch.csv.\n";
  s += "#SBATCH --job-name=" + slurm.job_name + "\n";
  s += "#SBATCH --array=" + array + "\n";
  s += "#SBATCH --ntasks=1\n";
  s += "#SBATCH --output=" + (dir / "task-%A_%a.out").string() + "\n";
  for (const auto& d : slurm.directives) s += "#SBATCH " + d + "\n";
  s += "set -u\n";
  s += "exec " + shell_quote(options.executable.string()) + " -q batch task " +
       shell_quote(out.string()) +
       " \"${SLURM_ARRAY_TASK_ID:?this script runs as a Slurm array task}\"";
  if (!options.analyze_args.empty()) {
    s += " --";
    for (const auto& a : options.analyze_args) s += " " + shell_quote(a);
  }
  s += "\n";
  return s;
}

namespace {

// "123" or "123;cluster" from `sbatch --parsable`.
Result<std::string> submit(const std::vector<std::string>& argv) {
  auto run = run_captured(argv);
  if (!run) return tl::unexpected(run.error());
  if (run->exit_code != 0) {
    std::string err = failure_reason(run->err, run->exit_code, run->term_signal);
    return make_error(ErrorCode::kFailedPrecondition, "{} failed: {}", argv[0], err);
  }
  std::string id = run->out;
  if (auto semi = id.find(';'); semi != std::string::npos) id.resize(semi);
  while (!id.empty() && (id.back() == '\n' || id.back() == '\r' || id.back() == ' ')) id.pop_back();
  if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
    return make_error(ErrorCode::kCorruptData, "{} printed no job id (got \"{}\")", argv[0],
                      run->out);
  return id;
}

}  // namespace

Result<SlurmSubmission> submit_slurm(const BatchOptions& options, const SlurmOptions& slurm) {
  if (auto s = slurm.check(); !s) return tl::unexpected(s.error());
  if (auto s = open_batch_folder(options); !s) return tl::unexpected(s.error());
  auto lock = lock_batch_folder(options.out_dir);
  if (!lock) return tl::unexpected(lock.error());
  auto plan = plan_batch(options);
  if (!plan) return tl::unexpected(plan.error());

  SlurmSubmission sub;
  std::string list;
  for (const auto& in : *plan) {
    if (in.status != PlanStatus::kRun) continue;
    auto prep = prepare_output(options.out_dir, in, options.analyze_args, options.force);
    if (!prep) {
      ChildOutcome o;
      o.started = true;
      o.reason = prep.error().message;
      record_outcome(options.out_dir, in, options.analyze_args, o);
      continue;
    }
    if (*prep == Preparation::kKeep) {
      ++sub.already_finished;
      continue;
    }
    list += in.path.string() + "\n";
    ++sub.tasks;
  }
  const fs::path dir = fs::absolute(options.out_dir).lexically_normal() / "slurm";
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: cannot create: {}", dir.string(), ec.message());
  sub.list = dir / "inputs.txt";
  sub.script = dir / "batch.sbatch";
  if (auto s = write_file_atomically(sub.list, list); !s) return tl::unexpected(s.error());
  if (auto s = write_file_atomically(sub.script, slurm_script(options, slurm, sub.tasks)); !s)
    return tl::unexpected(s.error());
  if (sub.tasks == 0) {
    if (auto r = collect_batch(options.out_dir); !r) return tl::unexpected(r.error());
    return sub;
  }
  auto id = submit({slurm.sbatch, "--parsable", sub.script.string()});
  if (!id) return tl::unexpected(id.error());
  sub.job_id = *id;
  if (slurm.collect_job) {
    const fs::path out = fs::absolute(options.out_dir).lexically_normal();
    const std::string collect =
        shell_quote(options.executable.string()) + " -q batch collect " + shell_quote(out.string());
    std::vector<std::string> argv = {slurm.sbatch,
                                     "--parsable",
                                     "--dependency=afterany:" + sub.job_id,
                                     "--job-name=" + slurm.job_name + "-collect",
                                     "--ntasks=1",
                                     "--output=" + (dir / "collect-%j.out").string()};
    argv.insert(argv.end(), slurm.directives.begin(), slurm.directives.end());
    argv.push_back("--wrap=" + collect);
    auto cid = submit(argv);
    if (!cid) return tl::unexpected(cid.error());
    sub.collect_job_id = *cid;
  }
  const nlohmann::json j = {{"job_id", sub.job_id},
                            {"collect_job_id", sub.collect_job_id},
                            {"tasks", sub.tasks},
                            {"already_finished", sub.already_finished},
                            {"script", sub.script.string()},
                            {"list", sub.list.string()},
                            {"submitted_utc", utc_now()}};
  if (auto s = write_file_atomically(dir / "submission.json", j.dump(2) + "\n"); !s)
    return tl::unexpected(s.error());
  return sub;
}

}  // namespace dreamsense::batch
