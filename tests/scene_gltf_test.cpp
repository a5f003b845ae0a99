// glTF loader tests on small files written by the tests themselves (scene_gltf_writer.h):
// transforms and instancing, attribute and index formats, sparse accessors, generated normals and
// tangents, materials, lights, cameras, and the errors and warnings for bad input.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

#include "image/image.h"
#include "scene/gltf_loader.h"
#include "scene_gltf_writer.h"
#include "test_support.h"
#include "util/error.h"
#include "util/file_io.h"

namespace gi {
namespace {

using nlohmann::json;
using test::GltfWriter;

template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a gi::Error";
  return "";
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// The triangle (0,0,0), (1,0,0), (0,1,0), counter-clockwise seen from +z, normals +z.
int triangleMesh(GltfWriter& w, const std::string& name = "tri", int material = -1) {
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  int nrm = w.addAccessor(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}, test::kGltfFloat, "VEC3");
  return w.addMesh(name, {{"POSITION", pos}, {"NORMAL", nrm}}, w.addIndices({0, 1, 2}), material);
}

uint32_t instanceNamed(const Scene& s, const std::string& name) {
  for (size_t i = 0; i < s.instanceNames.size(); ++i)
    if (s.instanceNames[i] == name) return uint32_t(i);
  ADD_FAILURE() << "no instance " << name;
  return 0;
}

// Corner k of the first triangle of the named instance.
glm::vec3 corner(const Scene& s, const std::string& instance, int k) {
  uint32_t id = instanceNamed(s, instance);
  for (size_t t = 0; t < s.triangles.size(); ++t)
    if (s.triangleInstance[t] == id) return s.positions[s.triangles[t][k]];
  ADD_FAILURE() << "instance " << instance << " has no triangles";
  return glm::vec3(0.0f);
}

glm::vec3 faceNormal(const Scene& s, size_t t) {
  const glm::uvec3& tri = s.triangles[t];
  return glm::normalize(glm::cross(s.positions[tri[1]] - s.positions[tri[0]], s.positions[tri[2]] - s.positions[tri[0]]));
}

TEST(SceneGltf, NodeTransformsTrsMatrixAndNesting) {
  auto dir = test::tempDir("scene_gltf_transforms");
  GltfWriter w;
  int mesh = triangleMesh(w);
  const float h = std::sqrt(0.5f);  // quaternion of 90° about +z: (0, 0, sin 45°, cos 45°)
  w.addNode({{"name", "translated"}, {"mesh", mesh}, {"translation", {1, 2, 3}}});
  w.addNode({{"name", "rotated"}, {"mesh", mesh}, {"rotation", {0, 0, h, h}}});
  w.addNode({{"name", "scaled"}, {"mesh", mesh}, {"scale", {2, 3, 4}}});
  w.addNode({{"name", "trs"}, {"mesh", mesh}, {"translation", {1, 0, 0}}, {"rotation", {0, 0, h, h}}, {"scale", {2, 2, 2}}});
  w.addNode({{"name", "matrix"}, {"mesh", mesh}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 6, 7, 1}}});
  int child = w.addNode({{"name", "child"}, {"mesh", mesh}, {"scale", {2, 2, 2}}}, false);
  int middle = w.addNode({{"name", "middle"}, {"rotation", {0, 0, h, h}}, {"children", {child}}}, false);
  w.addNode({{"name", "parent"}, {"translation", {10, 0, 0}}, {"children", {middle}}});
  Scene s = loadGltfScene(w.write(dir, "transforms"));

  ASSERT_EQ(s.triangleCount(), 6u);
  expectNear(corner(s, "translated", 1), {2, 2, 3});
  expectNear(corner(s, "rotated", 1), {0, 1, 0});
  expectNear(corner(s, "rotated", 2), {-1, 0, 0});
  expectNear(corner(s, "scaled", 1), {2, 0, 0});
  expectNear(corner(s, "scaled", 2), {0, 3, 0});
  expectNear(corner(s, "trs", 1), {1, 2, 0});  // scale, then rotate, then translate
  expectNear(corner(s, "matrix", 0), {5, 6, 7});
  expectNear(corner(s, "child", 1), {10, 2, 0});  // parent · middle · child
  for (size_t v = 0; v < s.normals.size(); ++v) expectNear(s.normals[v], {0, 0, 1});
}

