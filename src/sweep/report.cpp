#include "sweep/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <OpenImageIO/strutil.h>
#include <nlohmann/json.hpp>

#include "image/image.h"
#include "sweep/results.h"
#include "util/error.h"
#include "util/file_io.h"

namespace gi::sweep {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// Distinct colours for passes (Tableau 10), assigned in first-seen order over the whole sweep.
const char* kPalette[] = {"#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f",
                          "#edc948", "#b07aa1", "#ff9da7", "#9c755f", "#bab0ac"};

// A "nice" axis step (1, 2 or 5 × 10^k) giving about `ticks` intervals up to `maxValue`.
double niceStep(double maxValue, int ticks) {
  if (!(maxValue > 0)) return 1;
  double raw = maxValue / ticks, mag = std::pow(10.0, std::floor(std::log10(raw)));
  double n = raw / mag;
  return (n <= 1 ? 1 : n <= 2 ? 2 : n <= 5 ? 5 : 10) * mag;
}

// A configuration's name in a group: its technique and the parameters that vary in the group.
std::string configurationLabel(const Json& row, const std::set<std::string>& varying) {
  std::string s = row["technique"].get<std::string>();
  for (auto& [n, v] : row["params"].items())
    if (varying.count(n)) s += " " + n + "=" + v.get<std::string>();
  return s;
}

// Parameters not set to the same value in every row of the group (absent counts as a value).
std::set<std::string> varyingParams(const std::vector<const Json*>& group, std::string& common) {
  std::map<std::string, std::set<std::string>> values;
  for (auto* r : group)
    for (auto& [n, v] : (*r)["params"].items()) values[n];
  for (auto* r : group)
    for (auto& [n, vs] : values) vs.insert((*r)["params"].contains(n) ? (*r)["params"][n].get<std::string>() : "(default)");
  std::set<std::string> varying;
  common.clear();
  for (auto& [n, vs] : values) {
    if (vs.size() > 1) varying.insert(n);
    else common += (common.empty() ? "" : " ") + n + "=" + *vs.begin();
  }
  return varying;
}

double numberOf(const Json& row, const char* key) { return row.contains(key) ? row[key].get<double>() : 0.0; }

// Horizontal bar chart: one bar per row label; `segments` per bar are (colour key, value, tooltip);
// an optional whisker (lo, hi) per bar.
struct Bar {
  std::string label;
  std::vector<std::tuple<std::string, double, std::string>> segments;
  double whiskerLo = NAN, whiskerHi = NAN;
};

std::string barChart(const std::vector<Bar>& bars, const std::map<std::string, std::string>& colours,
                     const std::string& axisLabel, int width) {
  const int labelW = 260, rowH = 20, top = 8, axisH = 34, plotW = width - labelW - 20;
  double maxV = 0;
  for (auto& b : bars) {
    double sum = 0;
    for (auto& s : b.segments) sum += std::get<1>(s);
    maxV = std::max({maxV, sum, std::isnan(b.whiskerHi) ? 0.0 : b.whiskerHi});
  }
  double step = niceStep(maxV, 5), axisMax = std::max(step, std::ceil(maxV / step) * step);
  const int height = top + rowH * int(bars.size()) + axisH;
  auto x = [&](double v) { return labelW + v / axisMax * plotW; };
  std::string svg = "<svg xmlns='http://www.w3.org/2000/svg' width='" + std::to_string(width) + "' height='" +
                    std::to_string(height) + "' class='chart'>";
  for (double t = 0; t <= axisMax + step * 0.5; t += step) {
    svg += "<line x1='" + fmt("%.1f", x(t)) + "' x2='" + fmt("%.1f", x(t)) + "' y1='" + std::to_string(top) + "' y2='" +
           std::to_string(height - axisH + 4) + "' class='grid'/>";
    svg += "<text x='" + fmt("%.1f", x(t)) + "' y='" + std::to_string(height - axisH + 17) + "' class='tick'>" +
           fmt("%g", t) + "</text>";
  }
  svg += "<text x='" + fmt("%.1f", labelW + plotW / 2.0) + "' y='" + std::to_string(height - 3) + "' class='axis'>" +
         escape(axisLabel) + "</text>";
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& b = bars[i];
    int y = top + int(i) * rowH;
    // Long labels are cut to fit the margin; the full one is the tooltip.
    std::string shown = b.label.size() > 42 ? b.label.substr(0, 41) + "…" : b.label;
    svg += "<text x='" + std::to_string(labelW - 6) + "' y='" + std::to_string(y + 14) + "' class='label'>" +
           escape(shown) + "<title>" + escape(b.label) + "</title></text>";
    double at = 0;
    for (auto& [key, v, tip] : b.segments) {
      auto c = colours.find(key);
      svg += "<rect x='" + fmt("%.1f", x(at)) + "' y='" + std::to_string(y + 3) + "' width='" +
             fmt("%.1f", std::max(0.0, x(at + v) - x(at))) + "' height='" + std::to_string(rowH - 6) + "' fill='" +
             (c == colours.end() ? "#888" : c->second) + "'><title>" + escape(tip) + "</title></rect>";
      at += v;
    }
    if (!std::isnan(b.whiskerLo)) {
      std::string yMid = std::to_string(y + rowH / 2);
      svg += "<line x1='" + fmt("%.1f", x(b.whiskerLo)) + "' x2='" + fmt("%.1f", x(b.whiskerHi)) + "' y1='" + yMid +
             "' y2='" + yMid + "' class='whisker'/>";
      for (double w : {b.whiskerLo, b.whiskerHi})
        svg += "<line x1='" + fmt("%.1f", x(w)) + "' x2='" + fmt("%.1f", x(w)) + "' y1='" + std::to_string(y + 5) +
               "' y2='" + std::to_string(y + rowH - 5) + "' class='whisker'/>";
    }
  }
  return svg + "</svg>";
}

