// `gi sweep`: run a sweep spec (scenes × cameras × resolutions × devices × techniques × parameter
// grids), each configuration as an isolated `gi bench` child; resume, shard, merge, and write the
// tables and the HTML report. Everything is in src/sweep/; the format is in docs/SWEEPS.md.
//   gi sweep SPEC.json --out DIR [--shard i/n] [--retry-failed] [--no-report]
//   gi sweep --report DIR
//   gi sweep --merge DIR... --out DIR
// A configuration that fails is a result (status failed, with its message), not an error of the
// sweep: the exit status is 0 once every configuration has a result, whatever it is.
#include <cstdio>

#include "app/commands.h"
#include "sweep/report.h"
#include "sweep/runner.h"
#include "util/error.h"

namespace gi::app {

namespace {

struct SweepArgs {
  std::string spec, out, reportDir, shard;
  std::vector<std::string> merge;
  bool retryFailed = false, noReport = false;
};

void run(const SweepArgs& a) {
  int modes = int(!a.spec.empty()) + int(!a.reportDir.empty()) + int(!a.merge.empty());
  if (modes != 1) throw Error("sweep: give exactly one of SPEC.json, --report DIR or --merge DIR... (see gi sweep --help)");
  if (!a.reportDir.empty()) {
    std::printf("wrote %s\n", sweep::writeReport(a.reportDir).c_str());
    return;
  }
  if (!a.merge.empty()) {
    if (!a.shard.empty()) throw Error("sweep: --shard does not apply to --merge");
    sweep::mergeSweeps(a.merge, a.out, !a.noReport);
    std::printf("merged %zu folder(s) into %s\n", a.merge.size(), a.out.c_str());
    return;
  }
  sweep::RunOptions o;
  o.outDir = a.out;
  if (!a.shard.empty()) o.shard = sweep::parseShard(a.shard);
  o.retryFailed = a.retryFailed;
  o.report = !a.noReport;
  sweep::runSweep(a.spec, o);
}

}  // namespace

void registerSweepCommand(CLI::App& app) {
  auto args = std::make_shared<SweepArgs>();
  auto* cmd = app.add_subcommand("sweep", "Run a benchmark sweep spec; resume, shard, merge, report (docs/SWEEPS.md)");
  cmd->add_option("spec", args->spec, "sweep spec (JSON, docs/SWEEPS.md)");
  cmd->add_option("--out", args->out, "sweep folder: results, images, logs (reused to resume)");
  cmd->add_option("--shard", args->shard, "run only slice i of n (0 <= i < n): configurations whose index is i mod n");
  cmd->add_flag("--retry-failed", args->retryFailed, "run configurations that failed before again");
  cmd->add_flag("--no-report", args->noReport, "do not write report.html at the end");
  cmd->add_option("--report", args->reportDir, "only (re)write DIR/report.html from the results in DIR");
  cmd->add_option("--merge", args->merge, "combine these sweep folders (shards of one spec) into --out")->expected(1, -1);
  cmd->callback([args] { run(*args); });
}

}  // namespace gi::app
