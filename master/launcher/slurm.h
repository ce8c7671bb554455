// The farm as one Slurm job step (tessera-up --slurm): every compose service becomes a
// range of consecutive task ranks in one `srun --multi-prog` configuration. In a
// heterogeneous job (two components: the display's node, then the farm's nodes) the display
// is a step of component 0 and the rest a step of component 1, run side by side. Each task
// runs `tessera-up --slurm-task`, which finds the master's and the display's nodes through
// files in the run folder (shared by the job's nodes: it is in the job's working folder),
// then starts its one stage as tessera-up would, restarts included.
//
// The run folder, <working folder>/.tessera-slurm/<job>-<farm>, mode 0700:
//   settings.env    the run's TESSERA_* settings (identity, CURVE on, key folder, --env)
//   keys/           the farm's CURVE keys, made for this run
//   multi-prog.conf the task ranks of each service (multi-prog-<group>.conf per component)
//   master.endpoint tcp://ADDRESS:PORT, written by the master's task when it starts
//   display.host    ADDRESS, written by the display's task
//   finished        written by the display's task when the display finished (success)
// ADDRESS is the node's NodeAddr as Slurm knows it; PORT is derived from the job id and the
// farm number and moved on by 100 while ports are taken on the master's node.
#pragma once
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "master/launcher/compose.h"

namespace tessera::launcher {

struct SlurmTaskRange {
  int first = 0, last = 0;  // task ranks, inclusive
  std::string service;
};

// One srun: its services' task ranks (from 0) and, in a heterogeneous job, its component.
struct SlurmStep {
  int het_group = -1;  // -1: not a heterogeneous job
  std::vector<SlurmTaskRange> ranges;
  int tasks = 0;
  std::string conf;  // its multi-prog file's name in the run folder
};

struct SlurmPlan {
  std::string job;                  // SLURM_JOB_ID
  int farm = 1;                     // the farm's number within the job
  std::filesystem::path run_dir;    // <cwd>/.tessera-slurm/<job>-<farm>
  std::vector<SlurmStep> steps;
  std::map<std::string, std::string> settings;  // what settings.env holds
};

// The steps: one with every service (het_size 0 or 1), or the display's and the rest's (2).
// Services in start order (dependencies first), replicas on consecutive ranks. Throws
// LaunchError for other component counts.
std::vector<SlurmStep> slurmSteps(const ComposeProject& project, int het_size);
// 20000..59900 in steps of 100, from the job id and the farm number: two farms of one job,
// or of jobs with neighbouring ids, start on different ports.
int slurmFirstPort(const std::string& job, int farm);
// A step's `srun --multi-prog` file: "RANKS TESSERA-UP --slurm-task SERVICE --offset %o ...".
std::string multiProgConfig(const SlurmPlan& plan, const SlurmStep& step, const std::string& tessera_up,
                            const std::string& compose_file);
// The srun command line that runs a step.
std::vector<std::string> srunCommand(const SlurmPlan& plan, const SlurmStep& step);
// settings.env text (KEY=VALUE lines, values quoted).
std::string settingsText(const std::map<std::string, std::string>& settings);

// tessera-up --slurm: makes the run folder and keys, runs srun, removes the folder.
// With dry_run prints the plan (multi-prog file, settings, each service's argv and
// environment) and creates nothing. Returns the exit code.
int runSlurm(const std::filesystem::path& compose_file, const ComposeOptions& options, bool dry_run);

// tessera-up --slurm-task: one task of the step (SLURM_PROCID, SLURMD_NODENAME): publishes
// or waits for the rendezvous files, then runs its stage; returns the exit code (non-zero
// only when the master or the display is lost, which ends the step: srun --kill-on-bad-exit).
int runSlurmTask(const std::filesystem::path& compose_file, const std::filesystem::path& run_dir,
                 const std::string& service, int replica);

}  // namespace tessera::launcher
