#include "scene/device_scene.h"

namespace gi {

DeviceScene::DeviceScene(cl::Context& ctx, const Scene& s) {
  triangleCount = static_cast<uint32_t>(s.triangles.size());
  vertexCount = static_cast<uint32_t>(s.positions.size());
  lightCount = static_cast<uint32_t>(s.lights.size());

  std::vector<glm::vec4> pos(vertexCount), nrm(vertexCount), tan(vertexCount);
  for (uint32_t i = 0; i < vertexCount; ++i) {
    pos[i] = glm::vec4(s.positions[i], 1.0f);
    nrm[i] = glm::vec4(i < s.normals.size() ? s.normals[i] : glm::vec3(0, 0, 1), 0.0f);
    tan[i] = i < s.tangents.size() ? s.tangents[i] : glm::vec4(0.0f);
  }
  std::vector<glm::vec2> uv(vertexCount, glm::vec2(0.0f));
  for (uint32_t i = 0; i < vertexCount && i < s.uvs.size(); ++i) uv[i] = s.uvs[i];
  std::vector<glm::uvec4> tris(triangleCount);
  for (uint32_t t = 0; t < triangleCount; ++t) tris[t] = glm::uvec4(s.triangles[t], s.triangleMaterial[t]);

  std::vector<GiTexture> texTable;
  std::vector<uint8_t> texelData;
  for (const Texture& t : s.textures) {
    GiTexture g{};
    g.offset = static_cast<uint32_t>(texelData.size() / 4);
    g.width = t.width;
    g.height = t.height;
    g.levels = t.levels;
    g.srgb = t.srgb ? 1 : 0;
    texTable.push_back(g);
    texelData.insert(texelData.end(), t.rgba8.begin(), t.rgba8.end());
  }
  if (texelData.empty()) texelData.assign(4, 0);

  positions = ctx.upload(pos, "vertex positions");
  normals = ctx.upload(nrm, "vertex normals");
  tangents = ctx.upload(tan, "vertex tangents");
  uvs = ctx.upload(uv, "vertex texture coordinates");
  triangles = ctx.upload(tris, "triangles");
  triangleInstance = ctx.upload(s.triangleInstance, "triangle instance ids");
  materials = ctx.upload(s.materials, "materials");
  textures = ctx.upload(texTable, "texture table");
  texels = ctx.upload(texelData, "texture atlas");
  lights = ctx.upload(s.lights, "lights");
  for (const cl::Buffer* b : {&positions, &normals, &tangents, &uvs, &triangles, &triangleInstance, &materials,
                              &textures, &texels, &lights})
    bytes += b->bytes();
}

}  // namespace gi
