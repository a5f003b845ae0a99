#include "gi/vpl/vpl_lights.h"
#include "util/halton.h"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace gi {

namespace {
constexpr float kInvPi = 0.31830988618379067154f;

float luminanceOf(glm::vec3 c) { return c.x * 0.2126f + c.y * 0.7152f + c.z * 0.0722f; }

int cdfSearch(const float* cdf, int n, float t) {
  int lo = 0, hi = n - 1;
  while (lo < hi) {
    int mid = (lo + hi) >> 1;
    if (cdf[mid] > t) hi = mid;
    else lo = mid + 1;
  }
  return lo;
}
}  // namespace

VplGenerator::VplGenerator(cl::Context& ctx, std::string label) : ctx_(ctx), label_(std::move(label)) {
  program_ = ctx_.buildProgram("kernels/gi/vpl/vpl_generate.cl");
  rowCdf_ = program_.kernel("vpl_row_cdf");
  marginal_ = program_.kernel("vpl_marginal_cdf");
  sample_ = program_.kernel("vpl_sample");
}

void VplGenerator::generate(const std::vector<ReflectiveShadowMap>& rsms, int perLight, float dminOverride,
                            VplSet& out, const VplBounces& bounces) {
  if (perLight < 1 || perLight > 4096) throw Error("VPL count " + std::to_string(perLight) + " outside 1..4096");
  int total = 0;
  for (int n : vplGenerationSizes(perLight, bounces)) total += n * int(rsms.size());
  if (!out.vpls || out.count != total) {
    out.vpls = cl::Buffer(ctx_, size_t(std::max(total, 1)) * 3 * 16, CL_MEM_READ_WRITE, "VPLs");
    if (total == 0) ctx_.fill(out.vpls, 0.0f);
  }
  out.count = total;
  out.perLight = perLight;
  for (size_t l = 0; l < rsms.size(); ++l) {
    const ReflectiveShadowMap& r = rsms[l];
    int res = r.view.width;
    if (res != cdfRes_) {
      texelCdf_ = cl::Buffer(ctx_, size_t(res) * res * 4, CL_MEM_READ_WRITE, "VPL texel CDF");
      rowSum_ = cl::Buffer(ctx_, size_t(res) * 4, CL_MEM_READ_WRITE, "VPL row sums");
      rowCdfBuf_ = cl::Buffer(ctx_, size_t(res) * 4, CL_MEM_READ_WRITE, "VPL row CDF");
      cdfRes_ = res;
    }
    rowCdf_.args(r.flux, res, texelCdf_, rowSum_);
    ctx_.launch(rowCdf_, cl::NDRange::d1(cl::roundUp(res, 16), 16), label_ + ": cdf");
    marginal_.args(rowSum_, res, rowCdfBuf_);
    ctx_.launch(marginal_, cl::NDRange::d1(1, 1), label_ + ": cdf");
    sample_.args(r.view, r.position, r.normal, r.flux, res, texelCdf_, rowCdfBuf_, perLight, dminOverride,
                 int(l) * perLight, out.vpls);
    ctx_.launch(sample_, cl::NDRange::d1(cl::roundUp(perLight, 64), 64), label_ + ": sample");
  }
  if (bounces.generations > 0 && total > 0) bounce(int(rsms.size()), bounces, out);
}

glm::uvec4 bounceSequence(int generation) {
  // Halton dimensions 2g and 2g + 1 (dimensions 0 and 1, bases 2 and 3, picked the RSM texel).
  static constexpr uint32_t kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61};
  if (generation < 1 || 2 * generation + 1 >= int(std::size(kPrimes)))
    throw Error("VPL generation " + std::to_string(generation) + " outside 1..8");
  // Multiplier ≈ base / golden ratio: consecutive digits land far apart.
  auto multiplier = [](uint32_t b) { return std::clamp(uint32_t(std::lround(0.6180339887 * b)), 1u, b - 1); };
  uint32_t bu = kPrimes[2 * generation], bv = kPrimes[2 * generation + 1];
  return {bu, multiplier(bu), bv, multiplier(bv)};
}

