// The scene in device memory: the buffers every kernel that touches geometry or materials reads.
// Layout (all read-only):
//   positions, normals, tangents : float4 per vertex (w = 1, 0, handedness)
//   uvs                          : float2 per vertex
//   triangles                    : uint4 per triangle (i0, i1, i2, material index)
//   triangleInstance             : uint per triangle
//   materials / textures / lights: GiMaterial / GiTexture / GiLight (kernels/common/shared_types.h)
//   texels                       : uchar4, every texture's mip chain (see GiTexture)
#pragma once
#include "cl/runtime.h"
#include "scene/scene.h"

namespace gi {

struct DeviceScene {
  DeviceScene(cl::Context& ctx, const Scene& scene);

  cl::Buffer positions, normals, tangents, uvs;
  cl::Buffer triangles, triangleInstance;
  cl::Buffer materials, textures, texels, lights;
  uint32_t triangleCount = 0, vertexCount = 0, lightCount = 0;
  uint64_t bytes = 0;  // device memory used
};

}  // namespace gi
