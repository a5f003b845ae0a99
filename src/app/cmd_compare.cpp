// `gi compare --reference A --test B`: image metrics of a test image against a reference
// (SSIM, ten Brug's grade, PSNR, RMSE, relative MSE, LDR-FLIP; src/metrics, docs/METRICS.md).
//
// Inputs: .exr/.hdr/.pfm files are linear HDR; anything else (PNG, JPEG, ...) is taken as already
// display-encoded (sRGB, [0,1]). Every metric needs each image in one domain, so each input is
// brought to both: a linear image gets the shared display transform (ALGORITHMS.md §0) with
// --exposure; a display image gets its inverse, srgbDecode(v) / exposure (values the display
// clipped stay clipped). SSIM, grade, PSNR and FLIP use display images; RMSE and relMSE linear.
//
// Outputs (JSON, heat map) are computed in full before anything is written and are written
// atomically; any error (unreadable file, size mismatch, unknown metric, bad output name) is
// one gi::Error line, a non-zero exit and no output file.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "image/image.h"
#include "metrics/metrics.h"
#include "util/error.h"
#include "util/file_io.h"

namespace gi::app {

namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kKnownMetrics = {"ssim", "grade", "grade255", "psnr", "rmse", "relmse", "flip"};

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

std::string lowerExtension(const fs::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string oneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// "ssim,flip" → validated, de-duplicated, in the order given.
std::vector<std::string> parseMetrics(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    if (name.empty()) continue;
    if (std::find(kKnownMetrics.begin(), kKnownMetrics.end(), name) == kKnownMetrics.end())
      throw Error("compare: unknown metric '" + name + "' (known: " + joined(kKnownMetrics) + ")");
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  }
  if (out.empty()) throw Error("compare: --metrics names no metric (known: " + joined(kKnownMetrics) + ")");
  return out;
}

struct Input {
  std::string path;
  bool linear = false;  // file holds linear HDR values
  Image display, lin;   // 3-channel RGB in both domains
};

Input load(const std::string& role, const std::string& path, float exposure) {
  if (!fs::exists(path)) throw Error("compare: " + role + " image '" + path + "' does not exist");
  Input in;
  in.path = path;
  std::string ext = lowerExtension(path);
  in.linear = ext == ".exr" || ext == ".hdr" || ext == ".pfm";
  Image raw;
  try {
    raw = readImage(path);
  } catch (const Error& e) {
    throw Error("compare: " + role + " image: " + oneLine(e.what()));
  }
  if (raw.width <= 0 || raw.height <= 0 || raw.channels <= 0) throw Error("compare: " + role + " image '" + path + "' is empty");
  Image rgb = metrics::toRgb(raw);
  if (in.linear) {
    in.display = displayTransform(rgb, exposure);
    in.lin = std::move(rgb);
  } else {
    in.lin = metrics::displayToLinear(rgb, exposure);
    in.display = std::move(rgb);
  }
  return in;
}

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

struct Options {
  std::string reference, test, metrics = joined(kKnownMetrics), heatmap, heatmapKind = "flip", json;
  float exposure = 1.0f;
  double ppd = metrics::kDefaultPpd;
};

void runCompare(const Options& o) {
  // Everything the user can get wrong is checked before the (slower) image work.
  const std::vector<std::string> names = parseMetrics(o.metrics);
  if (!(o.exposure > 0.0f) || !std::isfinite(o.exposure))
    throw Error("compare: --exposure must be a positive number (got " + std::to_string(o.exposure) + ")");
  if (!(o.ppd > 0.0) || !std::isfinite(o.ppd)) throw Error("compare: --ppd must be a positive number");
  if (!o.heatmap.empty()) {
    std::string ext = lowerExtension(o.heatmap);
    if (ext != ".png" && ext != ".exr")
      throw Error("compare: heat map '" + o.heatmap + "' must end in .png (magma colours) or .exr (raw values)");
  }

  const Input ref = load("reference", o.reference, o.exposure);
  const Input test = load("test", o.test, o.exposure);
  if (ref.display.width != test.display.width || ref.display.height != test.display.height)
    throw Error("compare: image sizes differ: reference '" + ref.path + "' is " + std::to_string(ref.display.width) + "x" +
                std::to_string(ref.display.height) + ", test '" + test.path + "' is " + std::to_string(test.display.width) +
                "x" + std::to_string(test.display.height));
  auto wants = [&](const char* n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  bool needSsim = wants("ssim") || wants("grade") || wants("grade255");
  if (needSsim && (ref.display.width < metrics::kSsimMinSize || ref.display.height < metrics::kSsimMinSize))
    throw Error("compare: ssim/grade need images of at least " + std::to_string(metrics::kSsimMinSize) + "x" +
                std::to_string(metrics::kSsimMinSize) + " pixels ('" + ref.path + "' is " + std::to_string(ref.display.width) +
                "x" + std::to_string(ref.display.height) + ")");

  nlohmann::json values = nlohmann::json::object(), details = nlohmann::json::object();
  struct Row { std::string name, value, note; };
  std::vector<Row> rows;
  char buf[64];
  auto fmt = [&](const char* f, double v) {
    std::snprintf(buf, sizeof buf, f, v);
    return std::string(buf);
  };

  std::optional<metrics::SsimResult> ssim;
  if (wants("ssim") || wants("grade")) ssim = metrics::ssim(ref.display, test.display);
  std::optional<metrics::FlipResult> flip;
  if (wants("flip") || (!o.heatmap.empty() && o.heatmapKind == "flip")) flip = metrics::flip(ref.display, test.display, o.ppd);

  for (const auto& n : names) {
    if (n == "ssim") {
      values["ssim"] = ssim->mean;
      details["ssim_rgb"] = {ssim->channel[0], ssim->channel[1], ssim->channel[2]};
      rows.push_back({n, fmt("%.6f", ssim->mean), "display; mean of R,G,B; 11x11 Gaussian s=1.5; 5 px border cropped"});
    } else if (n == "grade") {
      auto g = metrics::tenBrugGrade(ref.display, test.display, *ssim);
      values["grade"] = g.grade;
      details["grade_mssim_rgb"] = {g.mssim[0], g.mssim[1], g.mssim[2]};
      details["grade_counted_pixels"] = g.countedPixels;
      details["grade_ignored_black_pixels"] = g.ignoredBlackPixels;
      rows.push_back({n, fmt("%.4f", g.grade), "ten Brug: 10 x mean MSSIM^1000 of R,G,B; " + std::to_string(g.ignoredBlackPixels) +
                                                   " black-in-both px ignored"});
    } else if (n == "grade255") {
      auto g = metrics::tenBrugGrade(ref.display, test.display,
                                     metrics::ssim(ref.display, test.display, metrics::kSsimDataRange8Bit));
      values["grade255"] = g.grade;
      details["grade255_mssim_rgb"] = {g.mssim[0], g.mssim[1], g.mssim[2]};
      rows.push_back({n, fmt("%.4f", g.grade), "ten Brug's grade on SSIM with C1, C2 for L = 255 on [0,1] values (seed-003 tables only)"});
    } else if (n == "psnr") {
      double v = metrics::psnr(ref.display, test.display);
      values["psnr"] = number(v);
      details["psnr_infinite"] = std::isinf(v);
      rows.push_back({n, std::isinf(v) ? "inf dB" : fmt("%.4f dB", v), "display, peak 1"});
    } else if (n == "rmse") {
      double v = metrics::rmse(ref.lin, test.lin);
      values["rmse"] = number(v);
      rows.push_back({n, fmt("%.6g", v), "linear"});
    } else if (n == "relmse") {
      double v = metrics::relMse(ref.lin, test.lin);
      values["relmse"] = number(v);
      details["relmse_epsilon"] = metrics::kRelMseEpsilon;
      rows.push_back({n, fmt("%.6g", v), "linear; mean (t-r)^2/(r^2+0.01)"});
    } else if (n == "flip") {
      values["flip"] = flip->mean;
      rows.push_back({n, fmt("%.6f", flip->mean), "LDR-FLIP mean; " + fmt("%.2f", o.ppd) + " ppd"});
    }
  }

  // Heat map, computed in memory first.
  Image heat;
  if (!o.heatmap.empty()) {
    Image map;
    if (o.heatmapKind == "flip") map = flip->map;
    else if (o.heatmapKind == "abs") map = metrics::absoluteErrorMap(ref.display, test.display);
    else map = metrics::relativeErrorMap(ref.lin, test.lin);
    heat = lowerExtension(o.heatmap) == ".png" ? metrics::magmaHeatmap(map) : map;
  }

  nlohmann::json doc = {
      {"reference", {{"path", ref.path}, {"encoding", ref.linear ? "linear" : "display"}}},
      {"test", {{"path", test.path}, {"encoding", test.linear ? "linear" : "display"}}},
      {"width", ref.display.width},
      {"height", ref.display.height},
      {"exposure", o.exposure},
      {"ppd", o.ppd},
      {"metrics", values},
      {"details", details},
  };

  std::printf("reference %s (%s)\ntest      %s (%s)\nsize      %dx%d, exposure %g\n", ref.path.c_str(),
              ref.linear ? "linear" : "display", test.path.c_str(), test.linear ? "linear" : "display", ref.display.width,
              ref.display.height, double(o.exposure));
  std::printf("%-8s %-14s %s\n", "metric", "value", "notes");
  for (auto& r : rows) std::printf("%-8s %-14s %s\n", r.name.c_str(), r.value.c_str(), r.note.c_str());

  // Write; if the second output fails, take the first back so a failed run leaves nothing.
  bool wroteHeat = false;
  try {
    if (!o.heatmap.empty()) {
      writeImage(o.heatmap, heat);
      wroteHeat = true;
    }
    if (!o.json.empty()) {
      writeAtomically(o.json, [&](const fs::path& tmp) {
        std::ofstream out(tmp);
        out << doc.dump(2) << "\n";
        out.close();
        if (!out) throw Error("cannot write '" + o.json + "'");
      });
    }
  } catch (const Error& e) {
    if (wroteHeat) {
      std::error_code ec;
      fs::remove(o.heatmap, ec);
    }
    throw Error("compare: " + oneLine(e.what()));
  }
}

}  // namespace

void registerCompareCommand(CLI::App& app) {
  auto opts = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("compare", "Image metrics of a test image against a reference (docs/METRICS.md)");
  cmd->add_option("--reference", opts->reference, "Reference image (.exr linear HDR, .png display-encoded)")->required();
  cmd->add_option("--test", opts->test, "Test image (.exr linear HDR, .png display-encoded)")->required();
  cmd->add_option("--metrics", opts->metrics, "Comma-separated subset of " + joined(kKnownMetrics))->capture_default_str();
  cmd->add_option("--exposure", opts->exposure, "Exposure of the display transform for linear inputs")->capture_default_str();
  cmd->add_option("--ppd", opts->ppd, "FLIP pixels per degree (default: 0.7 m from a 0.7 m wide 3840 px monitor)")
      ->capture_default_str();
  cmd->add_option("--heatmap", opts->heatmap, "Write an error heat map: .png (magma colours) or .exr (raw values)");
  cmd->add_option("--heatmap-kind", opts->heatmapKind, "Heat map of: flip (FLIP error), abs (|t-r| of display values), rel "
                                                       "(linear (t-r)^2/(r^2+0.01)); all shown on [0,1]")
      ->check(CLI::IsMember({"flip", "abs", "rel"}))
      ->capture_default_str();
  cmd->add_option("--json", opts->json, "Write the metrics as JSON");
  cmd->callback([opts] { runCompare(*opts); });
}

}  // namespace gi::app