struct Point {
  double time, error;
  std::string label;
  bool pareto = false;
};

// Marks the points no other point beats in both time and error (ties in both count as equal).
void markPareto(std::vector<Point>& pts) {
  for (auto& p : pts) {
    p.pareto = true;
    for (auto& q : pts)
      if (&q != &p && q.time <= p.time && q.error <= p.error && (q.time < p.time || q.error < p.error)) {
        p.pareto = false;
        break;
      }
  }
}

std::string scatter(std::vector<Point> pts, const std::string& errorLabel) {
  const int width = 760, height = 380, left = 70, right = 140, top = 14, bottom = 46;
  const int plotW = width - left - right, plotH = height - top - bottom;
  double maxT = 0, maxE = 0;
  for (auto& p : pts) {
    maxT = std::max(maxT, p.time);
    maxE = std::max(maxE, p.error);
  }
  double stepT = niceStep(maxT, 5), stepE = niceStep(maxE, 5);
  double axT = std::max(stepT, std::ceil(maxT / stepT) * stepT), axE = std::max(stepE, std::ceil(maxE / stepE) * stepE);
  auto X = [&](double t) { return left + t / axT * plotW; };
  auto Y = [&](double e) { return top + plotH - e / axE * plotH; };
  std::string svg = "<svg xmlns='http://www.w3.org/2000/svg' width='" + std::to_string(width) + "' height='" +
                    std::to_string(height) + "' class='chart'>";
  for (double t = 0; t <= axT + stepT * 0.5; t += stepT)
    svg += "<line x1='" + fmt("%.1f", X(t)) + "' x2='" + fmt("%.1f", X(t)) + "' y1='" + std::to_string(top) + "' y2='" +
           std::to_string(top + plotH) + "' class='grid'/><text x='" + fmt("%.1f", X(t)) + "' y='" +
           std::to_string(top + plotH + 16) + "' class='tick'>" + fmt("%g", t) + "</text>";
  for (double e = 0; e <= axE + stepE * 0.5; e += stepE)
    svg += "<line x1='" + std::to_string(left) + "' x2='" + std::to_string(left + plotW) + "' y1='" + fmt("%.1f", Y(e)) +
           "' y2='" + fmt("%.1f", Y(e)) + "' class='grid'/><text x='" + std::to_string(left - 6) + "' y='" +
           fmt("%.1f", Y(e) + 4) + "' class='label'>" + fmt("%g", e) + "</text>";
  svg += "<text x='" + std::to_string(left + plotW / 2) + "' y='" + std::to_string(height - 6) +
         "' class='axis'>device time per frame, ms (median)</text>";
  svg += "<text transform='translate(14," + std::to_string(top + plotH / 2) + ") rotate(-90)' class='axis'>" +
         escape(errorLabel) + "</text>";
  markPareto(pts);
  std::vector<Point> front;
  for (auto& p : pts)
    if (p.pareto) front.push_back(p);
  std::sort(front.begin(), front.end(), [](auto& a, auto& b) { return a.time < b.time; });
  if (front.size() > 1) {
    std::string path;
    for (size_t i = 0; i < front.size(); ++i) {
      // A staircase: from each front point, right to the next point's time, then down to its error.
      path += (i ? "L" : "M") + fmt("%.1f", X(front[i].time)) + "," + fmt("%.1f", Y(front[i].error));
      if (i + 1 < front.size()) path += "L" + fmt("%.1f", X(front[i + 1].time)) + "," + fmt("%.1f", Y(front[i].error));
    }
    svg += "<path d='" + path + "' class='front'/>";
  }
  for (auto& p : pts) {
    std::string tip = p.label + ": " + fmt("%.3f ms", p.time) + ", " + errorLabel + " " + fmt("%.4f", p.error) +
                      (p.pareto ? " (Pareto front)" : "");
    svg += "<circle cx='" + fmt("%.1f", X(p.time)) + "' cy='" + fmt("%.1f", Y(p.error)) + "' r='" +
           (p.pareto ? "6" : "4") + "' class='" + (p.pareto ? "pt front-pt" : "pt") + "'><title>" + escape(tip) +
           "</title></circle>";
    svg += "<text x='" + fmt("%.1f", X(p.time) + 8) + "' y='" + fmt("%.1f", Y(p.error) - 6) + "' class='ptlabel'>" +
           escape(p.label) + "</text>";
  }
  return svg + "</svg>";
}