TEST(SceneGltf, NormalsUseInverseTransposeAndMirrorsKeepFrontFaces) {
  auto dir = test::tempDir("scene_gltf_normals");
  GltfWriter w;
  const float n = 1.0f / std::sqrt(3.0f);
  int pos = w.addPositions({1, 0, 0, 0, 1, 0, 0, 0, 1});
  int nrm = w.addAccessor(std::vector<float>{n, n, n, n, n, n, n, n, n}, test::kGltfFloat, "VEC3");
  int mesh = w.addMesh("slope", {{"POSITION", pos}, {"NORMAL", nrm}}, w.addIndices({0, 1, 2}));
  w.addNode({{"name", "stretched"}, {"mesh", mesh}, {"scale", {2, 1, 1}}});
  w.addNode({{"name", "mirrored"}, {"mesh", mesh}, {"scale", {-1, 1, 1}}});
  Scene s = loadGltfScene(w.write(dir, "normals"));
  ASSERT_EQ(s.triangleCount(), 2u);
  for (size_t t = 0; t < 2; ++t) {
    glm::vec3 geometric = faceNormal(s, t);
    for (int k = 0; k < 3; ++k) expectNear(s.normals[s.triangles[t][k]], geometric);
  }
  expectNear(s.normals[s.triangles[instanceNamed(s, "stretched")][0]], glm::normalize(glm::vec3(0.5f, 1, 1)));
}

TEST(SceneGltf, OneMeshUsedByTwoNodesGivesTwoInstances) {
  auto dir = test::tempDir("scene_gltf_instancing");
  GltfWriter w;
  int mesh = triangleMesh(w, "shared");
  w.addNode({{"name", "left"}, {"mesh", mesh}, {"translation", {-2, 0, 0}}});
  w.addNode({{"name", "right"}, {"mesh", mesh}, {"translation", {2, 0, 0}}});
  Scene s = loadGltfScene(w.write(dir, "instancing"));
  ASSERT_EQ(s.triangleCount(), 2u);
  EXPECT_EQ(s.positions.size(), 6u);
  EXPECT_NE(s.triangleInstance[0], s.triangleInstance[1]);
  EXPECT_EQ(s.instanceNames.size(), 2u);
  expectNear(corner(s, "left", 0), {-2, 0, 0});
  expectNear(corner(s, "right", 0), {2, 0, 0});
}

TEST(SceneGltf, MissingNormalsGiveFlatNormals) {
  auto dir = test::tempDir("scene_gltf_flat");
  GltfWriter w;
  // A folded quad (a "tent"): two triangles sharing the edge (0,0,0)-(0,1,0), one tilted.
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 1});
  int mesh = w.addMesh("tent", {{"POSITION", pos}}, w.addIndices({0, 1, 2, 0, 2, 3}));
  w.addNode({{"mesh", mesh}});
  Scene s = loadGltfScene(w.write(dir, "flat"));
  ASSERT_EQ(s.triangleCount(), 2u);
  EXPECT_EQ(s.positions.size(), 6u) << "flat shading un-welds the shared vertices";
  for (size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k) expectNear(s.normals[s.triangles[t][k]], faceNormal(s, t));
  expectNear(s.normals[s.triangles[0][0]], {0, 0, 1});
  expectNear(s.normals[s.triangles[1][0]], glm::normalize(glm::vec3(1, 0, 1)));
}

