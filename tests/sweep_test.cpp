// `gi sweep` machinery: spec expansion (cartesian grids, zipped lists, "all"), errors, sharding;
// and, through the real binary on tiny configurations (built-in Cornell box, 32x32): a failing
// configuration recorded while the sweep goes on, resume without redoing finished work, and a
// 2-shard run merged equal to the unsharded run (same configurations, statuses and image bytes).
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "gi/technique.h"
#include "render/renderer.h"
#include "sweep/spec.h"
#include "test_support.h"
#include "util/error.h"

using namespace gi;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string paramOf(const sweep::Configuration& c, const std::string& name) {
  for (auto& [n, v] : c.params)
    if (n == name) return v;
  return "";
}

void expectSpecError(const json& spec, const std::string& mustMention) {
  try {
    sweep::parseSpec(spec);
    ADD_FAILURE() << "accepted: " << spec.dump();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(mustMention), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(SweepSpec, ExpandsCartesianGridsAndZippedLists) {
  json spec = json::parse(R"({
    "name": "t", "scenes": ["", {"path": "scenes/sponza.json", "cameras": ["0", "1"]}],
    "resolutions": ["64x48", [32, 32]], "devices": ["cpu"], "frames": 3, "warmup": 1,
    "techniques": ["direct",
      {"name": "vpl", "set": {"vpl.d_min": 0.01}, "grid": {"vpl.count": [16, 64, 256]},
       "zip": {"shadow.resolution": [256, 512], "rsm.resolution": [64, 128]}}]})");
  sweep::Spec s = sweep::parseSpec(spec);
  // (1 camera + 2 cameras) x 2 resolutions x 1 device x (1 + 3 x 2) points.
  ASSERT_EQ(s.configurations.size(), 3u * 2u * 7u);
  std::set<std::string> ids;
  std::set<std::string> vplPoints;
  for (auto& c : s.configurations) {
    ids.insert(c.id);
    EXPECT_EQ(c.frames, 3);
    EXPECT_EQ(c.device, "cpu");
    if (c.technique == "vpl" && c.sceneLabel == "cornell" && c.width == 64) {
      EXPECT_EQ(paramOf(c, "vpl.d_min"), "0.01");
      // Zipped: the shadow and RSM resolutions advance together, never crossed.
      std::string sr = paramOf(c, "shadow.resolution"), rr = paramOf(c, "rsm.resolution");
      EXPECT_TRUE((sr == "256" && rr == "64") || (sr == "512" && rr == "128")) << c.describe();
      vplPoints.insert(paramOf(c, "vpl.count") + "/" + sr);
    }
  }
  EXPECT_EQ(ids.size(), s.configurations.size());
  EXPECT_EQ(vplPoints, (std::set<std::string>{"16/256", "16/512", "64/256", "64/512", "256/256", "256/512"}));
  EXPECT_EQ(s.configurations[0].sceneLabel, "cornell");
  EXPECT_EQ(s.configurations.back().sceneLabel, "sponza");
  EXPECT_EQ(s.configurations.back().camera, "1");
  for (size_t i = 0; i < s.configurations.size(); ++i) EXPECT_EQ(s.configurations[i].index, int(i));

  // Ids name what is rendered: the order of keys and of the spec's lists does not change them.
  json reordered = spec;
  reordered["resolutions"] = json::parse(R"([[32, 32], "64x48"])");
  reordered["techniques"][1]["zip"] = json::parse(R"({"rsm.resolution": [64, 128], "shadow.resolution": [256, 512]})");
  std::set<std::string> ids2;
  for (auto& c : sweep::parseSpec(reordered).configurations) ids2.insert(c.id);
  EXPECT_EQ(ids, ids2);
}

TEST(SweepSpec, AllMeansEveryRegisteredTechnique) {
  sweep::Spec s = sweep::parseSpec(json::parse(R"({"resolutions": ["16x16"], "techniques": ["all"]})"));
  ASSERT_EQ(s.configurations.size(), techniqueRegistry().size() + 1);
  EXPECT_EQ(s.configurations[0].technique, "direct");
  for (size_t i = 0; i < techniqueRegistry().size(); ++i)
    EXPECT_EQ(s.configurations[i + 1].technique, techniqueRegistry()[i].name);
}

TEST(SweepSpec, RejectsMalformedSpecsNamingTheProblem) {
  expectSpecError(json::parse(R"({"resolutions": ["8x8"]})"), "techniques");
  expectSpecError(json::parse(R"({"techniques": ["direct"]})"), "resolutions");
  expectSpecError(json::parse(R"({"resolutions": ["8x0"], "techniques": ["direct"]})"), "resolution");
  expectSpecError(json::parse(R"({"resolutions": ["8x8"], "techniques": ["direct"], "colour": 1})"), "colour");
  expectSpecError(json::parse(R"({"resolutions": ["8x8"], "techniques": [{"name": "vpl", "zip": {"a": [1, 2], "b": [1]}}]})"),
                  "'a' has 2, 'b' has 1");
  expectSpecError(json::parse(R"({"resolutions": ["8x8"], "techniques": [{"name": "vpl", "grid": {"vpl.count": []}}]})"),
                  "vpl.count");
  expectSpecError(json::parse(R"({"resolutions": ["8x8"], "techniques": ["direct", "direct"]})"), "appears twice");
  expectSpecError(json::parse(R"({"resolutions": ["8x8"], "techniques": ["direct"], "frames": 0})"), "frames");
}

// A reference spp override applies to its scene and/or resolution only, and gives those
// configurations their own reference key; malformed overrides name the problem.
TEST(SweepSpec, ReferenceSppOverridesMatchTheirSceneAndResolution) {
  sweep::Spec s = sweep::parseSpec(json::parse(R"({"scenes": [{"path": "", "label": "box"}, {"path": "scenes/sponza.json", "label": "room"}],
      "resolutions": ["8x8", "16x8"], "techniques": ["direct"],
      "reference": {"spp": 64, "spp_overrides": [{"scene": "room", "resolution": "16x8", "spp": 4},
                                                 {"resolution": "16x8", "spp": 16}]}})"));
  ASSERT_EQ(s.configurations.size(), 4u);
  std::map<std::string, int> spp;
  std::set<std::string> keys;
  for (auto& c : s.configurations) {
    spp[c.sceneLabel + " " + std::to_string(c.width)] = s.reference.sppFor(c);
    keys.insert(sweep::referenceKey(c, s.reference));
  }
  EXPECT_EQ(spp["box 8"], 64);
  EXPECT_EQ(spp["box 16"], 16);  // the second override (any scene at 16x8)
  EXPECT_EQ(spp["room 8"], 64);
  EXPECT_EQ(spp["room 16"], 4);  // the first override wins
  EXPECT_EQ(keys.size(), 4u);
  const std::string base = R"({"resolutions": ["8x8"], "techniques": ["direct"], "reference": {"spp": 8, "spp_overrides": )";
  expectSpecError(json::parse(base + R"([{"scene": "nowhere", "spp": 2}]}})"), "nowhere");
  expectSpecError(json::parse(base + R"([{"spp": 2}]}})"), "'scene' or a 'resolution'");
  expectSpecError(json::parse(base + R"([{"resolution": "8x8"}]}})"), "spp");
  expectSpecError(json::parse(base + R"([{"resolution": "8x8", "spp": 2, "colour": 1}]}})"), "colour");
  expectSpecError(json::parse(base + R"({"resolution": "8x8"}}})"), "must be a list");
}

TEST(SweepSpec, ShardsAreDisjointAndCoverTheSweep) {
  sweep::Spec s = sweep::parseSpec(json::parse(
      R"({"resolutions": ["8x8", "16x16", "24x24"], "techniques": [{"name": "vpl", "grid": {"vpl.count": [1, 2, 3, 4, 5]}}]})"));
  std::multiset<std::string> seen;
  for (int i = 0; i < 4; ++i)
    for (auto& c : sweep::selectShard(s.configurations, sweep::parseShard(std::to_string(i) + "/4"))) seen.insert(c.id);
  EXPECT_EQ(seen.size(), s.configurations.size());
  EXPECT_EQ(std::set<std::string>(seen.begin(), seen.end()).size(), s.configurations.size());
  for (const char* bad : {"4/4", "-1/2", "1/0", "1", "a/b", "1/2x"}) EXPECT_THROW(sweep::parseShard(bad), Error) << bad;
}

namespace {

json readJson(const fs::path& p) { return json::parse(std::ifstream(p)); }

// id -> (status, image bytes) of a finished sweep folder.
std::map<std::string, std::pair<std::string, std::string>> outcome(const fs::path& dir) {
  std::map<std::string, std::pair<std::string, std::string>> m;
  for (auto& row : readJson(dir / "results.json")["rows"]) {
    std::string image = row.contains("image") ? test::readFile(dir / row["image"].get<std::string>()) : "";
    m[row["id"]] = {row["status"], image};
  }
  return m;
}

}  // namespace

TEST(Sweep, RecordsFailuresResumesAndShardsMergeToTheSameResults) {
  auto dir = test::tempDir("sweep_run");
  fs::path spec = dir / "spec.json";
  std::ofstream(spec) << R"({"name": "tiny", "resolutions": ["32x32"], "frames": 2, "warmup": 1,
    "set": {"shadow.resolution": 256, "shadow.cube_resolution": 64, "rsm.resolution": 64},
    "techniques": ["direct", {"name": "vpl", "grid": {"vpl.count": [16]}}, "no_such_technique"]})";
  const std::string env = "GI_DEVICE=cpu";

  test::CommandResult r = test::runGi("sweep " + spec.string() + " --out " + (dir / "all").string() + " --no-report", env);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("[3/3]"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("left ~"), std::string::npos) << r.output;
  json results = readJson(dir / "all" / "results.json");
  ASSERT_EQ(results["rows"].size(), 3u) << results.dump(2);
  EXPECT_EQ(results["failed"], 1);
  const json& direct = results["rows"][0];
  EXPECT_EQ(direct["status"], "ok") << direct.dump(2);
  EXPECT_GT(direct["passes_ms"]["gbuffer"].get<double>(), 0.0);
  EXPECT_GT(direct["device_bytes"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(dir / "all" / direct["image"].get<std::string>()));
  const json& vpl = results["rows"][1];
  EXPECT_EQ(vpl["status"], "ok") << vpl.dump(2);
  EXPECT_EQ(vpl["params"]["vpl.count"], "16");
  EXPECT_EQ(vpl["params"]["shadow.resolution"], "256");  // the spec's common set
  EXPECT_TRUE(vpl["passes_ms"].contains("vpl")) << vpl.dump(2);
  const json& failed = results["rows"][2];
  EXPECT_EQ(failed["status"], "failed");
  EXPECT_NE(failed["message"].get<std::string>().find("unknown technique 'no_such_technique'"), std::string::npos)
      << failed["message"];
  std::string csv = test::readFile(dir / "all" / "results.csv");
  EXPECT_NE(csv.find("param:vpl.count"), std::string::npos) << csv;
  EXPECT_NE(csv.find("pass:vpl ms"), std::string::npos) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4) << csv;

  // Resume: nothing finished is redone; a configuration without a result is run again.
  r = test::runGi("sweep " + spec.string() + " --out " + (dir / "all").string() + " --no-report", env);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("3 already finished, 0 to run"), std::string::npos) << r.output;
  fs::remove(dir / "all" / "runs" / vpl["id"].get<std::string>() / "result.json");
  r = test::runGi("sweep " + spec.string() + " --out " + (dir / "all").string() + " --no-report", env);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("2 already finished, 1 to run"), std::string::npos) << r.output;
  EXPECT_EQ(readJson(dir / "all" / "results.json")["rows"].size(), 3u);

  // A folder holding another sweep is refused.
  fs::path other = dir / "other.json";
  std::ofstream(other) << R"({"resolutions": ["16x16"], "techniques": ["direct"]})";
  r = test::runGi("sweep " + other.string() + " --out " + (dir / "all").string(), env);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find("different sweep"), std::string::npos) << r.output;

  // Two shards, merged, equal the unsharded run.
  for (int i = 0; i < 2; ++i) {
    r = test::runGi("sweep " + spec.string() + " --shard " + std::to_string(i) + "/2 --out " +
                        (dir / ("shard" + std::to_string(i))).string() + " --no-report",
                    env);
    ASSERT_EQ(r.exitCode, 0) << r.output;
  }
  EXPECT_EQ(readJson(dir / "shard0" / "results.json")["rows"].size(), 2u);
  EXPECT_EQ(readJson(dir / "shard1" / "results.json")["rows"].size(), 1u);
  r = test::runGi("sweep --merge " + (dir / "shard0").string() + " " + (dir / "shard1").string() + " --out " +
                  (dir / "merged").string() + " --no-report");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(outcome(dir / "merged"), outcome(dir / "all"));
  fs::remove_all(dir);
}

