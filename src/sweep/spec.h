// A sweep specification (docs/SWEEPS.md) and its expansion into configurations: every
// combination of scene × camera × resolution × device × technique entry × parameter point.
// A technique entry's parameter points are the cartesian product of its `grid` axes and of its
// `zip` groups (the lists of one zip group advance together), each with the spec's and the entry's
// fixed `set`. The technique "all" stands for direct and every technique of the registry.
//
// Every configuration has a stable id, a hash of what it renders, so that a resumed, sharded or
// merged sweep recognises finished work regardless of the order of the spec's lists.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace gi::sweep {

struct Configuration {
  int index = 0;            // position in the expansion (the order in which a sweep runs)
  std::string id;           // 16 hex digits, a hash of the fields below
  std::string scene;        // as given to `gi bench` ("" = built-in Cornell box)
  std::string sceneLabel;   // short name for tables ("cornell", "sponza", ...)
  std::string camera;       // name or index ("" = the scene's default)
  int width = 0, height = 0;
  std::string device;       // as given to --device ("" = the default device)
  std::string technique;
  std::vector<std::pair<std::string, std::string>> params;  // --set name=value, in spec order
  int frames = 10, warmup = 2;

  std::string paramsText() const;  // "name=value name=value"
  std::string describe() const;    // one line for progress output
  nlohmann::json toJson() const;
};

// How a configuration's reference image is made (`gi reference`), or none.
struct ReferenceSpec {
  bool enabled = false;
  int spp = 256, maxBounces = 8;
  std::string device;  // "" = the default device
  // "spp_overrides": [{"scene": LABEL, "resolution": "WxH", "spp": N}, ...] — a different sample
  // count for the references of one scene and/or resolution (e.g. a 1280×720 Sponza that would
  // take hours at the spec's spp). The first override whose given fields all match wins.
  struct SppOverride {
    std::string sceneLabel;  // "" = any scene
    int width = 0, height = 0;  // 0 = any resolution
    int spp = 0;
  };
  std::vector<SppOverride> sppOverrides;
  int sppFor(const Configuration& c) const;
};

struct Spec {
  std::string name;
  std::vector<Configuration> configurations;
  ReferenceSpec reference;
  double timeoutSeconds = 0;  // per configuration; 0 = none
  std::string media;          // media folder passed to every child ("" = the default search)
};

// Parses and expands a spec. Throws gi::Error naming the offending key for anything malformed:
// unknown keys, empty lists, zip lists of different lengths, bad resolutions, duplicate
// configurations, or more than 100 000 configurations.
Spec parseSpec(const nlohmann::json& spec);
Spec loadSpec(const std::string& path);

// "i/n" with 0 <= i < n: the configurations whose index is i modulo n (round-robin, so that
// each shard gets a similar mix of cheap and expensive configurations).
struct Shard {
  int index = 0, count = 1;
};
Shard parseShard(const std::string& text);  // throws gi::Error on anything but "i/n"
std::vector<Configuration> selectShard(const std::vector<Configuration>& all, Shard shard);

// The key of the reference image a configuration is compared with (scene, camera, size, spp...).
std::string referenceKey(const Configuration& c, const ReferenceSpec& r);

}  // namespace gi::sweep