// A 2×2 quad in the z = 0 plane facing +z with a normal map, with the given UVs at the corners
// (-1,1), (1,1), (1,-1), (-1,-1).
std::filesystem::path normalMappedQuad(const std::filesystem::path& dir, const std::string& name,
                                       const std::vector<float>& uvs, const json& nodeExtra = json::object()) {
  writeImage(dir / "flat_normal.png", Image(4, 4, 3, 0.5f));
  GltfWriter w;
  int pos = w.addPositions({-1, 1, 0, 1, 1, 0, 1, -1, 0, -1, -1, 0});
  int nrm = w.addAccessor(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, test::kGltfFloat, "VEC3");
  int uv = w.addAccessor(uvs, test::kGltfFloat, "VEC2");
  w.doc["images"] = {{{"uri", "flat_normal.png"}}};
  w.doc["textures"] = {{{"source", 0}}};
  int mat = w.addMaterial({{"name", "bumpy"}, {"normalTexture", {{"index", 0}, {"scale", 0.5}}}});
  int mesh = w.addMesh("quad", {{"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}}, w.addIndices({0, 3, 2, 0, 2, 1}), mat);
  json node = {{"mesh", mesh}};
  node.update(nodeExtra);
  w.addNode(node);
  return w.write(dir, name);
}

void expectTangents(const Scene& s, const glm::vec3& expectedTangent, float expectedW) {
  ASSERT_EQ(s.tangents.size(), s.positions.size());
  for (size_t v = 0; v < s.tangents.size(); ++v) {
    glm::vec3 t(s.tangents[v]);
    EXPECT_NEAR(glm::length(t), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(t, s.normals[v]), 0.0f, 1e-5f);
    expectNear(t, expectedTangent);
    EXPECT_EQ(s.tangents[v].w, expectedW);
    // The glTF bitangent cross(n, t)·w points along -v, here always +y (v runs down the quad).
    expectNear(glm::cross(s.normals[v], t) * s.tangents[v].w, {0, 1, 0});
  }
}

TEST(SceneGltf, TangentsGeneratedForNormalMapsWithHandedness) {
  auto dir = test::tempDir("scene_gltf_tangents");
  // u along +x, v along -y: the ordinary (right-handed) layout.
  Scene plain = loadGltfScene(normalMappedQuad(dir, "plain", {0, 0, 1, 0, 1, 1, 0, 1}));
  expectTangents(plain, {1, 0, 0}, 1.0f);
  EXPECT_EQ(plain.materials[0].normal_scale, 0.5f);
  EXPECT_FALSE(plain.textures[plain.materials[0].normal_tex].srgb);
  // u mirrored (along -x): the tangent turns round and the frame becomes left-handed.
  Scene mirroredUv = loadGltfScene(normalMappedQuad(dir, "mirrored_uv", {1, 0, 0, 0, 0, 1, 1, 1}));
  expectTangents(mirroredUv, {-1, 0, 0}, -1.0f);
  // A mirroring node transform flips x: tangent (-1,0,0), and the handedness flips with it.
  Scene mirroredNode = loadGltfScene(normalMappedQuad(dir, "mirrored_node", {0, 0, 1, 0, 1, 1, 0, 1}, {{"scale", {-1, 1, 1}}}));
  expectTangents(mirroredNode, {-1, 0, 0}, -1.0f);
}

TEST(SceneGltf, NoTangentsWithoutNormalMap) {
  auto dir = test::tempDir("scene_gltf_no_tangents");
  GltfWriter w;
  w.addNode({{"mesh", triangleMesh(w)}});
  Scene s = loadGltfScene(w.write(dir, "plain"));
  ASSERT_EQ(s.tangents.size(), s.positions.size());
  for (const glm::vec4& t : s.tangents) EXPECT_EQ(t, glm::vec4(0.0f));
}

TEST(SceneGltf, SparseAccessorsAreApplied) {
  auto dir = test::tempDir("scene_gltf_sparse");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  std::vector<uint16_t> which = {2};
  std::vector<float> replacement = {0, 5, 0};
  w.doc["accessors"][pos]["sparse"] = {{"count", 1},
                                       {"indices", {{"bufferView", w.addView(which.data(), 2)}, {"componentType", test::kGltfUShort}}},
                                       {"values", {{"bufferView", w.addView(replacement.data(), 12)}}}};
  // TEXCOORD_0 with no bufferView at all: zeros, then vertex 1 set by the sparse values.
  std::vector<uint8_t> uvWhich = {1};
  std::vector<float> uvValue = {0.25f, 0.75f};
  w.doc["accessors"].push_back({{"componentType", test::kGltfFloat}, {"count", 3}, {"type", "VEC2"},
                                {"sparse", {{"count", 1},
                                            {"indices", {{"bufferView", w.addView(uvWhich.data(), 1)}, {"componentType", test::kGltfUByte}}},
                                            {"values", {{"bufferView", w.addView(uvValue.data(), 8)}}}}}});
  int uv = int(w.doc["accessors"].size() - 1);
  int mesh = w.addMesh("sparse", {{"POSITION", pos}, {"TEXCOORD_0", uv}}, w.addIndices({0, 1, 2}));
  w.addNode({{"mesh", mesh}});
  Scene s = loadGltfScene(w.write(dir, "sparse"));
  ASSERT_EQ(s.triangleCount(), 1u);
  expectNear(s.positions[s.triangles[0][2]], {0, 5, 0});
  expectNear(s.positions[s.triangles[0][1]], {1, 0, 0});
  EXPECT_EQ(s.uvs[s.triangles[0][0]], glm::vec2(0.0f));
  EXPECT_EQ(s.uvs[s.triangles[0][1]], glm::vec2(0.25f, 0.75f));
}

TEST(SceneGltf, IndexComponentTypesAllGiveTheSameTriangles) {
  auto dir = test::tempDir("scene_gltf_indices");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
  int i8 = w.addAccessor(std::vector<uint8_t>{0, 1, 2, 2, 1, 3}, test::kGltfUByte, "SCALAR");
  int i16 = w.addAccessor(std::vector<uint16_t>{0, 1, 2, 2, 1, 3}, test::kGltfUShort, "SCALAR");
  int i32 = w.addIndices({0, 1, 2, 2, 1, 3});
  for (auto [name, acc] : {std::pair{"u8", i8}, std::pair{"u16", i16}, std::pair{"u32", i32}})
    w.addNode({{"name", name}, {"mesh", w.addMesh(name, {{"POSITION", pos}}, acc)}});
  Scene s = loadGltfScene(w.write(dir, "indices"));
  ASSERT_EQ(s.triangleCount(), 6u);
  for (const char* name : {"u16", "u32"})
    for (int k = 0; k < 3; ++k) EXPECT_EQ(corner(s, name, k), corner(s, "u8", k)) << name;
}

TEST(SceneGltf, NormalizedIntegerTexcoords) {
  auto dir = test::tempDir("scene_gltf_uv");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  int uv8 = w.addAccessor(std::vector<uint8_t>{0, 0, 255, 0, 51, 255}, test::kGltfUByte, "VEC2", true);
  int uv16 = w.addAccessor(std::vector<uint16_t>{0, 0, 65535, 0, 13107, 65535}, test::kGltfUShort, "VEC2", true);
  w.addNode({{"name", "u8"}, {"mesh", w.addMesh("u8", {{"POSITION", pos}, {"TEXCOORD_0", uv8}})}});
  w.addNode({{"name", "u16"}, {"mesh", w.addMesh("u16", {{"POSITION", pos}, {"TEXCOORD_0", uv16}})}});
  Scene s = loadGltfScene(w.write(dir, "uv"));
  for (const char* name : {"u8", "u16"}) {
    uint32_t id = instanceNamed(s, name);
    const glm::uvec3& t = s.triangles[id];
    EXPECT_EQ(s.uvs[t[0]], glm::vec2(0, 0)) << name;
    EXPECT_EQ(s.uvs[t[1]], glm::vec2(1, 0)) << name;
    EXPECT_NEAR(s.uvs[t[2]].x, 0.2f, 1e-6f) << name;
    EXPECT_EQ(s.uvs[t[2]].y, 1.0f) << name;
  }
}

TEST(SceneGltf, TriangleStripsAndFansBecomeFrontFacingTriangles) {
  auto dir = test::tempDir("scene_gltf_strips");
  GltfWriter w;
  // Strip order: (0,0) (1,0) (0,1) (1,1) -> two triangles of the unit square, both facing +z.
  int strip = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
  // Fan around (0,0): (0,0) (1,0) (1,1) (0,1).
  int fan = w.addPositions({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  w.addNode({{"name", "strip"}, {"mesh", w.addMesh("strip", {{"POSITION", strip}}, -1, -1, 5)}});
  w.addNode({{"name", "fan"}, {"mesh", w.addMesh("fan", {{"POSITION", fan}}, -1, -1, 6)}});
  Scene s = loadGltfScene(w.write(dir, "strips"));
  ASSERT_EQ(s.triangleCount(), 4u);
  for (size_t t = 0; t < 4; ++t) expectNear(faceNormal(s, t), {0, 0, 1});
}

TEST(SceneGltf, PointsAndLinesAreSkippedWithAWarning) {
  auto dir = test::tempDir("scene_gltf_lines");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0});
  w.addNode({{"mesh", w.addMesh("wire", {{"POSITION", pos}}, -1, -1, 1)}});
  w.addNode({{"mesh", triangleMesh(w)}});
  testing::internal::CaptureStderr();
  Scene s = loadGltfScene(w.write(dir, "lines"));
  std::string warnings = testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.triangleCount(), 1u);
  EXPECT_NE(warnings.find("mesh 'wire' primitive 0"), std::string::npos) << warnings;
}

TEST(SceneGltf, SceneWithoutTrianglesIsAnError) {
  auto dir = test::tempDir("scene_gltf_empty");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0});
  w.addNode({{"mesh", w.addMesh("wire", {{"POSITION", pos}}, -1, -1, 1)}});
  auto file = w.write(dir, "empty");
  setWarningsEnabled(false);
  std::string message = errorOf([&] { loadGltfScene(file); });
  setWarningsEnabled(true);
  EXPECT_NE(message.find("empty.gltf"), std::string::npos) << message;
  EXPECT_NE(message.find("no triangles"), std::string::npos) << message;
}

