#pragma once
// `dreamsense batch --slurm`: the same analyses as a Slurm job array, one input per array task.
//
// In OUT/slurm/ it writes inputs.txt (the inputs still to analyse, one absolute path per line;
// array index i = line i, 0-based) and batch.sbatch, a job-array script whose task i runs
//   dreamsense -q batch task OUT i -- <analyze flags>
// (the same analysis, done record and log as a local batch), submits it with
// `sbatch --parsable`, then submits `dreamsense batch collect OUT` as a job that runs after the
// array has ended (--dependency=afterany), which writes OUT/batch.csv. The job ids are kept in
// OUT/slurm/submission.json. The dreamsense executable and OUT must be on a file system that the
// compute nodes share.

#include "dreamsense/batch/batch.hpp"

#include <string>
#include <vector>

namespace dreamsense::batch {

struct SlurmOptions {
  std::string sbatch = "sbatch";        // program that submits (looked up in PATH)
  int max_running = 0;                  // array throttle (%N); 0: no limit
  std::vector<std::string> directives;  // extra "#SBATCH ..." options, e.g. --partition=x
  bool collect_job = true;              // also submit the collect job
  std::string job_name = "dreamsense-batch";
  Status check() const;
};

struct SlurmSubmission {
  std::filesystem::path script, list;
  size_t tasks = 0;                    // array size (0: nothing left to analyse, nothing submitted)
  size_t already_finished = 0;         // inputs kept from earlier runs
  std::string job_id, collect_job_id;  // empty when not submitted
};

// The job-array script (also written to OUT/slurm/batch.sbatch).
std::string slurm_script(const BatchOptions& options, const SlurmOptions& slurm, size_t tasks);

// Quotes one word for bash (single quotes).
std::string shell_quote(const std::string& word);

// Plans, clears partial outputs, writes the list and the script, and submits them. With nothing
// left to analyse it submits nothing and writes batch.csv at once.
Result<SlurmSubmission> submit_slurm(const BatchOptions& options, const SlurmOptions& slurm);

}  // namespace dreamsense::batch
