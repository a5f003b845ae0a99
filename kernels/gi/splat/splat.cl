// Splatting indirect illumination (Dachsbacher & Stamminger 2006) in compute form, as tiled
// light culling (ALGORITHMS.md §2.4). No visibility unless compiled with GI_VPL_VISIBILITY
// (one shadow ray per pixel–VPL pair, kernels/gi/vpl/vpl_visibility.h).
//
// A VPL's influence radius r is where E_p falls below ε × its value at d_min for the brightest
// receiver orientation: Φ/(π d²) < ε·Φ/(π d_min²)  ⇔  d² > d_min²/ε. Pairs farther apart are cut;
// all nearer pairs are evaluated exactly as in the all-pairs gather (kernels/gi/vpl/vpl_gather.cl).
//   splat_bounds  one work-item per VPL: screen-space tile rectangle of its influence sphere
//                 (the 8 corners of the sphere's bounding box projected; a corner behind the eye
//                 -> whole screen; zero flux -> empty);
//   splat_bin     one work-item per (tile, VPL set): the set's VPLs whose rectangle covers the
//                 tile, in index order (deterministic, no atomics);
//   splat_shade   GI_VW pixels of one pixel class in a tile row per work-item, each VPL of the
//                 (tile, set) list broadcast.
// Interleaved (n×m sets, ALGORITHMS.md §2.3): tiles are 16n × 16 pixels, and a work-item's lanes
// are the pixels of one class c = (x mod n) + n·(y mod m) of its tile row (x = x_c + n·lane), so
// it evaluates only set c's VPLs: n·m times fewer pairs than un-interleaved, as the seed's
// per-sub-buffer splatting. Not interleaved: n = m = 1, one set, 16 × 16 tiles.
#include "common/math.h"
#include "common/shared_types.h"
#include "common/vector_width.h"
#include "gi/vpl/vpl_visibility.h"

#define SPLAT_TILE 16

#if GI_VW == 16
#define GATHER(p, i) (float16)((p)[(i).s0], (p)[(i).s1], (p)[(i).s2], (p)[(i).s3], (p)[(i).s4], (p)[(i).s5], \
                               (p)[(i).s6], (p)[(i).s7], (p)[(i).s8], (p)[(i).s9], (p)[(i).sa], (p)[(i).sb], \
                               (p)[(i).sc], (p)[(i).sd], (p)[(i).se], (p)[(i).sf])
#elif GI_VW == 8
#define GATHER(p, i) (float8)((p)[(i).s0], (p)[(i).s1], (p)[(i).s2], (p)[(i).s3], (p)[(i).s4], (p)[(i).s5], \
                              (p)[(i).s6], (p)[(i).s7])
#else
#define GATHER(p, i) ((p)[i])
#endif

kernel void splat_bounds(GiView camera, global const float4* vpls, int count, float epsilon, int tileWidth,
                         int tilesX, int tilesY, global int4* rects) {
  int k = get_global_id(0);
  if (k >= count) return;
  float4 a = vpls[3 * k];
  float4 f = vpls[3 * k + 2];
  if (!(f.x > 0.0f || f.y > 0.0f || f.z > 0.0f)) {
    rects[k] = (int4)(1, 1, 0, 0);  // empty
    return;
  }
  float r = sqrt(a.w / epsilon);
  float x0 = GI_INF, y0 = GI_INF, x1 = -GI_INF, y1 = -GI_INF;
  bool behind = false;
  for (int c = 0; c < 8; ++c) {
    float3 p = a.xyz + (float3)((c & 1) ? r : -r, (c & 2) ? r : -r, (c & 4) ? r : -r);
    float4 h = mat4_mul(camera.view_proj, (float4)(p, 1.0f));
    if (h.w <= 1e-6f) {
      behind = true;
      break;
    }
    float sx = (h.x / h.w * 0.5f + 0.5f) * (float)camera.width, sy = (0.5f - h.y / h.w * 0.5f) * (float)camera.height;
    x0 = fmin(x0, sx);
    x1 = fmax(x1, sx);
    y0 = fmin(y0, sy);
    y1 = fmax(y1, sy);
  }
  if (behind) {
    rects[k] = (int4)(0, 0, tilesX - 1, tilesY - 1);
    return;
  }
  int tx0 = (int)floor(clamp(x0, -1.0f, (float)camera.width + 1.0f)) / tileWidth;
  int ty0 = (int)floor(clamp(y0, -1.0f, (float)camera.height + 1.0f)) / SPLAT_TILE;
  int tx1 = (int)floor(clamp(x1, -1.0f, (float)camera.width + 1.0f)) / tileWidth;
  int ty1 = (int)floor(clamp(y1, -1.0f, (float)camera.height + 1.0f)) / SPLAT_TILE;
  if (x1 < 0.0f || y1 < 0.0f || x0 > (float)camera.width || y0 > (float)camera.height) {
    rects[k] = (int4)(1, 1, 0, 0);
    return;
  }
  rects[k] = (int4)(max(tx0, 0), max(ty0, 0), min(tx1, tilesX - 1), min(ty1, tilesY - 1));
}