TEST(SceneGltf, NanVerticesAndDegenerateTrianglesAreSkippedWithOneWarning) {
  auto dir = test::tempDir("scene_gltf_bad_triangles");
  GltfWriter w;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0, nan, 0, 0, 2, 0, 0});
  // good; NaN corner; repeated index; collinear (0,0,0)-(1,0,0)-(2,0,0).
  int mesh = w.addMesh("bad", {{"POSITION", pos}}, w.addIndices({0, 1, 2, 0, 3, 2, 1, 1, 2, 0, 1, 4}));
  w.addNode({{"mesh", mesh}});
  w.addNode({{"mesh", mesh}, {"translation", {0, 0, 1}}});  // instanced: still one warning
  testing::internal::CaptureStderr();
  Scene s = loadGltfScene(w.write(dir, "bad"));
  std::string warnings = testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.triangleCount(), 2u);
  EXPECT_NE(warnings.find("mesh 'bad' primitive 0: skipped 3 of 4 triangles (1 with NaN/Inf vertices, 2 degenerate)"),
            std::string::npos)
      << warnings;
  size_t lines = std::count(warnings.begin(), warnings.end(), '\n');
  EXPECT_EQ(lines, 1u) << warnings;
}

TEST(SceneGltf, MaterialsAndTextureColourSpaces) {
  auto dir = test::tempDir("scene_gltf_materials");
  Image checker(4, 2, 4, 1.0f);
  writeImage(dir / "shared.png", checker);
  GltfWriter w;
  w.doc["images"] = {{{"uri", "shared.png"}}};
  w.doc["textures"] = {{{"source", 0}}};
  w.doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
  int mat = w.addMaterial({{"name", "painted"},
                           {"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.25, 1.0, 0.75}},
                                                     {"baseColorTexture", {{"index", 0}}},
                                                     {"metallicFactor", 0.2},
                                                     {"roughnessFactor", 0.6},
                                                     {"metallicRoughnessTexture", {{"index", 0}}}}},
                           {"emissiveFactor", {1.0, 0.5, 0.25}},
                           {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}}},
                           {"alphaMode", "MASK"},
                           {"alphaCutoff", 0.3},
                           {"doubleSided", true}});
  w.addNode({{"mesh", triangleMesh(w, "painted", mat)}});
  w.addNode({{"mesh", triangleMesh(w, "plain")}, {"translation", {0, 0, -1}}});
  Scene s = loadGltfScene(w.write(dir, "materials"));

  ASSERT_EQ(s.materials.size(), 2u);
  const GiMaterial& m = s.materials[0];
  EXPECT_EQ(m.base_color[0], 0.5f);
  EXPECT_EQ(m.base_color[3], 0.75f);
  EXPECT_FLOAT_EQ(m.metallic, 0.2f);
  EXPECT_FLOAT_EQ(m.roughness, 0.6f);
  EXPECT_FLOAT_EQ(m.emissive[0], 4.0f);
  EXPECT_FLOAT_EQ(m.emissive[1], 2.0f);
  EXPECT_FLOAT_EQ(m.emissive[2], 1.0f);
  EXPECT_EQ(m.alpha_mode, GI_ALPHA_MASK);
  EXPECT_FLOAT_EQ(m.alpha_cutoff, 0.3f);
  EXPECT_EQ(m.double_sided, 1);
  EXPECT_EQ(m.normal_tex, GI_NO_TEXTURE);
  // One image used as colour and as data: two textures, decoded from the one file.
  ASSERT_EQ(s.textures.size(), 2u);
  ASSERT_NE(m.base_color_tex, m.metallic_roughness_tex);
  EXPECT_TRUE(s.textures[m.base_color_tex].srgb);
  EXPECT_FALSE(s.textures[m.metallic_roughness_tex].srgb);
  EXPECT_EQ(s.textures[m.base_color_tex].width, 4);
  EXPECT_EQ(s.textures[m.base_color_tex].levels, 3);
  // The primitive without a material gets glTF's default material.
  const GiMaterial& d = s.materials[1];
  EXPECT_EQ(d.base_color[0], 1.0f);
  EXPECT_EQ(d.metallic, 1.0f);
  EXPECT_EQ(d.roughness, 1.0f);
  EXPECT_EQ(d.base_color_tex, GI_NO_TEXTURE);
}

