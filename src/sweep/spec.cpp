#include "sweep/spec.h"

#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "gi/technique.h"
#include "util/error.h"
#include "util/file_io.h"
#include "util/hash.h"

namespace gi::sweep {

namespace {

using nlohmann::json;

constexpr size_t kMaxConfigurations = 100000;

std::string hex16(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

void checkKeys(const json& object, const std::string& where, const std::set<std::string>& allowed) {
  if (!object.is_object()) throw Error("sweep spec: " + where + " must be an object");
  for (auto& [key, value] : object.items())
    if (!allowed.count(key)) {
      std::string names;
      for (auto& a : allowed) names += (names.empty() ? "" : ", ") + a;
      throw Error("sweep spec: unknown key '" + key + "' in " + where + " (known: " + names + ")");
    }
}

// A non-empty list from `key` (a single value counts as a list of one); `fallback` if absent.
json listOf(const json& parent, const std::string& key, const json& fallback) {
  if (!parent.contains(key)) return fallback;
  json v = parent.at(key);
  if (!v.is_array()) v = json::array({v});
  if (v.empty()) throw Error("sweep spec: '" + key + "' must not be an empty list");
  return v;
}

// Parameter values are written as `gi bench --set` takes them: strings as they are, numbers and
// booleans in their JSON spelling.
std::string valueText(const json& v, const std::string& where) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number() || v.is_boolean()) return v.dump();
  throw Error("sweep spec: " + where + ": parameter values must be numbers, strings or booleans");
}

std::string stringOf(const json& v, const std::string& where) {
  if (!v.is_string()) throw Error("sweep spec: " + where + " must be a string");
  return v.get<std::string>();
}

int positiveInt(const json& parent, const std::string& key, int fallback, int hi) {
  if (!parent.contains(key)) return fallback;
  const json& v = parent.at(key);
  if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > hi)
    throw Error("sweep spec: '" + key + "' must be an integer in 0.." + std::to_string(hi));
  return v.get<int>();
}

std::pair<int, int> parseResolution(const json& v) {
  int w = 0, h = 0;
  if (v.is_string()) {
    char tail = 0;
    if (std::sscanf(v.get<std::string>().c_str(), "%dx%d%c", &w, &h, &tail) != 2) w = h = 0;
  } else if (v.is_array() && v.size() == 2 && v[0].is_number_integer() && v[1].is_number_integer()) {
    w = v[0].get<int>();
    h = v[1].get<int>();
  }
  if (w < 1 || h < 1 || w > 16384 || h > 16384)
    throw Error("sweep spec: resolution " + v.dump() + " must be \"WxH\" or [W, H] with sides in 1..16384");
  return {w, h};
}

struct SceneEntry {
  std::string path, label;
  json cameras;  // null = the spec's camera list
};

SceneEntry parseScene(const json& v) {
  SceneEntry s;
  if (v.is_string()) {
    s.path = v.get<std::string>();
  } else {
    checkKeys(v, "a scene", {"path", "label", "cameras"});
    s.path = v.contains("path") ? stringOf(v["path"], "scene 'path'") : "";
    if (v.contains("label")) s.label = stringOf(v["label"], "scene 'label'");
    if (v.contains("cameras")) s.cameras = listOf(v, "cameras", json());
  }
  if (s.label.empty()) s.label = s.path.empty() ? "cornell" : std::filesystem::path(s.path).stem().string();
  return s;
}

using Point = std::vector<std::pair<std::string, std::string>>;

void assign(Point& p, const std::string& name, const std::string& value) {
  for (auto& [n, v] : p)
    if (n == name) {
      v = value;
      return;
    }
  p.emplace_back(name, value);
}