// VPL k belongs to set k mod sets ("stride", ordering 0) or ⌊k / perSet⌋ ("contiguous", 1);
// perSet = ⌈count / sets⌉ is also each (tile, set) list's capacity.
kernel void splat_bin(global const int4* rects, int count, int tilesX, int tilesY, int sets, int ordering,
                      int perSet, global int* lists, global int* counts) {
  int ts = get_global_id(0);
  if (ts >= tilesX * tilesY * sets) return;
  int t = ts / sets, c = ts % sets;
  int tx = t % tilesX, ty = t / tilesX;
  global int* list = lists + (size_t)ts * perSet;
  int first = ordering == 0 ? c : c * perSet, step = ordering == 0 ? sets : 1;
  int end = ordering == 0 ? count : min(count, (c + 1) * perSet);
  int n = 0;
  for (int k = first; k < end; k += step) {
    int4 r = rects[k];
    if (tx >= r.x && tx <= r.z && ty >= r.y && ty <= r.w) list[n++] = k;
  }
  counts[ts] = n;
}

// Interleaved (n·m > 1): the output is irradiance E × n·m (the set's weight; for the
// discontinuity filter) instead of L = ρ/π·E. Work-item gx of row y: class column cx = gx mod n,
// lane chunk and tile from the rest; lane l is pixel x = tile·16n + cx + n·(chunk·GI_VW + l).
kernel void splat_shade(int width, int height, int tilesX, global const float* gPosition, global const float* gNormal,
                        global const float4* albedo, global const float4* vpls, float epsilon,
                        global const int* lists, global const int* counts, int n, int m, int perSet,
                        global float4* out GI_VPL_VISIBILITY_PARAMS) {
  GI_VPL_VISIBILITY_BEGIN
  int gx = get_global_id(0), y = get_global_id(1);
  const int chunks = SPLAT_TILE / GI_VW;
  int cx = gx % n, chunk = (gx / n) % chunks, tx = gx / (n * chunks);
  int xFirst = tx * SPLAT_TILE * n + cx + n * chunk * GI_VW;
  if (xFirst >= width || y >= height) return;
  int sets = n * m, set = cx + n * (y % m);
  int tileSet = ((y / SPLAT_TILE) * tilesX + tx) * sets + set;
  intV xs = xFirst + n * GI_LANES;
  intV x = min(xs, width - 1);
  intV p4 = (y * width + x) * 4;
  floatV px = GATHER(gPosition, p4), py = GATHER(gPosition, p4 + 1), pz = GATHER(gPosition, p4 + 2),
         pw = GATHER(gPosition, p4 + 3);
  floatV nx = GATHER(gNormal, p4), ny = GATHER(gNormal, p4 + 1), nz = GATHER(gNormal, p4 + 2);
  floatV er = (floatV)(0.0f), eg = (floatV)(0.0f), eb = (floatV)(0.0f);
  global const int* list = lists + (size_t)tileSet * perSet;
  int listed = counts[tileSet];
  for (int j = 0; j < listed; ++j) {
    int k = list[j];
    float4 a = vpls[3 * k], b = vpls[3 * k + 1], f = vpls[3 * k + 2];
    floatV vx = a.x - px, vy = a.y - py, vz = a.z - pz;
    floatV d2 = vx * vx + vy * vy + vz * vz;
    floatV cp = -(b.x * vx + b.y * vy + b.z * vz);
    floatV cr = nx * vx + ny * vy + nz * vz;
    floatV g = max(cp, 0.0f) * max(cr, 0.0f) / (max(d2, 1e-20f) * max(d2, a.w));
#if GI_VW == 1
    g = d2 * epsilon < a.w ? g : 0.0f;
#else
    g = select((floatV)(0.0f), g, d2 * epsilon < a.w);
#endif
#ifdef GI_VPL_VISIBILITY
    g = GI_VPL_VISIBLE(px, py, pz, a.xyz, GI_SEL((floatV)(0.0f), g, pw > 0.0f));  // no rays for background lanes
#endif
    er += f.x * g;
    eg += f.y * g;
    eb += f.z * g;
  }
  float scale = (float)sets * GI_INV_PI;
#if GI_VW == 1
  {
    size_t i = (size_t)y * width + xFirst;
    float3 e = pw > 0.0f ? (float3)(er, eg, eb) * scale : (float3)(0.0f);
    out[i] = sets > 1 ? (float4)(e, 0.0f) : (float4)(albedo[i].xyz * e * GI_INV_PI, 0.0f);
  }
#else
  float vals[4][GI_VW];
  vstoreV(er, 0, vals[0]);
  vstoreV(eg, 0, vals[1]);
  vstoreV(eb, 0, vals[2]);
  vstoreV(pw, 0, vals[3]);
  for (int l = 0; l < GI_VW; ++l) {
    if (xFirst + n * l >= width) break;
    size_t i = (size_t)y * width + xFirst + n * l;
    float3 e = vals[3][l] > 0.0f ? (float3)(vals[0][l], vals[1][l], vals[2][l]) * scale : (float3)(0.0f);
    out[i] = sets > 1 ? (float4)(e, 0.0f) : (float4)(albedo[i].xyz * e * GI_INV_PI, 0.0f);
  }
#endif
}