TEST(SceneGltf, EmissiveTrianglesGetAStandInSpotLight) {
  auto dir = test::tempDir("scene_gltf_emissive");
  GltfWriter w;
  int mat = w.addMaterial({{"emissiveFactor", {1.0, 0.5, 0.25}},
                           {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 2.0}}}}}});
  // A 2×1 emitter facing down at y = 3.
  int pos = w.addPositions({0, 3, 0, 2, 3, 0, 2, 3, 1, 0, 3, 1});
  int mesh = w.addMesh("panel", {{"POSITION", pos}}, w.addIndices({0, 1, 2, 0, 2, 3}), mat);
  w.addNode({{"name", "lamp"}, {"mesh", mesh}});
  w.addNode({{"name", "floor"}, {"mesh", triangleMesh(w)}, {"scale", {5, 5, 5}}, {"rotation", {-std::sqrt(0.5), 0, 0, std::sqrt(0.5)}}});
  Scene s = loadGltfScene(w.write(dir, "emissive"));
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lightNames[0], "emitter:lamp");
  const GiLight& l = s.lights[0];
  EXPECT_EQ(l.type, GI_LIGHT_SPOT);
  EXPECT_EQ(l.falloff, GI_SPOT_FALLOFF_COSINE);
  EXPECT_EQ(l.cos_inner, 0.0f);
  EXPECT_EQ(l.cos_outer, 0.0f);
  EXPECT_EQ(l.shadow_map, -1);
  // I0 = L·A with L = (2, 1, 0.5), A = 2.
  expectNear({l.intensity[0], l.intensity[1], l.intensity[2]}, {4, 2, 1});
  expectNear({l.direction[0], l.direction[1], l.direction[2]}, {0, -1, 0});
  EXPECT_NEAR(l.position[0], 1.0f, 1e-5f);
  EXPECT_NEAR(l.position[2], 0.5f, 1e-5f);
  EXPECT_LT(l.position[1], 3.0f);
  EXPECT_GT(l.position[1], 3.0f - 0.01f);
}

