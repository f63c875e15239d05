// The spate command-line program: parse, load the case, run, report. Exit codes (spate --help,
// docs/cli.md): 0 done, 1 `compare` found differences, 2 bad input, 3 the run went unstable,
// 4 internal error, 5 an output could not be written, 6 out of memory, 130/143 stopped by
// SIGINT/SIGTERM.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>

#include "commands.hpp"
#include "comm/process_group.hpp"
#include "io/log.hpp"
#include "io/provenance.hpp"
#include "io/version.hpp"
#ifdef SPATE_WITH_CATALYST
#include "insitu_helper.hpp"
#endif

namespace {

// Under mpirun every rank ends the same way. Bad input and internal errors may strike one rank
// only, while its peers wait in a collective: MPI_Abort ends them all (no hang). Outcomes every
// rank agrees on (done, differences, unstable) finalise MPI normally.
// Bad input is mostly found by every rank at once; rank 0 writes the refusal's summary.json, so the
// others give it a moment before they end the job.
int finish(int code) {
  const auto& group = spate::process_group();
  if (group.ranks > 1 && code == 2 && group.rank != 0) std::this_thread::sleep_for(std::chrono::seconds(1));
  if (group.ranks > 1 && (code == 2 || (code >= 4 && code <= 6))) spate::abort_process_group(code);
  spate::finalize_process_group();
  return code;
}

std::string who() {
  const auto& g = spate::process_group();
  return g.ranks > 1 ? fmt::format("spate (rank {} of {})", g.rank, g.ranks) : std::string("spate");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace spate::app;
#ifdef SPATE_WITH_CATALYST
  // The in-situ helper process spate starts for its Catalyst pipelines (adaptors/catalyst).
  if (argc > 1 && std::string_view(argv[1]) == spate::catalyst::kHelperCommand) return spate::catalyst::run_insitu_helper(argc, argv);
#endif
  // A file-size limit (ulimit -f) makes a write fail with EFBIG, which spate reports, rather than
  // kill the process with SIGXFSZ before it can say anything.
  std::signal(SIGXFSZ, SIG_IGN);
  spate::record_invocation(argc, argv);
  spate::configure_logging(spdlog::level::info);
  try {
    spate::init_process_group(argc, argv);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  spate::configure_logging(spdlog::level::info, who());
  CLI::App app{"spate: weakly-compressible SPH for free-surface flows, on CPUs and GPUs, watched and steered in situ.\n"};
  app.set_version_flag("--version", fmt::format("spate {} (commit {})", spate::version(), spate::git_commit()),
                       "Print the version and the git commit it was built from, then exit");
  // Options of the program itself may also follow the command (spate run case.yaml --log-level debug).
  app.fallthrough();
  std::string log_level = "info";
  app.add_option("--log-level", log_level,
                 "trace, debug, info (default), warning, error or off. Without a terminal lines carry a UTC timestamp")
      ->check([](const std::string& v) { return spate::parse_log_level(v) ? std::string() : "expected trace, debug, info, warning, error or off"; });
  app.footer(
      "Exit codes: 0 done; 1 compare found differences; 2 bad input (case file, options, restart file, steering log,\n"
      "            output folder, a run too large for the memory); 3 the run went unstable (diagnostic snapshot written,\n"
      "            last good checkpoint kept); 4 internal error; 5 an output could not be written (disk full);\n"
      "            6 out of memory; 130, 143 stopped by SIGINT, SIGTERM (final checkpoint written). docs/cli.md has more.");
  app.require_subcommand(1);
  // Parse errors look like every other bad-input message (and exit 2, below).
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return fmt::format("spate: error: {}\nRun 'spate --help' or 'spate COMMAND --help' for more information.\n", e.what());
  });

  RunArgs run;
  auto* run_cmd = app.add_subcommand("run", "Run a case");
  run_cmd->add_option("case", run.case_file, "Case file (YAML)")->required();
  run_cmd->add_option("--out", run.out, "Output folder (default out/<case name>)");
  auto* steps_opt = run_cmd->add_option("--steps", run.steps, "Run this many steps");
  run_cmd->add_option("--until", run.until, "Run until this simulated time [s]")->excludes(steps_opt);
  run_cmd->add_option("--set", run.overrides, "Override a case key: key.path=value (repeatable)");
  run_cmd->add_option("--threads", run.threads, "CPU threads in all (default: all cores)");
  run_cmd->add_option("--devices", run.devices, "Device workers (x-slabs) in this process");
  run_cmd->add_option("--backend", run.backend, "cpu or cuda");
  run_cmd->add_option("--checkpoint-every", run.checkpoint_every, "Write a checkpoint every N steps");
  run_cmd->add_option("--checkpoint-keep-last", run.checkpoint_keep_last, "Keep the newest K checkpoints (default 2; 0: all)");
  run_cmd->add_option("--checkpoint-keep-every", run.checkpoint_keep_every,
                      "Also keep for good every checkpoint at a multiple of N x --checkpoint-every steps");
  run_cmd->add_option("--restart", run.restart, "Continue from a checkpoint (HDF5)");
  run_cmd->add_flag("--quiet", run.quiet, "No progress output");
  run_cmd->add_option("--pipeline", run.pipelines, "ParaView Catalyst script (repeatable)");
  run_cmd->add_option("--insitu-every", run.insitu_every, "Run pipelines every N steps");
  auto* live_opt = run_cmd->add_option("--live", run.live, "Connect out to ParaView Catalyst Live at [HOST:]PORT (docs/live.md)")
                       ->expected(0, 1)
                       ->default_str("localhost:22222");
  run_cmd->add_option("--steering-log", run.steering_log, "Replay a recorded steering log");

