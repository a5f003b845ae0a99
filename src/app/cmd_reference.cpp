// `gi reference`: a path-traced reference image (src/reference/path_tracer.h) as linear EXR,
// optionally with its per-pixel variance-of-the-mean EXR.
//
// - Progress on stderr: samples done / total, elapsed, estimated time left.
// - Ctrl-C (SIGINT) stops after the launch in flight, writes the image so far (normalised by the
//   samples done, and the variance if asked), says so, and exits with status 130.
// - Cache: a finished reference is kept in <program cache dir>/references/<key>.exr (+ .var.exr),
//   the key hashing the scene (builtin name, or the scene file's bytes, plus the names and sizes of
//   the buffers and images a .gltf refers to, and for a scene config the glTF it names), camera, size, mode, spp, bounces, seed, diffuse-only and the
//   expanded kernel source. It is looked up before loading the scene, and a hit is copied to
//   --out at once. --no-cache neither reads nor writes it. Interrupted renders are not cached.
// - Samples per launch adapt so one launch takes about 0.3 s; results do not depend on it.
// - --checkpoint FILE: resume from FILE when it holds an earlier run of the same reference (same
//   key as the cache, spp aside), save the running sums there every --checkpoint-seconds and on
//   Ctrl-C, and delete it when done (--keep-checkpoint keeps it, to add samples later with a
//   larger --spp). Resuming gives the same bits as one uninterrupted run. `gi sweep` uses it, so
//   an hours-long reference survives the sweep being stopped.
// Hidden `gi export-scene SCENE --out DIR`: the flattened scene as one OBJ per instance plus
// scene.json (materials, cameras, lights), for bench/cross_check_mitsuba.py.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/common_options.h"
#include "image/image.h"
#include "reference/path_tracer.h"
#include "render/renderer.h"
#include "render/views.h"
#include "scene/media_path.h"
#include "scene/scene_loader.h"
#include "util/file_io.h"
#include "util/hash.h"

namespace gi::app {

namespace {

std::atomic<bool> gInterrupted{false};
extern "C" void onSigint(int) { gInterrupted.store(true); }

struct ReferenceArgs {
  std::string scene, camera, mode = "full", out, variance;
  int width = 0, height = 0, spp = 256, maxBounces = 8;
  uint32_t seed = 0;
  bool diffuseOnly = false, noCache = false, keepCheckpoint = false;
  std::string checkpoint;
  double checkpointSeconds = 60.0;
  CommonOptions common;
};

// A checkpoint: one text line naming the reference (everything of the cache key but the spp),
// one line "width height samples", then Σ L and Σ L² as raw float4 per pixel.
constexpr const char* kCheckpointMagic = "gi path tracer checkpoint 1";

void writeCheckpoint(const std::string& path, const std::string& identity, int width, int height,
                     const PathTracer::Accumulation& acc) {
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream o(tmp, std::ios::binary);
    o << kCheckpointMagic << "\n" << identity << "\n" << width << " " << height << " " << acc.samples << "\n";
    o.write(reinterpret_cast<const char*>(acc.sum.data()), std::streamsize(acc.sum.size() * sizeof(float)));
    o.write(reinterpret_cast<const char*>(acc.sumSq.data()), std::streamsize(acc.sumSq.size() * sizeof(float)));
    if (!o) throw Error("cannot write the checkpoint " + tmp.string());
  });
}