// The parameter points of one technique entry: fixed `set`, times the cartesian product of the
// `grid` axes and the `zip` groups.
std::vector<Point> expandPoints(const json& entry, const std::string& technique, const Point& common) {
  const std::string where = "technique '" + technique + "'";
  Point fixed = common;
  if (entry.contains("set")) {
    if (!entry["set"].is_object()) throw Error("sweep spec: " + where + " 'set' must be an object name: value");
    for (auto& [name, v] : entry["set"].items()) assign(fixed, name, valueText(v, where + " set " + name));
  }
  // Axes: each a list of partial points; the grid's axes have one parameter, a zip group several.
  std::vector<std::vector<Point>> axes;
  if (entry.contains("grid")) {
    if (!entry["grid"].is_object()) throw Error("sweep spec: " + where + " 'grid' must be an object of lists");
    for (auto& [name, values] : entry["grid"].items()) {
      json list = values.is_array() ? values : json::array({values});
      if (list.empty()) throw Error("sweep spec: " + where + " grid '" + name + "' is an empty list");
      std::vector<Point> axis;
      for (auto& v : list) axis.push_back(Point{{name, valueText(v, where + " grid " + name)}});
      axes.push_back(std::move(axis));
    }
  }
  if (entry.contains("zip")) {
    json groups = entry["zip"].is_array() ? entry["zip"] : json::array({entry["zip"]});
    for (auto& group : groups) {
      if (!group.is_object() || group.empty())
        throw Error("sweep spec: " + where + " 'zip' must be an object of equally long lists (or a list of them)");
      size_t length = 0;
      std::string first;
      for (auto& [name, values] : group.items()) {
        if (!values.is_array() || values.empty())
          throw Error("sweep spec: " + where + " zip '" + name + "' must be a non-empty list");
        if (first.empty()) {
          first = name;
          length = values.size();
        } else if (values.size() != length) {
          throw Error("sweep spec: " + where + " zip lists differ in length: '" + first + "' has " + std::to_string(length) +
                      ", '" + name + "' has " + std::to_string(values.size()));
        }
      }
      std::vector<Point> axis(length);
      for (auto& [name, values] : group.items())
        for (size_t i = 0; i < length; ++i) axis[i].emplace_back(name, valueText(values[i], where + " zip " + name));
      axes.push_back(std::move(axis));
    }
  }
  std::vector<Point> points{fixed};
  for (auto& axis : axes) {
    std::vector<Point> next;
    for (auto& p : points)
      for (auto& partial : axis) {
        Point q = p;
        for (auto& [n, v] : partial) assign(q, n, v);
        next.push_back(std::move(q));
        if (next.size() > kMaxConfigurations)
          throw Error("sweep spec: " + where + " expands to more than " + std::to_string(kMaxConfigurations) + " points");
      }
    points = std::move(next);
  }
  return points;
}

}  // namespace

std::string Configuration::paramsText() const {
  std::string s;
  for (auto& [n, v] : params) s += (s.empty() ? "" : " ") + n + "=" + v;
  return s;
}

std::string Configuration::describe() const {
  std::string s = sceneLabel + (camera.empty() ? "" : "/" + camera) + " " + std::to_string(width) + "x" +
                  std::to_string(height) + " " + technique;
  if (!params.empty()) s += " " + paramsText();
  if (!device.empty()) s += " on " + device;
  return s;
}

nlohmann::json Configuration::toJson() const {
  json p = json::object();
  for (auto& [n, v] : params) p[n] = v;
  return {{"id", id},           {"index", index}, {"scene", scene},   {"scene_label", sceneLabel},
          {"camera", camera},   {"width", width}, {"height", height}, {"device", device},
          {"technique", technique}, {"params", p}, {"frames", frames}, {"warmup", warmup}};
}