void VplGenerator::bounce(int lights, const VplBounces& b, VplSet& out) {
  if (b.generations <= 0) return;
  if (!b.bvh || !b.scene) throw Error("VPL bounces need the scene's BVH");
  if (!bounce_.get()) {
    bounceProgram_ = ctx_.buildProgram("kernels/gi/vpl/vpl_bounce.cl");
    alive_ = bounceProgram_.kernel("vpl_alive");
    bounce_ = bounceProgram_.kernel("vpl_bounce");
  }
  std::vector<int> sizes = vplGenerationSizes(out.perLight, b);
  size_t aliveBytes = size_t(*std::max_element(sizes.begin(), sizes.end())) * lights * 4;
  if (!aliveList_ || aliveList_.bytes() < aliveBytes) {
    aliveList_ = cl::Buffer(ctx_, aliveBytes, CL_MEM_READ_WRITE, "VPL live parents");
    aliveCount_ = cl::Buffer(ctx_, size_t(lights) * 4, CL_MEM_READ_WRITE, "VPL live parent counts");
  } else if (aliveCount_.bytes() < size_t(lights) * 4) {
    aliveCount_ = cl::Buffer(ctx_, size_t(lights) * 4, CL_MEM_READ_WRITE, "VPL live parent counts");
  }
  int parentFirst = 0;
  for (int g = 1; g < int(sizes.size()); ++g) {
    int childFirst = parentFirst + sizes[g - 1] * lights;
    alive_.args(out.vpls, lights, parentFirst, sizes[g - 1], aliveList_, aliveCount_);
    ctx_.launch(alive_, cl::NDRange::d1(cl::roundUp(lights, 16), 16), label_ + ": bounce");
    glm::uvec4 seq = bounceSequence(g);
    unsigned a = b.bvh->setArgs(bounce_, 0);
    bounce_.setArg(a++, b.scene->positions);
    bounce_.setArg(a++, b.scene->normals);
    bounce_.setArg(a++, b.scene->tangents);
    for (int v : {lights, parentFirst, sizes[g - 1]}) bounce_.setArg(a++, v);
    bounce_.setArg(a++, aliveList_);
    bounce_.setArg(a++, aliveCount_);
    for (int v : {childFirst, sizes[g]}) bounce_.setArg(a++, v);
    for (int c = 0; c < 4; ++c) bounce_.setArg(a++, uint32_t(seq[c]));
    bounce_.setArg(a++, b.rayEpsilon);
    bounce_.setArg(a++, out.vpls);
    ctx_.launch(bounce_, cl::NDRange::d1(cl::roundUp(size_t(sizes[g]) * lights, 64), 64), label_ + ": bounce");
    parentFirst = childFirst;
  }
}

glm::vec3 hostBounceDirection(glm::vec3 n, int walk, int generation, int k, int m) {
  glm::uvec4 seq = bounceSequence(generation);
  float u = scrambledRadicalInverse(uint32_t(walk) + 1, seq.x, seq.y) + float(k) / float(m);
  float v = scrambledRadicalInverse(uint32_t(walk) + 1, seq.z, seq.w) + radicalInverse(uint32_t(k), 2);
  u -= std::floor(u);
  v -= std::floor(v);
  // orthonormal_basis() of kernels/common/math.h (Duff et al. 2017).
  float s = n.z >= 0.0f ? 1.0f : -1.0f;
  float a = -1.0f / (s + n.z), c = n.x * n.y * a;
  glm::vec3 t(1.0f + s * n.x * n.x * a, s * c, -s * n.x), b(c, s + n.y * n.y * a, -n.y);
  float r = std::sqrt(u), phi = 2.0f * 3.14159265358979f * v;
  return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0f, 1.0f - u));
}

std::vector<HostVpl> hostGenerateVpls(const GiView& view, const std::vector<glm::vec4>& position,
                                      const std::vector<glm::vec4>& normal, const std::vector<glm::vec4>& flux,
                                      int res, int count, float dminOverride) {
  std::vector<float> texelCdf(size_t(res) * res), rowCdf(res);
  float run = 0.0f;
  for (int y = 0; y < res; ++y) {
    float s = 0.0f;
    for (int x = 0; x < res; ++x) {
      s += std::max(luminanceOf(glm::vec3(flux[size_t(y) * res + x])), 0.0f);
      texelCdf[size_t(y) * res + x] = s;
    }
    run += s;
    rowCdf[y] = run;
  }
  std::vector<HostVpl> out(count);
  float total = rowCdf[res - 1];
  if (!(total > 0.0f)) return out;
  glm::vec3 axis = -glm::vec3(view.view[2], view.view[6], view.view[10]);
  glm::vec3 eye(view.eye[0], view.eye[1], view.eye[2]);
  for (int k = 0; k < count; ++k) {
    float u1 = radicalInverse(uint32_t(k) + 1, 2), u2 = radicalInverse(uint32_t(k) + 1, 3);
    int y = cdfSearch(rowCdf.data(), res, u2 * total);
    const float* tc = texelCdf.data() + size_t(y) * res;
    int x = cdfSearch(tc, res, u1 * tc[res - 1]);
    size_t t = size_t(y) * res + x;
    glm::vec3 phi(flux[t]);
    float lum = std::max(luminanceOf(phi), 0.0f);
    HostVpl& v = out[k];
    v.position = glm::vec3(position[t]);
    v.normal = glm::vec3(normal[t]);
    v.flux = lum > 0.0f ? phi * (total / (float(count) * lum)) : glm::vec3(0.0f);
    float footprint = view.texel_world_size;
    if (!view.orthographic) footprint *= std::abs(glm::dot(v.position - eye, axis));
    float dmin = dminOverride > 0.0f ? dminOverride : 0.5f * footprint;
    v.dmin2 = dmin * dmin;
  }
  return out;
}

