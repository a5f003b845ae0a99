// The all-pairs VPL gather with the receiver's full BRDF (`vpl.specular=true`; docs/techniques/vpl.md,
// "Specular receivers"). ALGORITHMS.md §2 gathers diffuse light only, L = ρ/π · Σ E_p
// (vpl_gather.cl); the engine's BRDF (common/brdf.h) also has the GGX lobe, and the direct pass and
// the path tracer evaluate it. This pass writes, per camera pixel x with shading normal n, view
// direction ω_o, albedo ρ, specular F0 and roughness,
//   L(x) = Σ_p (ρ/π + f_spec(ω_o, ω_i)) · Φ_p/π · max(0, n_p·(−ω_i)) · max(0, n·ω_i) / max(d², d_min²)
// with ω_i = (x_p − x)/d: the VPL's radiant intensity Φ_p cos θ_p / π times the cosine at x over
// the clamped squared distance — the diffuse term is vpl_gather's, term for term — and f_spec =
// brdf_specular() written lane-wise (ggx_D · smith_visibility · fresnel_schlick, the direct pass's
// form; zero where the viewer is below the shading normal). VPLs stay diffuse emitters. With
// GI_VPL_VISIBILITY each facing pair is tested by one shadow ray, shared by both terms.
//
// One work-item = GI_VW consecutive pixels (row-major), each VPL broadcast to all lanes.
#include "common/brdf.h"
#include "common/math.h"
#include "common/vector_width.h"
#include "gi/vpl/vpl_visibility.h"