TEST(Sweep, RefusesAFolderAnotherSweepIsWriting) {
  auto dir = test::tempDir("sweep_lock");
  fs::path spec = dir / "spec.json";
  std::ofstream(spec) << R"({"resolutions": ["16x16"], "techniques": ["direct"]})";
  fs::create_directories(dir / "out");
  int fd = ::open((dir / "out" / ".lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);  // as a running sweep holds it
  test::CommandResult r = test::runGi("sweep " + spec.string() + " --out " + (dir / "out").string(), "GI_DEVICE=cpu");
  ::close(fd);
  EXPECT_NE(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("another gi sweep is writing"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "runs"));
  fs::remove_all(dir);
}

// The specs shipped in bench/sweeps/ must keep working as techniques and parameters change: every
// one parses, and every configuration names a registered technique (chain), parameters that exist
// and are in range, and a scene config that exists in the repository.
TEST(SweepSpec, ShippedSpecsNameRealScenesTechniquesAndParameters) {
  const fs::path root = fs::path(GI_TEST_DATA_DIR).parent_path().parent_path();
  int specs = 0;
  for (const auto& entry : fs::directory_iterator(root / "bench" / "sweeps")) {
    if (entry.path().extension() != ".json") continue;
    ++specs;
    SCOPED_TRACE(entry.path().string());
    sweep::Spec spec;
    ASSERT_NO_THROW(spec = sweep::loadSpec(entry.path().string()));
    EXPECT_FALSE(spec.configurations.empty());
    for (const sweep::Configuration& c : spec.configurations) {
      SCOPED_TRACE(c.describe());
      if (!c.scene.empty()) EXPECT_TRUE(fs::exists(root / c.scene)) << c.scene;
      if (c.technique != "direct") EXPECT_NO_THROW(parseTechniqueChain(c.technique));
      ParamSet params = declareAllParams();
      for (const auto& [name, value] : c.params) EXPECT_NO_THROW(params.set(name, value)) << name << "=" << value;
    }
  }
  EXPECT_GE(specs, 4);
}
