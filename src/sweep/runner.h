// Running a sweep (docs/SWEEPS.md). Layout of a sweep folder:
//   spec.json                 the spec as given (a resumed or merged sweep must have the same)
//   runs/<id>/result.json     one finished configuration: status ok|failed, message, `gi bench` JSON
//   runs/<id>/{bench.json, image.png, heatmap.png, log.txt}
//   references/<key>.exr      path-traced references (`gi reference`), shared by configurations;
//   references/<key>.checkpoint  a reference's progress while it renders (resumed after a stop)
//   results.json, results.csv one row per finished configuration; report.html (sweep/report.h)
// Each configuration runs as a child process of the same `gi` binary (`gi bench ...`), so a crash,
// an error or a time-out is recorded as that configuration's failure and the sweep goes on.
// result.json is written atomically after the child ends: a configuration interrupted midway has
// none and is run again on resume; finished ones (ok or failed) are not, unless retryFailed.
#pragma once
#include <string>
#include <vector>

#include "sweep/spec.h"

namespace gi::sweep {

struct RunOptions {
  std::string outDir;
  Shard shard;               // the whole sweep by default
  bool retryFailed = false;  // run failed configurations again on resume
  bool report = true;        // write report.html at the end
};

// Runs every configuration of the shard that has no result yet; returns the number that failed
// (in this run or before). Throws gi::Error for a bad spec, or a folder holding another sweep.
int runSweep(const std::string& specPath, const RunOptions& options);

// Combines the folders of shards of one sweep (same spec.json) into outDir, then writes the
// tables (and the report). A configuration finished in several inputs keeps an ok result over a
// failed one, else the first input's.
void mergeSweeps(const std::vector<std::string>& dirs, const std::string& outDir, bool report);

}  // namespace gi::sweep