// Reads a checkpoint of this reference; throws gi::Error naming the file if it is another
// reference's, truncated, or has more samples than asked for.
PathTracer::Accumulation readCheckpoint(const std::string& path, const std::string& identity, int width, int height,
                                        int spp) {
  std::ifstream in(path, std::ios::binary);
  std::string magic, id, dims;
  if (!std::getline(in, magic) || magic != kCheckpointMagic || !std::getline(in, id) || !std::getline(in, dims))
    throw Error("--checkpoint " + path + ": not a gi path tracer checkpoint");
  if (id != identity)
    throw Error("--checkpoint " + path + ": it belongs to another reference (scene, camera, size, mode, bounces, seed or "
                "path tracer code differ); delete it or name another file");
  int w = 0, h = 0;
  PathTracer::Accumulation acc;
  if (std::sscanf(dims.c_str(), "%d %d %d", &w, &h, &acc.samples) != 3 || w != width || h != height || acc.samples < 0)
    throw Error("--checkpoint " + path + ": its header '" + dims + "' does not match " + std::to_string(width) + "x" +
                std::to_string(height));
  if (acc.samples > spp)
    throw Error("--checkpoint " + path + " already holds " + std::to_string(acc.samples) + " spp, more than --spp " +
                std::to_string(spp));
  const size_t floats = size_t(width) * height * 4;
  acc.sum.resize(floats);
  acc.sumSq.resize(floats);
  in.read(reinterpret_cast<char*>(acc.sum.data()), std::streamsize(floats * sizeof(float)));
  in.read(reinterpret_cast<char*>(acc.sumSq.data()), std::streamsize(floats * sizeof(float)));
  if (!in || in.peek() != std::char_traits<char>::eof())
    throw Error("--checkpoint " + path + ": truncated or too long for " + std::to_string(width) + "x" +
                std::to_string(height));
  return acc;
}

