#include "sweep/results.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include "sweep/spec.h"
#include "util/error.h"
#include "util/file_io.h"

namespace gi::sweep {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

json readJson(const fs::path& path) {
  try {
    return json::parse(readTextFile(path));
  } catch (const json::exception& e) {
    throw Error(path.string() + ": " + e.what());
  }
}

// One table row from a configuration and its result.json.
OrderedJson flatten(const Configuration& c, const json& result) {
  OrderedJson row;
  row["id"] = c.id;
  row["index"] = c.index;
  row["status"] = result.value("status", "failed");
  row["message"] = result.value("message", "");
  row["scene"] = c.sceneLabel;
  row["scene_path"] = c.scene;
  row["camera"] = c.camera;
  row["width"] = c.width;
  row["height"] = c.height;
  row["device"] = c.device;
  row["technique"] = c.technique;
  row["params"] = OrderedJson::object();
  for (auto& [n, v] : c.params) row["params"][n] = v;
  row["frames"] = c.frames;
  row["warmup"] = c.warmup;
  row["seconds"] = result.value("seconds", 0.0);
  row["log"] = result.value("log", "");
  if (result.contains("quality_message")) row["quality_message"] = result["quality_message"];
  if (!result.contains("bench")) return row;
  const json& b = result["bench"];
  row["device_name"] = b["device"].value("name", "");
  row["driver"] = b["device"].value("driver", "");
  row["git_revision"] = b.value("git_revision", "");
  row["frame_wall_ms"] = b["frame_wall_ms"]["median_ms"];
  row["device_total_ms"] = b["device_total_ms"]["median_ms"];
  row["passes_ms"] = OrderedJson::object();
  row["passes"] = OrderedJson::array();
  for (auto& p : b["passes"]) {
    row["passes_ms"][p["name"].get<std::string>()] = p["median_ms"];
    row["passes"].push_back(OrderedJson{{"name", p["name"]}, {"median_ms", p["median_ms"]},
                                        {"min_ms", p["min_ms"]}, {"max_ms", p["max_ms"]}});
  }
  row["kernels_ms"] = OrderedJson::object();
  for (auto& k : b["kernels"]) row["kernels_ms"][k["name"].get<std::string>()] = k["median_ms"];
  row["device_bytes"] = b.value("device_bytes", uint64_t(0));
  row["host_peak_rss_bytes"] = b.value("host_peak_rss_bytes", uint64_t(0));
  row["exposure"] = b.value("exposure", 1.0);
  row["image"] = b.value("image", "");
  if (b.contains("statistics")) row["statistics"] = b["statistics"];
  if (b.contains("quality")) {
    const json& q = b["quality"];
    row["quality"] = OrderedJson::object();
    for (const char* m : {"ssim", "grade", "grade255", "flip", "relmse", "psnr_db"}) row["quality"][m] = q.contains(m) ? q[m] : json();
    row["heatmap"] = q.value("heatmap", "");
    row["reference"] = q.value("reference", "");
    if (q.contains("reference_spp")) row["reference_spp"] = q["reference_spp"];
  } else {
    row["quality"] = nullptr;
  }
  return row;
}

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string csvValue(const OrderedJson& v) {
  if (v.is_null()) return "";
  if (v.is_string()) return csvField(v.get<std::string>());
  if (v.is_number_float()) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
    return buf;
  }
  return csvField(v.dump());
}

void writeText(const fs::path& path, const std::string& text) {
  writeAtomically(path, [&](const fs::path& tmp) {
    std::ofstream o(tmp, std::ios::binary);
    o << text;
    o.close();
    if (!o) throw Error("cannot write " + path.string());
  });
}

}  // namespace

OrderedJson loadResults(const std::string& dir) {
  Spec spec = parseSpec(readJson(fs::path(dir) / "spec.json"));
  OrderedJson doc, rows = OrderedJson::array();
  int failed = 0;
  for (auto& c : spec.configurations) {
    fs::path file = fs::path(dir) / "runs" / c.id / "result.json";
    if (!fs::exists(file)) continue;
    rows.push_back(flatten(c, readJson(file)));
    if (rows.back()["status"] != "ok") ++failed;
  }
  doc["sweep"] = spec.name;
  doc["total"] = spec.configurations.size();
  doc["finished"] = rows.size();
  doc["failed"] = failed;
  doc["rows"] = rows;
  return doc;
}

void writeResultTables(const std::string& dir) {
  const OrderedJson doc = loadResults(dir);
  const OrderedJson& rows = doc["rows"];
  writeText(fs::path(dir) / "results.json", doc.dump(2) + "\n");

  // CSV: fixed columns, then the union of parameters, passes and kernels in first-seen order.
  std::vector<std::string> params, passes, kernels, statistics;
  auto collect = [](std::vector<std::string>& names, const OrderedJson& object) {
    if (!object.is_object()) return;
    for (auto& [n, v] : object.items())
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  };
  for (auto& r : rows) {
    collect(params, r["params"]);
    if (r.contains("passes_ms")) collect(passes, r["passes_ms"]);
    if (r.contains("kernels_ms")) collect(kernels, r["kernels_ms"]);
    if (r.contains("statistics")) collect(statistics, r["statistics"]);
  }
  const std::vector<std::string> fixed = {"id", "status", "message", "scene", "camera", "width", "height", "device",
                                          "technique", "frames", "warmup", "device_name", "driver", "git_revision",
                                          "frame_wall_ms", "device_total_ms", "device_bytes", "host_peak_rss_bytes"};
  const std::vector<std::string> quality = {"ssim", "grade", "grade255", "flip", "relmse", "psnr_db"};
  std::string csv;
  auto header = [&](const std::string& h) { csv += (csv.empty() || csv.back() == '\n' ? "" : ",") + csvField(h); };
  for (auto& f : fixed) header(f);
  for (auto& p : params) header("param:" + p);
  for (auto& p : passes) header("pass:" + p + " ms");
  for (auto& k : kernels) header("kernel:" + k + " ms");
  for (auto& st : statistics) header("statistic:" + st);
  for (auto& q : quality) header(q);
  for (const char* f : {"image", "heatmap", "reference", "reference_spp"}) header(f);
  csv += "\n";
  for (auto& r : rows) {
    std::vector<std::string> cells;
    auto at = [&](const OrderedJson& object, const std::string& key) {
      cells.push_back(object.is_object() && object.contains(key) ? csvValue(object[key]) : "");
    };
    for (auto& f : fixed) at(r, f);
    for (auto& p : params) at(r["params"], p);
    for (auto& p : passes) at(r.contains("passes_ms") ? r["passes_ms"] : OrderedJson(), p);
    for (auto& k : kernels) at(r.contains("kernels_ms") ? r["kernels_ms"] : OrderedJson(), k);
    for (auto& st : statistics) at(r.contains("statistics") ? r["statistics"] : OrderedJson(), st);
    for (auto& q : quality) at(r.contains("quality") ? r["quality"] : OrderedJson(), q);
    for (const char* f : {"image", "heatmap", "reference", "reference_spp"}) at(r, f);
    for (size_t i = 0; i < cells.size(); ++i) csv += (i ? "," : "") + cells[i];
    csv += "\n";
  }
  writeText(fs::path(dir) / "results.csv", csv);
}

}  // namespace gi::sweep