  InfoArgs info;
  auto* info_cmd = app.add_subcommand("info", "Particle counts, resolution, sound speed, time step and memory of a case; no run");
  info_cmd->add_option("case", info.case_file, "Case file (YAML)")->required();
  info_cmd->add_option("--set", info.overrides, "Override a case key: key.path=value (repeatable)");
  info_cmd->add_option("--backend", info.backend, "cpu or cuda");
  info_cmd->add_option("--devices", info.devices, "Device workers to size memory for");
  info_cmd->add_flag("--json", info.json, "Print one JSON object");

  CompareArgs cmp;
  auto* cmp_cmd = app.add_subcommand("compare", "Compare two checkpoints particle by particle (matched by id)");
  cmp_cmd->add_option("a", cmp.a, "First checkpoint")->required();
  cmp_cmd->add_option("b", cmp.b, "Second checkpoint")->required();
  cmp_cmd->add_option("--tolerance", cmp.tolerance, "Largest allowed absolute difference (default 0: bit-identical)");
  cmp_cmd->add_option("--scaled-tolerance", cmp.scaled_tolerance,
                      "Largest allowed difference of each field as a fraction of its scale (dp, c0, rho0, c0^2/h, rho0 c0/h; material exact), "
                      "from the case stored in the first checkpoint");

  PostArgs post;
  auto* post_cmd = app.add_subcommand("post", "After a run: evaluate probes and run Catalyst pipelines on its saved snapshots or checkpoints");
  post_cmd->add_option("run_dir", post.run_dir, "The run's output folder (spate run --out)")->required();
  post_cmd->add_option("--probe", post.probes,
                       "A probe as in a case file, in YAML: '{name: p1, type: pressure, position: [0.5, 0.1]}' (repeatable; "
                       "replaces the case's probes)");
  post_cmd->add_option("--from", post.from, "snapshots or checkpoints (default: snapshots when the run wrote any)");
  post_cmd->add_option("--step", post.steps, "Only this saved step (repeatable)");
  post_cmd->add_option("--pipeline", post.pipelines, "ParaView Catalyst script to run on every saved step (repeatable)");
  post_cmd->add_option("--out", post.out, "Output folder (default RUN_DIR/post)");
  post_cmd->add_option("--threads", post.threads, "CPU threads (default: all cores)");
  post_cmd->add_flag("--plot", post.plot, "Also plot the probes (as spate plot OUT)");

  PlotArgs plot;
  auto* plot_cmd = app.add_subcommand("plot", "PNG plots of every probe of a run (or of a spate post output folder)");
  plot_cmd->add_option("dir", plot.dir, "Run folder (or post output folder) with probes/*.csv")->required();
  plot_cmd->add_option("--out", plot.out, "Where the PNGs go (default DIR/plots)");

  GrowthArgs growth;
  auto* growth_cmd = app.add_subcommand("growth", "Growth rate of an instability: fit C e^(n t) + D e^(-n t) to a probe's amplitude in its linear range");
  growth_cmd->add_option("csv", growth.csv, "Probe CSV (probes/<name>.csv of a run)")->required();
  growth_cmd->add_option("--column", growth.column, "Column name, without its unit (default: amplitude)");
  growth_cmd->add_option("--until", growth.until, "The linear range ends where the amplitude first exceeds this (default: 5 times its first value)");
  growth_cmd->add_flag("--json", growth.json, "Print one JSON object");

  BenchArgs bench;
  auto* bench_cmd = app.add_subcommand("bench", "Measure particle-steps and neighbour interactions per second");
  bench_cmd->add_option("case", bench.case_file, "Case file (YAML)")->required();
  bench_cmd->add_option("--set", bench.overrides, "Override a case key (repeatable)");
  bench_cmd->add_option("--steps", bench.steps, "Timed steps (after warm-up)");
  bench_cmd->add_option("--threads", bench.threads, "CPU threads in all");
  bench_cmd->add_option("--devices", bench.devices, "Device workers");
  bench_cmd->add_option("--backend", bench.backend, "cpu or cuda");
  bench_cmd->add_flag("--json", bench.json, "Print one JSON object");
  bench_cmd->add_flag("--pass-times", bench.pass_times,
                      "Time each pass of the step (SPATE_PASS_TIMERS=1; CUDA events on a GPU): pass_seconds per device");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return finish(code == 0 ? 0 : 2);
  }
  // --quiet (run) means warnings and errors only, unless a level was asked for.
  spdlog::level::level_enum level = *spate::parse_log_level(log_level);
  if (run.quiet && app.get_option("--log-level")->count() == 0) level = spdlog::level::warn;
  spate::configure_logging(level, who());
  try {
    run.live_requested = live_opt->count() > 0;
    spate::app::check_environment();
    if (*run_cmd) return finish(run_command(run));
    if (*info_cmd) return finish(info_command(info));
    if (*cmp_cmd) return finish(compare_command(cmp));
    if (*post_cmd) return finish(post_command(post));
    if (*plot_cmd) return finish(plot_command(plot));
    if (*growth_cmd) return finish(growth_command(growth));
    if (*bench_cmd) return finish(bench_command(bench));
  } catch (const BadInput& e) {
    spdlog::error("{}", e.what());
    return finish(2);
  } catch (const std::filesystem::filesystem_error& e) {
    // A file or folder spate was asked to use and cannot: not a bug in spate.
    spdlog::error("{}", e.what());
    return finish(2);
  } catch (const std::exception& e) {
    spdlog::error("internal error: {}", e.what());
    return finish(4);
  }
  return finish(0);
}
