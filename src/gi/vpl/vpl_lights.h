// Virtual point lights from reflective shadow maps (ALGORITHMS.md §2, §2.2;
// kernels/gi/vpl/vpl_generate.cl) and the interleaved all-pairs gather shared by the `vpl` and
// `igi` techniques (§2.3; kernels/gi/vpl/vpl_gather.cl).
#pragma once
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "cl/runtime.h"
#include "util/halton.h"  // radicalInverse, used by the host mirrors
#include "raster/gbuffer.h"
#include "gi/vpl/vpl_visibility.h"

namespace gi {

// VPLs of all lights, float4 ×3 each: (position, d_min²), (normal, 0), (flux Φ_p in W, 0).
// Generation-major: the RSM's VPLs (generation 0, `perLight` consecutive ones per light), then
// each further generation g of vpl.bounces, vplGenerationSizes()[g] per light, light by light.
struct VplSet {
  cl::Buffer vpls;
  int count = 0;     // all lights, all generations
  int perLight = 0;  // generation 0
};

// Flux-importance sampling of each light's RSM with the Halton (2, 3) sequence; CDFs built on the
// device every frame, nothing read back. Deterministic for a fixed light and scene.
class VplGenerator {
public:
  explicit VplGenerator(cl::Context& ctx, std::string label = "vpl");
  // perLight in 1..4096; dminOverride > 0 replaces the default 0.5 × RSM texel footprint.
  // bounces.generations > 0 appends Keller's further generations (kernels/gi/vpl/vpl_bounce.cl).
  void generate(const std::vector<ReflectiveShadowMap>& rsms, int perLight, float dminOverride, VplSet& out,
                const VplBounces& bounces = {});
  // The further generations alone: `out` holds generation 0 of `lights` lights at its start and
  // room for the rest (tests seed it by hand).
  void bounce(int lights, const VplBounces& bounces, VplSet& out);

private:
  cl::Context& ctx_;
  std::string label_;
  cl::Program program_, bounceProgram_;
  cl::Kernel rowCdf_, marginal_, sample_, alive_, bounce_;
  cl::Buffer aliveList_, aliveCount_;
  cl::Buffer texelCdf_, rowSum_, rowCdfBuf_;
  int cdfRes_ = 0;
};


// Host mirror of the generation (same formulas and summation order), for tests and the bench.
struct HostVpl {
  glm::vec3 position{0};
  float dmin2 = 0;
  glm::vec3 normal{0};
  glm::vec3 flux{0};
};
std::vector<HostVpl> hostGenerateVpls(const GiView& rsmView, const std::vector<glm::vec4>& position,
                                      const std::vector<glm::vec4>& normal, const std::vector<glm::vec4>& flux,
                                      int res, int count, float dminOverride);
// Host mirror of the direction of child k of m leaving the VPL of slot `walk` (0-based within its
// light and generation) and normal n towards generation `generation` ≥ 1
// (kernels/gi/vpl/vpl_bounce.cl), and the scrambled Halton bases and multipliers of that
// generation: (base u, multiplier u, base v, multiplier v).
glm::vec3 hostBounceDirection(glm::vec3 n, int walk, int generation, int k = 0, int m = 1);
glm::uvec4 bounceSequence(int generation);
// Host mirror of the specular term of kernels/gi/vpl/vpl_brdf_gather.cl: receiver at x, shading normal
// n, unit direction to the eye wo, specular F0 and roughness; W/(m²·sr).
glm::vec3 hostSpecularRadiance(const std::vector<HostVpl>& vpls, glm::vec3 x, glm::vec3 n, glm::vec3 wo, glm::vec3 f0,
                               float roughness);
// Host mirror of E_p summed over VPLs k = first, first + step, … (ALGORITHMS.md §2), W/m².
glm::vec3 hostIrradiance(const std::vector<HostVpl>& vpls, glm::vec3 x, glm::vec3 n, int first = 0, int step = 1);

// The interleaved gather: de-interleave the G-buffer into n·m sub-images (SoA planes), shade
// each with VPL set c (VPL k -> set k mod n·m, weights × n·m), re-interleave. n = m = 1 is the
// plain all-pairs gather. shadeCameraOrder() does the three steps in one pass.
class InterleavedGather {
public:
  // `prefix` names the launches: "<prefix>: de-interleave", "<prefix>: shade", "<prefix>: re-interleave".
  InterleavedGather(cl::Context& ctx, std::string prefix);
  void resize(int width, int height, int n, int m);
  // Position and shading normal (the irradiance at the receiver) into the sub-image planes.
  void deinterleave(const GBuffer& g);
  // `visibility` enabled: every pair is tested by a shadow ray (the visibility variant of the gather).
  void shade(const VplSet& vpls, const VplVisibility* visibility = nullptr);
  void reinterleaveRadiance(const GBuffer& g, cl::Buffer& out);  // L = ρ/π · E
  void reinterleaveIrradiance(cl::Buffer& out);                    // E, float4 per pixel
  // De-interleave (shading normals) + shade + re-interleave as one kernel (launch "<prefix>: shade"):
  // each work-item reads its sub-image run straight from the G-buffer and writes camera order, E
  // (radiance false) or L = ρ/π · E. Same values; planes() and irradiance() are not written.
  void shadeCameraOrder(const GBuffer& g, const VplSet& vpls, const VplVisibility* visibility, bool radiance,
                        cl::Buffer& out);

  int n() const { return n_; }
  int m() const { return m_; }
  int subWidth() const { return subW_; }    // ⌈W/n⌉ pixels
  int subHeight() const { return subH_; }   // ⌈H/m⌉ pixels
  int subPitch() const { return subPitch_; }  // slots per sub-image row: subWidth rounded up to 16
  int stride() const { return stride_; }    // slots per sub-image: subPitch · subHeight
  size_t slots() const { return size_t(n_) * m_ * stride_; }
  const cl::Buffer& planes() const { return planes_; }          // 6 planes: x, y, z, nx, ny, nz
  const cl::Buffer& irradiance() const { return irradiance_; }  // 3 planes: E r, g, b

private:
  cl::Context& ctx_;
  std::string prefix_;
  cl::Program program_;
  cl::Kernel deinterleave_, gather_, reRadiance_, reIrradiance_, gatherCamera_;
  cl::Program visibleProgram_;  // built on the first shade with visibility
  cl::Kernel visibleGather_, visibleGatherCamera_;
  cl::Buffer planes_, irradiance_;
  cl::NDRange copyRange() const;
  void allocatePlanes();  // on the first use of the copies (the fused path needs no planes)
  void buildVisibilityProgram(const VplVisibility& visibility);
  int width_ = 0, height_ = 0, n_ = 0, m_ = 0, subW_ = 0, subH_ = 0, subPitch_ = 0, stride_ = 0;
};

// Host mirror of the packed index (tests).
inline size_t packedIndex(int x, int y, int n, int m, int subPitch, int stride) {
  int c = (x % n) + n * (y % m);
  return size_t(c) * stride + size_t(y / m) * subPitch + size_t(x / n);
}

}  // namespace gi