glm::vec3 hostIrradiance(const std::vector<HostVpl>& vpls, glm::vec3 x, glm::vec3 n, int first, int step) {
  glm::vec3 e(0.0f);
  for (size_t k = size_t(first); k < vpls.size(); k += size_t(step)) {
    const HostVpl& p = vpls[k];
    glm::vec3 v = p.position - x;
    float d2 = glm::dot(v, v);
    float cp = -glm::dot(p.normal, v), cr = glm::dot(n, v);
    float g = std::max(cp, 0.0f) * std::max(cr, 0.0f) / (std::max(d2, 1e-20f) * std::max(d2, p.dmin2));
    e += p.flux * g;
  }
  return e * (float(step) * kInvPi);
}

glm::vec3 hostSpecularRadiance(const std::vector<HostVpl>& vpls, glm::vec3 x, glm::vec3 n, glm::vec3 wo, glm::vec3 f0,
                               float roughness) {
  float nv = glm::dot(n, wo);
  if (!(nv > 0.0f)) return glm::vec3(0.0f);
  float a = std::max(roughness * roughness, 1e-3f), a2 = a * a;  // ggx_alpha()
  glm::vec3 l(0.0f);
  for (const HostVpl& p : vpls) {
    glm::vec3 v = p.position - x;
    float d2 = std::max(glm::dot(v, v), 1e-20f), d = std::sqrt(d2);
    float cp = -glm::dot(p.normal, v), cr = glm::dot(n, v);
    if (cp <= 0.0f || cr <= 0.0f) continue;
    glm::vec3 wi = v / d, h = glm::normalize(wo + wi);
    float nh = std::max(glm::dot(n, h), 0.0f), nl = cr / d;
    float dd = nh * nh * (a2 - 1.0f) + 1.0f;
    float D = a2 / (3.14159265358979f * dd * dd);
    float gv = nl * std::sqrt(nv * nv * (1.0f - a2) + a2), gl = nv * std::sqrt(nl * nl * (1.0f - a2) + a2);
    float V = 0.5f / std::max(gv + gl, 1e-12f);
    float m = std::clamp(1.0f - glm::dot(wi, h), 0.0f, 1.0f), m5 = m * m * m * m * m;
    glm::vec3 F = f0 + (1.0f - f0) * m5;
    l += p.flux * F * (D * V * cp * cr / (d2 * std::max(d2, p.dmin2)));
  }
  return l * kInvPi;
}

InterleavedGather::InterleavedGather(cl::Context& ctx, std::string prefix) : ctx_(ctx), prefix_(std::move(prefix)) {
  program_ = ctx_.buildProgram("kernels/gi/vpl/vpl_gather.cl");
  deinterleave_ = program_.kernel("gi_deinterleave");
  gather_ = program_.kernel("vpl_gather");
  reRadiance_ = program_.kernel("gi_reinterleave_radiance");
  reIrradiance_ = program_.kernel("gi_reinterleave_irradiance");
  gatherCamera_ = program_.kernel("vpl_gather_camera");
}

void InterleavedGather::resize(int width, int height, int n, int m) {
  if (n < 1 || n > 8 || m < 1 || m > 8) throw Error("interleave pattern " + std::to_string(n) + "x" + std::to_string(m) + " outside 1x1..8x8");
  if (width == width_ && height == height_ && n == n_ && m == m_) return;
  width_ = width;
  height_ = height;
  n_ = n;
  m_ = m;
  subW_ = (width + n - 1) / n;
  subH_ = (height + m - 1) / m;
  subPitch_ = int(cl::roundUp(size_t(subW_), 16));  // whole 16-slot runs per row (vpl_gather.cl copies)
  stride_ = subPitch_ * subH_;
  planes_ = cl::Buffer();
  irradiance_ = cl::Buffer();
}