TEST(SceneGltf, KhrLightsPunctualInEngineUnits) {
  auto dir = test::tempDir("scene_gltf_lights");
  GltfWriter w;
  w.doc["extensionsUsed"] = {"KHR_lights_punctual"};
  w.doc["extensions"]["KHR_lights_punctual"]["lights"] = {
      {{"name", "sun"}, {"type", "directional"}, {"color", {1.0, 0.5, 0.25}}, {"intensity", 3.0}},
      {{"name", "bulb"}, {"type", "point"}, {"intensity", 10.0}, {"range", 5.0}},
      {{"name", "torch"}, {"type", "spot"}, {"intensity", 2.0}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.4}}}}};
  const double h = std::sqrt(0.5);  // -90° about x: the node's -Z axis points down
  auto lightExt = [](int i) { return json{{"KHR_lights_punctual", {{"light", i}}}}; };
  w.addNode({{"name", "sun node"}, {"rotation", {-h, 0, 0, h}}, {"extensions", lightExt(0)}});
  w.addNode({{"translation", {1, 2, 3}}, {"extensions", lightExt(1)}});
  w.addNode({{"translation", {0, 4, 0}}, {"rotation", {-h, 0, 0, h}}, {"extensions", lightExt(2)}});
  w.addNode({{"mesh", triangleMesh(w)}});
  Scene s = loadGltfScene(w.write(dir, "lights"));
  ASSERT_EQ(s.lights.size(), 3u);
  EXPECT_EQ(s.lightNames[0], "sun");
  const GiLight &sun = s.lights[0], &bulb = s.lights[1], &torch = s.lights[2];
  EXPECT_EQ(sun.type, GI_LIGHT_DIRECTIONAL);
  expectNear({sun.intensity[0], sun.intensity[1], sun.intensity[2]}, {3, 1.5f, 0.75f});  // W/m²
  expectNear({sun.direction[0], sun.direction[1], sun.direction[2]}, {0, -1, 0});
  EXPECT_EQ(bulb.type, GI_LIGHT_POINT);
  expectNear({bulb.intensity[0], bulb.intensity[1], bulb.intensity[2]}, {10, 10, 10});  // W/sr
  expectNear({bulb.position[0], bulb.position[1], bulb.position[2]}, {1, 2, 3});
  EXPECT_EQ(bulb.range, 5.0f);
  EXPECT_EQ(torch.type, GI_LIGHT_SPOT);
  EXPECT_EQ(torch.falloff, GI_SPOT_FALLOFF_GLTF);
  EXPECT_NEAR(torch.cos_inner, std::cos(0.2f), 1e-6f);
  EXPECT_NEAR(torch.cos_outer, std::cos(0.4f), 1e-6f);
  expectNear({torch.direction[0], torch.direction[1], torch.direction[2]}, {0, -1, 0});
  expectNear({torch.position[0], torch.position[1], torch.position[2]}, {0, 4, 0});
  for (const GiLight& l : s.lights) EXPECT_EQ(l.shadow_map, -1);
}