std::string dataUri(const fs::path& png) {
  if (!fs::exists(png)) return "";
  std::ifstream in(png, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return "data:image/png;base64," + OIIO::Strutil::base64_encode(bytes);
}

std::string figure(const std::string& uri, const std::string& caption, int width) {
  std::string img = uri.empty() ? "<div class='missing'>no image</div>"
                                : "<img src='" + uri + "' width='" + std::to_string(width) + "' alt='" + escape(caption) + "'>";
  return "<figure>" + img + "<figcaption>" + caption + "</figcaption></figure>";
}

// The display PNG of a reference EXR (same display transform as the frames), made once.
std::string referencePng(const fs::path& dir, const std::string& exrRelative, double exposure) {
  fs::path exr = dir / exrRelative, png = exr;
  png.replace_extension(".png");
  if (!fs::exists(png) && fs::exists(exr)) writeImage(png, displayTransform(readImage(exr), float(exposure)));
  return dataUri(png);
}

const char* kStyle = R"(
body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;background:#fff}
h1{font-size:22px}h2{font-size:18px;margin-top:32px;border-bottom:1px solid #ccc}h3{font-size:15px}
table{border-collapse:collapse;font-size:12px;margin:8px 0}td,th{border:1px solid #ddd;padding:3px 6px;text-align:right}
th{background:#f3f3f3}td.l,th.l{text-align:left}tr.failed td{background:#fde8e8}
.chart{display:block;margin:6px 0}.chart .grid{stroke:#e5e5e5}.chart .tick{font-size:11px;text-anchor:middle;fill:#555}
.chart .label{font-size:11px;text-anchor:end;fill:#333}.chart .axis{font-size:12px;text-anchor:middle;fill:#333}
.chart .whisker{stroke:#222;stroke-width:1.2}.chart .pt{fill:#4e79a7;opacity:.8}.chart .front-pt{fill:#e15759;stroke:#222}
.chart .front{fill:none;stroke:#e15759;stroke-width:2;stroke-dasharray:5 3}.chart .ptlabel{font-size:10px;fill:#444}
.legend span{display:inline-block;margin-right:12px;font-size:12px}.legend i{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:-2px}
.grid-images{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0;font-size:11px;max-width:260px}figure img{display:block;image-rendering:pixelated;border:1px solid #ccc;margin-bottom:2px}
.pass-charts{display:flex;flex-wrap:wrap;gap:16px}.pass-charts div{font-size:12px}.missing{width:256px;height:64px;background:#eee}
.meta{color:#555;font-size:12px}
)";

}  // namespace

std::string writeReport(const std::string& dirText) {
  const fs::path dir = dirText;
  const Json results = loadResults(dirText);
  const Json& rows = results["rows"];

  // Colours per pass, consistent over the page.
  std::map<std::string, std::string> colours;
  std::vector<std::string> passOrder;
  for (auto& r : rows)
    if (r.contains("passes_ms"))
      for (auto& [p, v] : r["passes_ms"].items())
        if (!colours.count(p)) {
          colours[p] = kPalette[passOrder.size() % std::size(kPalette)];
          passOrder.push_back(p);
        }

  // Groups: configurations that share scene, camera, resolution and device, in spec order.
  std::vector<std::string> groupOrder;
  std::map<std::string, std::vector<const Json*>> groups;
  for (auto& r : rows) {
    std::string key = r["scene"].get<std::string>() + (r["camera"].get<std::string>().empty() ? "" : " / camera " + r["camera"].get<std::string>()) +
                      " — " + std::to_string(r["width"].get<int>()) + "×" + std::to_string(r["height"].get<int>()) +
                      (r["device"].get<std::string>().empty() ? "" : " — device " + r["device"].get<std::string>());
    if (!groups.count(key)) groupOrder.push_back(key);
    groups[key].push_back(&r);
  }

  std::set<std::string> devices, revisions;
  for (auto& r : rows) {
    if (r.contains("device_name")) devices.insert(r["device_name"].get<std::string>() + " (driver " + r["driver"].get<std::string>() + ")");
    if (r.contains("git_revision")) revisions.insert(r["git_revision"].get<std::string>());
  }
  auto joined = [](const std::set<std::string>& s) {
    std::string o;
    for (auto& v : s) o += (o.empty() ? "" : "; ") + v;
    return o.empty() ? std::string("—") : o;
  };
  std::time_t now = std::time(nullptr);
  char when[64];
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));

  std::string h = "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>" +
                  escape(results["sweep"].get<std::string>()) + " — gi sweep report</title><style>" + kStyle +
                  "</style></head><body>";
  h += "<h1>Sweep “" + escape(results["sweep"].get<std::string>()) + "”</h1>";
  h += "<p class='meta'>" + std::to_string(results["finished"].get<int>()) + " of " +
       std::to_string(results["total"].get<int>()) + " configurations finished, " +
       std::to_string(results["failed"].get<int>()) + " failed. Devices: " + escape(joined(devices)) +
       ". gi revision: " + escape(joined(revisions)) + ". Generated " + when +
       ". Times are medians over the timed frames of OpenCL profiling events (gi bench); "
       "quality is LDR-FLIP of the final frame against the path-traced reference (lower is better).</p>";
  h += "<div class='legend'>";
  for (auto& p : passOrder) h += "<span><i style='background:" + colours[p] + "'></i>" + escape(p) + "</span>";
  h += "</div>";

  for (auto& key : groupOrder) {
    const auto& g = groups[key];
    h += "<h2>" + escape(key) + "</h2>";
    std::string common;
    const std::set<std::string> varying = varyingParams(g, common);
    auto label = [&](const Json& row) { return configurationLabel(row, varying); };
    if (!common.empty()) h += "<p class='meta'>Parameters set in every configuration below: " + escape(common) + "</p>";
    std::vector<Bar> stacked;
    for (auto* r : g) {
      if ((*r)["status"] != "ok") continue;
      Bar b{label(*r), {}};
      for (auto& p : (*r)["passes"])
        b.segments.emplace_back(p["name"].get<std::string>(), p["median_ms"].get<double>(),
                                p["name"].get<std::string>() + ": " + fmt("%.3f ms", p["median_ms"].get<double>()));
      stacked.push_back(std::move(b));
    }
    if (!stacked.empty()) {
      h += "<h3>Device time per frame by pass</h3>" + barChart(stacked, colours, "ms (median over frames)", 900);
      h += "<h3>Each pass: median, whisker min..max over frames</h3><div class='pass-charts'>";
      for (auto& pass : passOrder) {
        std::vector<Bar> bars;
        for (auto* r : g) {
          if ((*r)["status"] != "ok") continue;
          for (auto& p : (*r)["passes"])
            if (p["name"] == pass) {
              Bar b{label(*r), {{pass, p["median_ms"].get<double>(), pass + ": median " + fmt("%.3f ms", p["median_ms"].get<double>()) +
                                                                          ", min " + fmt("%.3f", p["min_ms"].get<double>()) +
                                                                          ", max " + fmt("%.3f", p["max_ms"].get<double>())}}};
              b.whiskerLo = p["min_ms"].get<double>();
              b.whiskerHi = p["max_ms"].get<double>();
              bars.push_back(std::move(b));
            }
        }
        if (!bars.empty()) h += "<div><b>" + escape(pass) + "</b>" + barChart(bars, colours, "ms", 520) + "</div>";
      }
      h += "</div>";
    }

    std::vector<Point> pts;
    for (auto* r : g)
      if ((*r)["status"] == "ok" && (*r)["quality"].is_object() && (*r)["quality"]["flip"].is_number())
        pts.push_back({numberOf(*r, "device_total_ms"), (*r)["quality"]["flip"].get<double>(), label(*r)});
    if (!pts.empty()) h += "<h3>Quality against time (Pareto front in red)</h3>" + scatter(pts, "LDR-FLIP");

    // Images: the reference, then every configuration's frame over its heat map.
    const Json* withReference = nullptr;
    for (auto* r : g)
      if (r->contains("reference") && !(*r)["reference"].get<std::string>().empty()) withReference = r;
    int thumb = std::clamp(g.front()->at("width").get<int>(), 128, 256);
    h += "<h3>Images</h3><div class='grid-images'>";
    if (withReference)
      h += figure(referencePng(dir, (*withReference)["reference"].get<std::string>(), (*withReference)["exposure"].get<double>()),
                  "<b>reference</b> (path traced)", thumb);
    for (auto* r : g) {
      if ((*r)["status"] != "ok") continue;
      std::string cap = "<b>" + escape(label(*r)) + "</b><br>" + fmt("%.3f ms", numberOf(*r, "device_total_ms"));
      if ((*r)["quality"].is_object()) {
        const Json& q = (*r)["quality"];
        if (q["flip"].is_number()) cap += ", FLIP " + fmt("%.4f", q["flip"].get<double>());
        if (q["ssim"].is_number()) cap += ", SSIM " + fmt("%.4f", q["ssim"].get<double>());
      }
      std::string img = figure(dataUri(dir / (*r)["image"].get<std::string>()), cap, thumb);
      if (r->contains("heatmap") && !(*r)["heatmap"].get<std::string>().empty())
        img = "<div>" + img + figure(dataUri(dir / (*r)["heatmap"].get<std::string>()), "FLIP error (magma, 0..1)", thumb) + "</div>";
      h += img;
    }
    h += "</div>";
  }

  // The table of every configuration.
  h += "<h2>All configurations</h2><table><tr><th class='l'>status</th><th class='l'>scene</th><th>size</th>"
       "<th class='l'>device</th><th class='l'>technique</th><th class='l'>parameters</th><th>frame wall ms</th>"
       "<th>device ms</th>";
  for (auto& p : passOrder) h += "<th>" + escape(p) + " ms</th>";
  h += "<th>device MiB</th><th>FLIP</th><th>SSIM</th><th>grade</th><th>grade255</th><th>relMSE</th><th class='l'>message</th></tr>";
  for (auto& r : rows) {
    bool ok = r["status"] == "ok";
    std::string params;
    for (auto& [n, v] : r["params"].items()) params += (params.empty() ? "" : " ") + n + "=" + v.get<std::string>();
    h += std::string("<tr") + (ok ? "" : " class='failed'") + "><td class='l'>" + escape(r["status"].get<std::string>()) +
         "</td><td class='l'>" + escape(r["scene"].get<std::string>()) + "</td><td>" + std::to_string(r["width"].get<int>()) +
         "×" + std::to_string(r["height"].get<int>()) + "</td><td class='l'>" +
         escape(r.value("device_name", r["device"].get<std::string>())) + "</td><td class='l'>" +
         escape(r["technique"].get<std::string>()) + "</td><td class='l'>" + escape(params) + "</td>";
    auto cell = [&](bool has, double v, const char* f) { h += "<td>" + (has ? fmt(f, v) : std::string()) + "</td>"; };
    cell(ok, numberOf(r, "frame_wall_ms"), "%.3f");
    cell(ok, numberOf(r, "device_total_ms"), "%.3f");
    for (auto& p : passOrder) {
      bool has = ok && r["passes_ms"].contains(p);
      cell(has, has ? r["passes_ms"][p].get<double>() : 0, "%.3f");
    }
    cell(ok, ok ? r["device_bytes"].get<double>() / (1024.0 * 1024.0) : 0, "%.1f");
    for (const char* m : {"flip", "ssim", "grade", "grade255", "relmse"}) {
      bool has = ok && r["quality"].is_object() && r["quality"][m].is_number();
      cell(has, has ? r["quality"][m].get<double>() : 0, "%.4g");
    }
    std::string msg = r["message"].get<std::string>();
    if (r.contains("quality_message")) msg += (msg.empty() ? "" : "; ") + r["quality_message"].get<std::string>();
    h += "<td class='l'>" + escape(msg) + "</td></tr>";
  }
  h += "</table></body></html>\n";

  fs::path out = dir / "report.html";
  writeAtomically(out, [&](const fs::path& tmp) {
    std::ofstream o(tmp, std::ios::binary);
    o << h;
    o.close();
    if (!o) throw Error("cannot write " + out.string());
  });
  return out.string();
}

}  // namespace gi::sweep