kernel void vpl_brdf_gather(int pixels, GiView camera, global const float4* position,
                            global const float4* normal, global const float4* albedo, global const float4* specular,
                            global const float4* vpls, int count, global float4* radiance GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  int first = (int)get_global_id(0) * GI_VW;
  if (first >= pixels) return;
  int valid = min(GI_VW, pixels - first);
  float lx[GI_VW], ly[GI_VW], lz[GI_VW], mx[GI_VW], my[GI_VW], mz[GI_VW], sr[GI_VW], sg[GI_VW], sb[GI_VW],
      rough[GI_VW], on[GI_VW];
  for (int l = 0; l < GI_VW; ++l) {
    int i = first + min(l, valid - 1);
    float4 p = position[i], n = normal[i], s = specular[i];
    // Off the surface (background, padding lanes): zero normal, nothing gathered (as vpl_gather).
    on[l] = l < valid && p.w > 0.0f ? 1.0f : 0.0f;
    lx[l] = p.x; ly[l] = p.y; lz[l] = p.z;
    mx[l] = n.x * on[l]; my[l] = n.y * on[l]; mz[l] = n.z * on[l];
    sr[l] = s.x; sg[l] = s.y; sb[l] = s.z; rough[l] = s.w;
  }
  floatV px = vloadV(0, lx), py = vloadV(0, ly), pz = vloadV(0, lz);
  floatV nx = vloadV(0, mx), ny = vloadV(0, my), nz = vloadV(0, mz);
  floatV f0r = vloadV(0, sr), f0g = vloadV(0, sg), f0b = vloadV(0, sb);
  floatV a = fmax(vloadV(0, rough) * vloadV(0, rough), GI_MIN_GGX_ALPHA);
  floatV a2 = a * a;
  // ω_o, towards the viewer (as the direct pass: one direction for an orthographic camera).
  floatV ox, oy, oz;
  if (camera.orthographic) {
    float3 w = -normalize(mat4_mul(camera.inv_view_proj, (float4)(0.0f, 0.0f, 1.0f, 0.0f)).xyz);
    ox = (floatV)(w.x); oy = (floatV)(w.y); oz = (floatV)(w.z);
  } else {
    ox = camera.eye[0] - px; oy = camera.eye[1] - py; oz = camera.eye[2] - pz;
    floatV oinv = rsqrt(fmax(ox * ox + oy * oy + oz * oz, 1e-20f));
    ox *= oinv; oy *= oinv; oz *= oinv;
  }
  floatV nv = nx * ox + ny * oy + nz * oz;
  // The specular lobe needs the viewer above the shading normal (brdf_eval()).
  floatV specOn = GI_SEL((floatV)(0.0f), vloadV(0, on), nv > 0.0f);
  floatV er = (floatV)(0.0f), eg = (floatV)(0.0f), eb = (floatV)(0.0f);  // Σ Φ_p · geometry (π E)
  floatV lr = (floatV)(0.0f), lg = (floatV)(0.0f), lb = (floatV)(0.0f);  // Σ Φ_p · geometry · f_spec
  for (int k = 0; k < count; ++k) {
    float4 va = vpls[3 * k], vb = vpls[3 * k + 1], vf = vpls[3 * k + 2];
    floatV vx = va.x - px, vy = va.y - py, vz = va.z - pz;  // receiver -> VPL
    floatV d2 = vx * vx + vy * vy + vz * vz;
    floatV cp = -(vb.x * vx + vb.y * vy + vb.z * vz);  // n_p·(x − x_p) = d cos θ_p
    floatV cr = nx * vx + ny * vy + nz * vz;           // n·(x_p − x) = d cos θ
    floatV w = max(cp, 0.0f) * max(cr, 0.0f) / (max(d2, 1e-20f) * max(d2, va.w));  // vpl_gather's term
    w = GI_VPL_VISIBLE(px, py, pz, va.xyz, w);
    er += vf.x * w;
    eg += vf.y * w;
    eb += vf.z * w;
    floatV ws = w * specOn;
    if (!GI_ANY(ws > 0.0f)) continue;  // no lane faces this VPL (or sees its lobe): skip the GGX terms
    d2 = fmax(d2, 1e-20f);
    floatV dinv = rsqrt(d2);
    floatV ix = vx * dinv, iy = vy * dinv, iz = vz * dinv;
    floatV hx = ox + ix, hy = oy + iy, hz = oz + iz;
    floatV hinv = rsqrt(fmax(hx * hx + hy * hy + hz * hz, 1e-20f));
    hx *= hinv; hy *= hinv; hz *= hinv;
    floatV nh = fmax(nx * hx + ny * hy + nz * hz, 0.0f);
    floatV dd = nh * nh * (a2 - 1.0f) + 1.0f;
    floatV D = a2 / (GI_PI * dd * dd);
    floatV nl = fmax(cr * dinv, 0.0f);
    floatV gv = nl * sqrt(nv * nv * (1.0f - a2) + a2);
    floatV gl = nv * sqrt(nl * nl * (1.0f - a2) + a2);
    floatV V = 0.5f / fmax(gv + gl, 1e-12f);
    floatV m = clamp(1.0f - (ix * hx + iy * hy + iz * hz), 0.0f, 1.0f);
    floatV m2 = m * m, m5 = m2 * m2 * m;
    floatV dvw = D * V * ws;
    lr += vf.x * dvw * (f0r + (1.0f - f0r) * m5);
    lg += vf.y * dvw * (f0g + (1.0f - f0g) * m5);
    lb += vf.z * dvw * (f0b + (1.0f - f0b) * m5);
  }
  float rr[GI_VW], rg[GI_VW], rb[GI_VW];
  vstoreV((er * GI_INV_PI) * GI_INV_PI, 0, rr);  // ρ/π · E with E = Σ Φ_p · geometry / π, as vpl_gather
  vstoreV((eg * GI_INV_PI) * GI_INV_PI, 0, rg);
  vstoreV((eb * GI_INV_PI) * GI_INV_PI, 0, rb);
  float sr2[GI_VW], sg2[GI_VW], sb2[GI_VW];
  vstoreV(lr * GI_INV_PI, 0, sr2);
  vstoreV(lg * GI_INV_PI, 0, sg2);
  vstoreV(lb * GI_INV_PI, 0, sb2);
  for (int l = 0; l < valid; ++l) {
    float3 rho = albedo[first + l].xyz;
    radiance[first + l] = (float4)(rho.x * rr[l] + sr2[l], rho.y * rg[l] + sg2[l], rho.z * rb[l] + sb2[l], 0.0f);
  }
}