TEST(SceneGltf, PerspectiveCamerasFromNodes) {
  auto dir = test::tempDir("scene_gltf_cameras");
  GltfWriter w;
  w.doc["cameras"] = {{{"name", "front"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}, {"aspectRatio", 2.0}}}},
                      {{"type", "perspective"}, {"perspective", {{"yfov", 1.0}, {"znear", 0.2}, {"zfar", 50.0}}}}};
  const double h = std::sqrt(0.5);  // 90° about +y: -Z turns to -X
  w.addNode({{"translation", {0, 1, 5}}, {"camera", 0}});
  w.addNode({{"name", "side node"}, {"translation", {5, 0, 0}}, {"rotation", {0, h, 0, h}}, {"camera", 1}});
  w.addNode({{"mesh", triangleMesh(w)}});
  Scene s = loadGltfScene(w.write(dir, "cameras"));
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_EQ(s.defaultCamera, 0);
  const Camera &front = s.cameras[0], &side = s.cameras[1];
  EXPECT_EQ(front.name, "front");
  expectNear(front.position, {0, 1, 5});
  expectNear(glm::normalize(front.target - front.position), {0, 0, -1});
  expectNear(front.up, {0, 1, 0});
  EXPECT_FLOAT_EQ(front.yfov, 0.5f);
  EXPECT_FLOAT_EQ(front.znear, 0.1f);
  EXPECT_GT(front.zfar, 5.0f) << "missing zfar is fitted to the bounds";
  EXPECT_EQ(s.defaultWidth, 640);
  EXPECT_EQ(s.defaultHeight, 320);
  EXPECT_EQ(side.name, "side node");
  expectNear(glm::normalize(side.target - side.position), {-1, 0, 0});
  EXPECT_FLOAT_EQ(side.zfar, 50.0f);
}

TEST(SceneGltf, FileWithoutCameraGetsOneFramingTheBounds) {
  auto dir = test::tempDir("scene_gltf_no_camera");
  GltfWriter w;
  w.addNode({{"mesh", triangleMesh(w)}, {"scale", {10, 10, 10}}});
  Scene s = loadGltfScene(w.write(dir, "nocam"));
  ASSERT_EQ(s.cameras.size(), 1u);
  const Camera& c = s.cameras[0];
  expectNear(c.target, s.bounds.center());
  EXPECT_NEAR(c.yfov, glm::radians(60.0f), 1e-6f);
  EXPECT_GE(glm::length(c.position - c.target), 2.0f * s.bounds.radius() - 1e-4f);
  EXPECT_GT(c.position.z, c.target.z);
  EXPECT_GT(c.znear, 0.0f);
  EXPECT_GT(c.zfar, glm::length(c.position - c.target) + s.bounds.radius());
}

TEST(SceneGltf, GlbAndDataUriStorageLoadTheSame) {
  auto dir = test::tempDir("scene_gltf_storage");
  GltfWriter w;
  w.addNode({{"mesh", triangleMesh(w)}});
  Scene fromBin = loadGltfScene(w.write(dir, "bin", GltfWriter::Storage::BinFile));
  Scene fromUri = loadGltfScene(w.write(dir, "uri", GltfWriter::Storage::DataUri));
  Scene fromGlb = loadGltfScene(w.write(dir, "glb", GltfWriter::Storage::Glb));
  EXPECT_EQ(fromUri.positions, fromBin.positions);
  EXPECT_EQ(fromGlb.positions, fromBin.positions);
  EXPECT_EQ(fromGlb.triangleCount(), 1u);
}

// ---- bad input ------------------------------------------------------------------------------

TEST(SceneGltf, TruncatedFileNamesTheFile) {
  auto dir = test::tempDir("scene_gltf_truncated");
  GltfWriter w;
  w.addNode({{"mesh", triangleMesh(w)}});
  auto file = w.write(dir, "cut");
  std::string text = readTextFile(file);
  std::ofstream(file) << text.substr(0, text.size() / 2);
  std::string message = errorOf([&] { loadGltfScene(file); });
  EXPECT_NE(message.find("cut.gltf"), std::string::npos) << message;
}