void InterleavedGather::allocatePlanes() {
  if (planes_) return;
  planes_ = cl::Buffer(ctx_, slots() * 6 * 4, CL_MEM_READ_WRITE, prefix_ + " G-buffer sub-images");
  irradiance_ = cl::Buffer(ctx_, slots() * 3 * 4, CL_MEM_READ_WRITE, prefix_ + " sub-image irradiance");
  ctx_.fill(irradiance_, 0.0f);
}

// The copies' work-items (vpl_gather.cl): dimension 0 = class column + n · (run of GI_VW slots of
// a sub-image row), dimension 1 = camera row, m·⌈H/m⌉ of them (the rows past H write empty slots).
// A work-group covers several runs of all n class columns of a few rows.
cl::NDRange InterleavedGather::copyRange() const {
  size_t vw = size_t(ctx_.vectorWidth());
  size_t runs = size_t(subPitch_) / vw;  // a multiple of 16 / vw
  size_t perGroup = 1;
  while (perGroup < 8 && runs % (perGroup * 2) == 0) perGroup *= 2;
  size_t rows = std::max<size_t>(1, 16 / perGroup);
  return cl::NDRange::d2(size_t(n_) * runs, cl::roundUp(size_t(m_) * subH_, rows), size_t(n_) * perGroup, rows);
}

void InterleavedGather::deinterleave(const GBuffer& g) {
  allocatePlanes();
  deinterleave_.args(width_, height_, n_, m_, subPitch_, stride_, g.position, g.normal, planes_);
  ctx_.launch(deinterleave_, copyRange(), prefix_ + ": de-interleave");
}

void InterleavedGather::shade(const VplSet& v, const VplVisibility* visibility) {
  allocatePlanes();
  int sets = n_ * m_;
  bool rays = visibility && visibility->enabled();
  if (rays) buildVisibilityProgram(*visibility);
  cl::Kernel& gather = rays ? visibleGather_ : gather_;
  gather.args(planes_, sets, stride_, v.vpls, v.count, irradiance_);
  if (rays) visibility->setArgs(gather, 6);
  size_t items = slots() / size_t(ctx_.vectorWidth());
  size_t local = ctx_.vectorWidth() > 1 ? 4 : 64;
  ctx_.launch(gather, cl::NDRange::d1(cl::roundUp(items, local), local), prefix_ + (rays ? ": shade + rays" : ": shade"));
}

void InterleavedGather::buildVisibilityProgram(const VplVisibility& visibility) {
  if (visibleGather_.get()) return;
  visibleProgram_ = ctx_.buildProgram("kernels/gi/vpl/vpl_gather.cl", visibility.defines());
  visibleGather_ = visibleProgram_.kernel("vpl_gather");
  visibleGatherCamera_ = visibleProgram_.kernel("vpl_gather_camera");
}

void InterleavedGather::shadeCameraOrder(const GBuffer& g, const VplSet& v, const VplVisibility* visibility,
                                         bool radiance, cl::Buffer& out) {
  bool rays = visibility && visibility->enabled();
  if (rays) buildVisibilityProgram(*visibility);
  cl::Kernel& k = rays ? visibleGatherCamera_ : gatherCamera_;
  k.args(width_, height_, n_, m_, subPitch_, stride_, g.position, g.normal, v.vpls, v.count, int(radiance), g.albedo,
         out);
  if (rays) visibility->setArgs(k, 13);
  // Labelled like shade(): the benchmarks' "shade" of `vpl`/`igi` now includes the copies' work.
  ctx_.launch(k, copyRange(), prefix_ + (rays ? ": shade + rays" : ": shade"));
}

void InterleavedGather::reinterleaveRadiance(const GBuffer& g, cl::Buffer& out) {
  reRadiance_.args(width_, height_, n_, m_, subPitch_, stride_, irradiance_, g.albedo, out);
  ctx_.launch(reRadiance_, copyRange(), prefix_ + ": re-interleave");
}

void InterleavedGather::reinterleaveIrradiance(cl::Buffer& out) {
  reIrradiance_.args(width_, height_, n_, m_, subPitch_, stride_, irradiance_, out);
  ctx_.launch(reIrradiance_, copyRange(), prefix_ + ": re-interleave");
}

}  // namespace gi
