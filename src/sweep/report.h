// report.html of a sweep folder (sweep/runner.h, sweep/results.h): one self-contained page (no
// external files, scripts or fonts; images embedded as PNG data URIs) with, per group of
// configurations sharing scene, camera, resolution and device:
//   - a stacked bar chart of the median device time of every pass per configuration, and one
//     chart per pass with the median as a bar and the min..max over frames as a whisker (SVG);
//   - quality (LDR-FLIP, lower is better) against device time per frame, the Pareto front
//     (configurations no other one beats in both) joined and marked (SVG);
//   - the reference next to every configuration's final frame with its FLIP heat map;
//   - a table of every configuration (status, parameters, times, memory, quality);
// and the failed configurations with their messages.
#pragma once
#include <string>

namespace gi::sweep {

// Writes <dir>/report.html (and the display PNG of each reference beside its EXR); returns its path.
std::string writeReport(const std::string& dir);

}  // namespace gi::sweep