Spec parseSpec(const json& j) {
  checkKeys(j, "the spec", {"name", "description", "scenes", "cameras", "resolutions", "devices", "techniques", "frames",
                            "warmup", "set", "reference", "timeout_s", "media"});
  Spec spec;
  spec.name = j.contains("name") ? stringOf(j["name"], "'name'") : "sweep";
  if (!j.contains("techniques")) throw Error("sweep spec: 'techniques' is required");
  const json scenes = listOf(j, "scenes", json::array({""}));
  const json cameras = listOf(j, "cameras", json::array({""}));
  const json resolutions = listOf(j, "resolutions", json());
  if (resolutions.is_null()) throw Error("sweep spec: 'resolutions' is required (\"WxH\" or [W, H] each)");
  const json devices = listOf(j, "devices", json::array({""}));
  const json techniques = listOf(j, "techniques", json());
  const int frames = positiveInt(j, "frames", 10, 100000), warmup = positiveInt(j, "warmup", 2, 10000);
  if (frames < 1) throw Error("sweep spec: 'frames' must be at least 1");
  if (j.contains("media")) spec.media = stringOf(j["media"], "'media'");
  if (j.contains("timeout_s")) {
    if (!j["timeout_s"].is_number() || j["timeout_s"].get<double>() < 0)
      throw Error("sweep spec: 'timeout_s' must be a number of seconds >= 0 (0 = no limit)");
    spec.timeoutSeconds = j["timeout_s"].get<double>();
  }
  if (j.contains("reference") && !j["reference"].is_null() && j["reference"] != false) {
    const json& r = j["reference"];
    checkKeys(r, "'reference'", {"spp", "max_bounces", "device", "spp_overrides"});
    spec.reference.enabled = true;
    spec.reference.spp = positiveInt(r, "spp", 256, 1 << 24);
    spec.reference.maxBounces = positiveInt(r, "max_bounces", 8, 1000);
    if (r.contains("device")) spec.reference.device = stringOf(r["device"], "reference 'device'");
    if (spec.reference.spp < 1) throw Error("sweep spec: reference 'spp' must be at least 1");
    if (r.contains("spp_overrides")) {
      if (!r["spp_overrides"].is_array()) throw Error("sweep spec: reference 'spp_overrides' must be a list");
      for (const json& o : r["spp_overrides"]) {
        if (!o.is_object()) throw Error("sweep spec: each reference spp override must be an object");
        checkKeys(o, "a reference spp override", {"scene", "resolution", "spp"});
        ReferenceSpec::SppOverride ov;
        if (o.contains("scene")) {
          ov.sceneLabel = stringOf(o["scene"], "spp override 'scene'");
          bool known = false;
          for (auto& sc : scenes) known = known || parseScene(sc).label == ov.sceneLabel;
          if (!known) throw Error("sweep spec: spp override scene '" + ov.sceneLabel + "' is none of the spec's scene labels");
        }
        if (o.contains("resolution")) std::tie(ov.width, ov.height) = parseResolution(o["resolution"]);
        if (ov.sceneLabel.empty() && ov.width == 0)
          throw Error("sweep spec: a reference spp override needs a 'scene' or a 'resolution'");
        ov.spp = positiveInt(o, "spp", 0, 1 << 24);
        if (ov.spp < 1) throw Error("sweep spec: a reference spp override needs 'spp' >= 1");
        spec.reference.sppOverrides.push_back(ov);
      }
    }
  }

  // Parameters every configuration gets (a technique entry's own set, grid and zip override them).
  Point common;
  if (j.contains("set")) {
    if (!j["set"].is_object()) throw Error("sweep spec: 'set' must be an object name: value");
    for (auto& [name, v] : j["set"].items()) common.emplace_back(name, valueText(v, "set " + name));
  }
  struct TechniqueEntry {
    std::string name;
    std::vector<Point> points;
  };
  std::vector<TechniqueEntry> entries;
  for (auto& t : techniques) {
    if (t == "all") {  // every technique this build has, with its defaults
      entries.push_back({"direct", {common}});
      for (const TechniqueInfo& info : techniqueRegistry()) entries.push_back({info.name, {common}});
      continue;
    }
    if (t.is_string()) {
      entries.push_back({t.get<std::string>(), {common}});
      continue;
    }
    checkKeys(t, "a technique entry", {"name", "set", "grid", "zip"});
    if (!t.contains("name")) throw Error("sweep spec: a technique entry needs a 'name'");
    std::string name = stringOf(t["name"], "technique 'name'");
    entries.push_back({name, expandPoints(t, name, common)});
  }

  std::set<std::string> ids;
  for (auto& sv : scenes) {
    SceneEntry scene = parseScene(sv);
    const json& cams = scene.cameras.is_null() ? cameras : scene.cameras;
    for (auto& cam : cams)
      for (auto& res : resolutions) {
        auto [w, h] = parseResolution(res);
        for (auto& dev : devices)
          for (auto& entry : entries)
            for (auto& point : entry.points) {
              Configuration c;
              c.index = int(spec.configurations.size());
              c.scene = scene.path;
              c.sceneLabel = scene.label;
              c.camera = cam.is_number_integer() ? cam.dump() : stringOf(cam, "a camera");
              c.width = w;
              c.height = h;
              c.device = stringOf(dev, "a device");
              c.technique = entry.name;
              c.params = point;
              c.frames = frames;
              c.warmup = warmup;
              // The id hashes what is rendered and how it is timed, with parameters sorted by name.
              json key = c.toJson();
              key.erase("index");
              key.erase("id");
              key.erase("scene_label");
              c.id = hex16(fnv1a64(key.dump()));  // nlohmann::json objects keep keys sorted
              if (!ids.insert(c.id).second)
                throw Error("sweep spec: configuration '" + c.describe() + "' appears twice");
              spec.configurations.push_back(std::move(c));
              if (spec.configurations.size() > kMaxConfigurations)
                throw Error("sweep spec: more than " + std::to_string(kMaxConfigurations) + " configurations");
            }
      }
  }
  return spec;
}

Spec loadSpec(const std::string& path) {
  json j;
  try {
    j = json::parse(readTextFile(path));
  } catch (const json::exception& e) {
    throw Error("sweep spec '" + path + "': " + e.what());
  }
  return parseSpec(j);
}

Shard parseShard(const std::string& text) {
  Shard s;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d/%d%c", &s.index, &s.count, &tail) != 2 || s.count < 1 || s.index < 0 ||
      s.index >= s.count)
    throw Error("--shard '" + text + "': expected i/n with 0 <= i < n (e.g. 0/4)");
  return s;
}

std::vector<Configuration> selectShard(const std::vector<Configuration>& all, Shard shard) {
  std::vector<Configuration> out;
  for (auto& c : all)
    if (c.index % shard.count == shard.index) out.push_back(c);
  return out;
}

int ReferenceSpec::sppFor(const Configuration& c) const {
  for (const SppOverride& o : sppOverrides)
    if ((o.sceneLabel.empty() || o.sceneLabel == c.sceneLabel) && (o.width == 0 || (o.width == c.width && o.height == c.height)))
      return o.spp;
  return spp;
}

std::string referenceKey(const Configuration& c, const ReferenceSpec& r) {
  json key = {{"scene", c.scene},   {"camera", c.camera}, {"width", c.width},
              {"height", c.height}, {"spp", r.sppFor(c)}, {"max_bounces", r.maxBounces}};
  return c.sceneLabel + "_" + std::to_string(c.width) + "x" + std::to_string(c.height) + "_" + hex16(fnv1a64(key.dump()));
}

}  // namespace gi::sweep