TEST(SceneGltf, MalformedJsonNamesTheFile) {
  auto dir = test::tempDir("scene_gltf_malformed");
  std::ofstream(dir / "garbage.gltf") << "{ \"asset\": { \"version\": \"2.0\" }, this is not json ]";
  std::string message = errorOf([&] { loadGltfScene(dir / "garbage.gltf"); });
  EXPECT_NE(message.find("garbage.gltf"), std::string::npos) << message;
}

TEST(SceneGltf, MissingFileNamesTheFile) {
  std::string message = errorOf([&] { loadGltfScene("/nonexistent/dir/none.gltf"); });
  EXPECT_NE(message.find("/nonexistent/dir/none.gltf"), std::string::npos) << message;
}

TEST(SceneGltf, MissingBinNamesTheBin) {
  auto dir = test::tempDir("scene_gltf_missing_bin");
  GltfWriter w;
  w.addNode({{"mesh", triangleMesh(w)}});
  auto file = w.write(dir, "nobin");
  std::filesystem::remove(dir / "nobin.bin");
  std::string message = errorOf([&] { loadGltfScene(file); });
  EXPECT_NE(message.find("nobin.gltf"), std::string::npos) << message;
  EXPECT_NE(message.find("nobin.bin"), std::string::npos) << message;
}

TEST(SceneGltf, MissingTextureImageNamesTheImage) {
  auto dir = test::tempDir("scene_gltf_missing_texture");
  GltfWriter w;
  w.doc["images"] = {{{"uri", "not_there.png"}}};
  w.doc["textures"] = {{{"source", 0}}};
  int mat = w.addMaterial({{"name", "wood"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  w.addNode({{"mesh", triangleMesh(w, "tri", mat)}});
  auto file = w.write(dir, "notex");
  std::string message = errorOf([&] { loadGltfScene(file); });
  EXPECT_NE(message.find("notex.gltf"), std::string::npos) << message;
  EXPECT_NE(message.find("not_there.png"), std::string::npos) << message;
  EXPECT_NE(message.find("wood"), std::string::npos) << message;
}

TEST(SceneGltf, RequiredDracoExtensionIsRefused) {
  auto dir = test::tempDir("scene_gltf_draco");
  GltfWriter w;
  w.addNode({{"mesh", triangleMesh(w)}});
  w.doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  w.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  auto file = w.write(dir, "draco");
  std::string message = errorOf([&] { loadGltfScene(file); });
  EXPECT_NE(message.find("draco.gltf"), std::string::npos) << message;
  EXPECT_NE(message.find("KHR_draco_mesh_compression"), std::string::npos) << message;
}

TEST(SceneGltf, OutOfRangeIndexIsAnError) {
  auto dir = test::tempDir("scene_gltf_bad_index");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  w.addNode({{"mesh", w.addMesh("broken", {{"POSITION", pos}}, w.addIndices({0, 1, 7}))}});
  auto file = w.write(dir, "badindex");
  std::string message = errorOf([&] { loadGltfScene(file); });
  EXPECT_NE(message.find("badindex.gltf"), std::string::npos) << message;
  EXPECT_NE(message.find("mesh 'broken' primitive 0"), std::string::npos) << message;
  EXPECT_NE(message.find("index 7"), std::string::npos) << message;
}

TEST(SceneGltf, AccessorBeyondItsBufferViewIsAnError) {
  auto dir = test::tempDir("scene_gltf_bad_accessor");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  w.doc["accessors"][pos]["count"] = 30;
  w.addNode({{"mesh", w.addMesh("short", {{"POSITION", pos}})}});
  auto file = w.write(dir, "badaccessor");
  std::string message = errorOf([&] { loadGltfScene(file); });
  EXPECT_NE(message.find("mesh 'short' primitive 0 attribute POSITION"), std::string::npos) << message;
}

TEST(SceneGltf, AttributeWithTooFewElementsIsAnError) {
  auto dir = test::tempDir("scene_gltf_short_attribute");
  GltfWriter w;
  int pos = w.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
  int uv = w.addAccessor(std::vector<float>{0, 0, 1, 0}, test::kGltfFloat, "VEC2");
  w.addNode({{"mesh", w.addMesh("uvless", {{"POSITION", pos}, {"TEXCOORD_0", uv}})}});
  auto file = w.write(dir, "shortattr");
  std::string message = errorOf([&] { loadGltfScene(file); });
  EXPECT_NE(message.find("mesh 'uvless' primitive 0: attribute TEXCOORD_0 has 2 elements, POSITION has 3"),
            std::string::npos)
      << message;
}

}  // namespace
}  // namespace gi