std::string lowerExt(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// What identifies the scene's content cheaply (see the file comment): the file's bytes; for a
// .gltf also the names and sizes of the buffers and images it refers to (not their bytes: Sponza's
// textures are hundreds of MB); for a scene config also the glTF it names.
std::string fileIdentity(const std::filesystem::path& file) {
  std::string text = readTextFile(file);
  std::ostringstream id;
  id << "file|" << std::hex << fnv1a64(text) << std::dec;
  if (lowerExt(file.string()) == ".gltf") {
    try {
      auto j = nlohmann::json::parse(text);
      for (const char* list : {"buffers", "images"}) {
        if (!j.contains(list) || !j[list].is_array()) continue;
        for (auto& e : j[list]) {
          if (!e.contains("uri") || !e["uri"].is_string()) continue;
          std::string uri = e["uri"].get<std::string>();
          if (uri.rfind("data:", 0) == 0) continue;  // embedded: already in the file's bytes
          std::error_code ec;
          auto size = std::filesystem::file_size(file.parent_path() / uri, ec);
          id << "|" << uri << ":" << (ec ? -1 : int64_t(size));
        }
      }
    } catch (const std::exception&) {
      // Malformed glTF fails in loadScene with a proper message.
    }
  }
  return id.str();
}

std::string sceneIdentity(const std::string& spec, const std::string& media) {
  if (spec.empty() || spec == "cornell" || spec.rfind("builtin:", 0) == 0) return "builtin|" + spec;
  std::filesystem::path file = resolveMediaFile(spec, media);
  std::string id = fileIdentity(file);
  if (lowerExt(file.string()) == ".json") {
    try {
      auto j = nlohmann::json::parse(readTextFile(file));
      if (j.contains("gltf") && j["gltf"].is_string())
        id += "||" + fileIdentity(resolveMediaFile(j["gltf"].get<std::string>(), media, {file.parent_path()}));
      if (j.contains("builtin") && j["builtin"].is_string()) id += "||builtin|" + j["builtin"].get<std::string>();
    } catch (const std::exception&) {
      // An unreadable config fails in loadScene with a proper message; no cache key needed.
    }
  }
  return id;
}

std::string hex16(uint64_t v) {
  char b[17];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
  return b;
}

// `resumedAt`: samples restored from a checkpoint (not part of `elapsed`, left out of the rate).
void progress(int done, int total, double elapsed, bool final, int resumedAt) {
  const int W = 30;
  int filled = total > 0 ? done * W / total : W;
  double left = done > resumedAt ? elapsed * double(total - done) / double(done - resumedAt) : 0.0;
  std::fprintf(stderr, "\r[%.*s%.*s] %d/%d spp  %.1f s elapsed, %.1f s left   ", filled,
               "##############################", W - filled, "..............................", done, total, elapsed,
               left);
  if (final) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

void run(const ReferenceArgs& a) {
  // Every flag is checked before any work, so a bad command writes nothing.
  if (a.out.empty()) throw Error("reference: --out FILE.exr is required");
  if (lowerExt(a.out) != ".exr") throw Error("--out '" + a.out + "': the reference is linear radiance, use .exr");
  if (!a.variance.empty() && lowerExt(a.variance) != ".exr")
    throw Error("--variance '" + a.variance + "': use .exr");
  ReferenceMode mode = parseReferenceMode(a.mode);

  // The cache is looked up before the scene is loaded (a hit must be instant): the key names the
  // camera, size and scene as given on the command line; the scene's content hash covers what
  // the defaults (default camera, size) are taken from.
  if (!a.checkpoint.empty() && !(a.checkpointSeconds > 0.0))
    throw Error("--checkpoint-seconds must be positive");
  auto referenceIdentity = [&](bool withSpp) {
    std::ostringstream k;
    k << sceneIdentity(a.scene, a.common.media) << "|camera " << a.camera << "|" << a.width << "x" << a.height
      << "|" << referenceModeName(mode);
    if (withSpp) k << "|spp " << a.spp;
    k << "|bounces " << a.maxBounces << "|seed " << a.seed << "|diffuse " << a.diffuseOnly << "|code "
      << hex16(pathTracerCodeHash());
    return k.str();
  };
  std::filesystem::path cacheExr, cacheVar;
  std::string cacheDir = cl::Context::cacheDirectory();
  if (!a.noCache && !cacheDir.empty()) {
    std::string key = hex16(fnv1a64(referenceIdentity(true)));
    std::filesystem::path dir = std::filesystem::path(cacheDir) / "references";
    cacheExr = dir / (key + ".exr");
    cacheVar = dir / (key + ".var.exr");
    if (std::filesystem::exists(cacheExr) && std::filesystem::exists(cacheVar)) {
      auto copy = [](const std::filesystem::path& from, const std::string& to) {
        writeAtomically(to, [&](const std::filesystem::path& tmp) {
          std::filesystem::copy_file(from, tmp, std::filesystem::copy_options::overwrite_existing);
        });
      };
      copy(cacheExr, a.out);
      if (!a.variance.empty()) copy(cacheVar, a.variance);
      std::printf("wrote %s (cached reference %s)\n", a.out.c_str(), cacheExr.string().c_str());
      return;
    }
  }

  Scene scene = loadScene(a.scene, a.common.media);
  const Camera& cam = selectCamera(scene, a.camera);
  PathTracerOptions o;
  o.width = a.width > 0 ? a.width : scene.defaultWidth;
  o.height = a.height > 0 ? a.height : scene.defaultHeight;
  o.maxBounces = a.maxBounces;
  o.mode = mode;
  o.diffuseOnly = a.diffuseOnly;
  o.seed = a.seed;

  cl::Context ctx(cl::selectDevice(a.common.device));
  PathTracer pt(ctx, scene, makeCameraView(cam, o.width, o.height), o);
  std::fprintf(stderr, "reference: %s, camera '%s', %dx%d, %s%s, %d spp, max %d bounces, seed %u; %zu triangles "
               "(BVH %.2f s), %u emissive, %u punctual lights\n",
               scene.name.c_str(), cam.name.c_str(), o.width, o.height, referenceModeName(mode),
               o.diffuseOnly ? " diffuse-only" : "", a.spp, o.maxBounces, o.seed, scene.triangleCount(),
               pt.bvhStats().buildSeconds, pt.emissiveTriangles(), pt.punctualLights());

  const std::string checkpointIdentity = a.checkpoint.empty() ? "" : referenceIdentity(false);
  if (!a.checkpoint.empty() && std::filesystem::exists(a.checkpoint)) {
    pt.restore(readCheckpoint(a.checkpoint, checkpointIdentity, o.width, o.height, a.spp));
    std::fprintf(stderr, "reference: resuming from %s at %d spp\n", a.checkpoint.c_str(), pt.samplesDone());
  }
  auto saveCheckpoint = [&] { writeCheckpoint(a.checkpoint, checkpointIdentity, o.width, o.height, pt.accumulation()); };

  gInterrupted.store(false);
  auto previous = std::signal(SIGINT, onSigint);
  auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  int batch = 1;
  double lastPrint = -1.0, lastCheckpoint = 0.0;
  const int resumedAt = pt.samplesDone();
  while (pt.samplesDone() < a.spp && !gInterrupted.load()) {
    int n = std::min(batch, a.spp - pt.samplesDone());
    auto tb = std::chrono::steady_clock::now();
    pt.addSamples(n);
    double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - tb).count();
    // Aim at ~0.3 s per launch: responsive to Ctrl-C and progress, few launch overheads.
    double perSample = dt / n;
    batch = std::clamp(int(0.3 / std::max(perSample, 1e-6)), 1, 256);
    if (elapsed() - lastPrint > 0.25 && pt.samplesDone() < a.spp) {
      progress(pt.samplesDone(), a.spp, elapsed(), false, resumedAt);
      lastPrint = elapsed();
    }
    if (!a.checkpoint.empty() && elapsed() - lastCheckpoint > a.checkpointSeconds && pt.samplesDone() < a.spp) {
      saveCheckpoint();
      lastCheckpoint = elapsed();
    }
  }
  std::signal(SIGINT, previous);
  progress(pt.samplesDone(), a.spp, elapsed(), true, resumedAt);
  bool interrupted = pt.samplesDone() < a.spp;
  if (!a.checkpoint.empty()) {
    if (interrupted || a.keepCheckpoint) saveCheckpoint();
    else std::filesystem::remove(a.checkpoint);
  }

  Image img = pt.image();
  Image var = pt.variance();
  writeImage(a.out, img);
  if (!a.variance.empty()) writeImage(a.variance, var);
  if (interrupted) {
    std::fprintf(stderr, "gi: interrupted: wrote %s with %d of %d samples per pixel\n", a.out.c_str(),
                 pt.samplesDone(), a.spp);
    std::fflush(stderr);
    std::exit(130);
  }
  if (!cacheExr.empty()) {
    try {
      std::filesystem::create_directories(cacheExr.parent_path());
      writeImage(cacheVar, var);  // variance first: a hit needs both, the image is checked last
      writeImage(cacheExr, img);
    } catch (const std::exception& e) {
      warn(std::string("reference cache not written: ") + e.what());
    }
  }
  std::printf("wrote %s (%d spp in %.1f s)\n", a.out.c_str(), pt.samplesDone(), elapsed());
  if (!a.variance.empty()) std::printf("wrote %s\n", a.variance.c_str());
}

// Hidden: the flattened scene as OBJ + JSON for external renderers (Mitsuba cross-check).
void exportScene(const std::string& spec, const std::string& media, const std::string& outDir) {
  if (outDir.empty()) throw Error("export-scene: --out DIR is required");
  Scene scene = loadScene(spec, media);
  std::filesystem::create_directories(outDir);
  std::map<uint32_t, std::vector<size_t>> byInstance;
  for (size_t t = 0; t < scene.triangleCount(); ++t) byInstance[scene.triangleInstance[t]].push_back(t);
  nlohmann::json j;
  j["name"] = scene.name;
  for (const GiMaterial& m : scene.materials) {
    nlohmann::json jm;
    jm["base_color"] = {m.base_color[0], m.base_color[1], m.base_color[2], m.base_color[3]};
    jm["emissive"] = {m.emissive[0], m.emissive[1], m.emissive[2]};
    jm["metallic"] = m.metallic;
    jm["roughness"] = m.roughness;
    jm["textured"] = m.base_color_tex >= 0 || m.emissive_tex >= 0;
    j["materials"].push_back(jm);
  }
  for (auto& [inst, tris] : byInstance) {
    std::string file = "instance_" + std::to_string(inst) + ".obj";
    std::ofstream o(std::filesystem::path(outDir) / file);
    o.precision(9);
    for (size_t t : tris)
      for (int k = 0; k < 3; ++k) {
        glm::vec3 p = scene.positions[scene.triangles[t][k]];
        o << "v " << p.x << " " << p.y << " " << p.z << "\n";
      }
    for (size_t i = 0; i < tris.size(); ++i) o << "f " << 3 * i + 1 << " " << 3 * i + 2 << " " << 3 * i + 3 << "\n";
    if (!o) throw Error("cannot write " + file);
    // One material per instance is what the cross-check supports; the first triangle's is taken.
    j["instances"].push_back({{"id", inst}, {"file", file}, {"material", scene.triangleMaterial[tris[0]]},
                              {"triangles", tris.size()}});
  }
  for (const Camera& c : scene.cameras)
    j["cameras"].push_back({{"name", c.name},
                            {"position", {c.position.x, c.position.y, c.position.z}},
                            {"target", {c.target.x, c.target.y, c.target.z}},
                            {"up", {c.up.x, c.up.y, c.up.z}},
                            {"yfov", c.yfov}});
  for (size_t i = 0; i < scene.lights.size(); ++i) j["lights"].push_back(i < scene.lightNames.size() ? scene.lightNames[i] : "");
  std::ofstream o(std::filesystem::path(outDir) / "scene.json");
  o << j.dump(1) << "\n";
  if (!o) throw Error("cannot write scene.json in " + outDir);
  std::printf("wrote %s (%zu instances)\n", outDir.c_str(), byInstance.size());
}

}  // namespace

