// Kernels used only by the OpenCL-layer tests.
#include "common/shared_types.h"

kernel void add_one(global float* data, uint n) {
  uint i = get_global_id(0);
  if (i < n) data[i] += 1.0f;
}

kernel void material_roundtrip(global const GiMaterial* m, global float* out) {
  out[0] = m->base_color[2];
  out[1] = m->roughness;
  out[2] = (float)m->normal_tex;
  out[3] = (float)m->double_sided;
}
