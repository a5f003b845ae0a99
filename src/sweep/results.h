// The result tables of a sweep folder (sweep/runner.h): one row per finished configuration, in
// the spec's order, flattened from runs/<id>/result.json.
//   results.json  {"sweep", "total", "finished", "failed", "rows": [...]}; a row has the
//                 configuration (id, scene, camera, width, height, device, technique, params),
//                 status and message, device name/driver, git revision, frame_wall_ms and
//                 device_total_ms (medians), passes_ms and kernels_ms (medians), passes (median,
//                 min, max), device_bytes, host_peak_rss_bytes, statistics (when the technique
//                 reports any, Technique::statistics), quality (ssim, grade, flip,
//                 relmse, psnr_db, or null), image/heatmap/reference paths relative to the folder,
//                 reference_spp.
//   results.csv   the same rows; columns param:<name>, pass:<name> ms, kernel:<name> ms and
//                 statistic:<name> are the union over rows.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace gi::sweep {

nlohmann::ordered_json loadResults(const std::string& dir);  // the results.json document, built afresh
void writeResultTables(const std::string& dir);       // writes results.json and results.csv

}  // namespace gi::sweep