void registerReferenceCommand(CLI::App& app) {
  auto a = std::make_shared<ReferenceArgs>();
  auto* cmd = app.add_subcommand("reference", "Path-trace a reference image (linear EXR) and its variance");
  cmd->add_option("scene", a->scene, "scene: a .gltf/.glb file, a scene config .json, or nothing for the built-in Cornell box");
  cmd->add_option("--camera", a->camera, "camera name or index (default: the scene's default camera)");
  cmd->add_option("--width", a->width, "image width in pixels (default: the scene's)")->check(CLI::Range(1, 16384));
  cmd->add_option("--height", a->height, "image height in pixels (default: the scene's)")->check(CLI::Range(1, 16384));
  cmd->add_option("--spp", a->spp, "samples per pixel (default 256)")->check(CLI::Range(1, 1 << 24));
  cmd->add_option("--max-bounces", a->maxBounces, "largest number of reflections of a light path (default 8; 1 = direct)")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--mode", a->mode, "full | direct (orders 0-1) | indirect (orders >= 2) | one-bounce (order 2 only)")
      ->check(CLI::IsMember({"full", "direct", "indirect", "one-bounce"}));
  cmd->add_flag("--diffuse-only", a->diffuseOnly, "turn the specular lobe off (f = albedo/pi)");
  cmd->add_option("--seed", a->seed, "random seed (default 0)");
  cmd->add_option("--out", a->out, "output image (.exr, linear radiance)")->required();
  cmd->add_option("--variance", a->variance, "also write the per-pixel variance of the mean (.exr)");
  cmd->add_flag("--no-cache", a->noCache, "neither reuse nor store a cached reference");
  cmd->add_option("--checkpoint", a->checkpoint,
                  "resume from / save progress to this file (deleted when done); same bits as an uninterrupted run");
  cmd->add_option("--checkpoint-seconds", a->checkpointSeconds, "seconds between checkpoint saves (default 60)")
      ->check(CLI::Range(0.001, 1e9));
  cmd->add_flag("--keep-checkpoint", a->keepCheckpoint, "keep the checkpoint when done (to add samples later)");
  addCommonOptions(cmd, a->common);
  cmd->callback([a] { run(*a); });

  auto e = std::make_shared<std::pair<std::string, std::string>>();
  auto common = std::make_shared<CommonOptions>();
  auto* ex = app.add_subcommand("export-scene", "Write the flattened scene as OBJ + JSON (for cross-checks)");
  ex->group("");  // hidden from --help
  ex->add_option("scene", e->first, "scene (as for reference)");
  ex->add_option("--out", e->second, "output folder")->required();
  addCommonOptions(ex, *common);
  ex->callback([e, common] { exportScene(e->first, common->media, e->second); });
}

}  // namespace gi::app
