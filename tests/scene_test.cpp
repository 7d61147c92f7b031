// Tests of scenes (docs/design.md §4): glTF loading (node hierarchy, normals, materials,
// textures, cameras, environment extras), the Embree ray caster, malformed scenes
// through the library and the `glaze` command, and capture sets written by
// `glaze render --captures`.
//
// Every scene is a small glTF file written by the test into a temporary directory
// (buffers as base64 data URIs, images as files). Every expectation is computed by hand
// from the file's numbers (transforms, barycentrics, the sRGB formula, ...), never taken
// from the implementation's own output.
#include "renderer/camera.h"
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"
#include "gltf_builder.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <variant>
#include <vector>

namespace glaze {
namespace {

using nlohmann::json;
using namespace testing;  // gltf_builder.h: GltfBuffer, gltf_document, write_gltf, encode_png, ...

// --- Running the command (as cli_test.cpp does). ---

// ---------------------------------------------------------------------------------------
// 1. Loading: transforms and normals.
// ---------------------------------------------------------------------------------------

// Parent: 90 degrees about +Z, then translation (1, 2, 3); child: translation (1, 0, 0)
// and scale 2; sphere radius 0.5 at the child. By hand: the child's origin goes to
// Rz(90) (1, 0, 0) + (1, 2, 3) = (0, 1, 0) + (1, 2, 3) = (1, 3, 3); radius 0.5 * 2 = 1;
// the sphere's frame is Rz(90), whose first column is (0, 1, 0).
TEST(SceneLoading, SphereInNodeHierarchyHasHandComputedWorldCentreAndRadius) {
  testing::TemporaryDirectory dir;
  json child = sphere_node(0.5);
  child["translation"] = {1, 0, 0};
  child["scale"] = {2, 2, 2};
  const json parent = {{"rotation", {0, 0, kS, kS}}, {"translation", {1, 2, 3}}, {"children", {1}}};
  const Scene scene = load_scene(write_gltf(dir, "hierarchy.gltf", gltf_document({parent, child}, {0})));
  ASSERT_EQ(scene.spheres.size(), 1u);
  ASSERT_TRUE(scene.meshes.empty());
  expect_vec_near(scene.spheres[0].center, Vec3(1, 3, 3), 1e-5f, "centre");
  EXPECT_NEAR(scene.spheres[0].radius, 1.0f, 1e-5f);
  expect_vec_near(scene.spheres[0].rotation.col(0), Vec3(0, 1, 0), 1e-5f, "frame x axis");
  expect_vec_near(scene.spheres[0].rotation.col(1), Vec3(-1, 0, 0), 1e-5f, "frame y axis");
}

// A triangle with explicit normals under scale (2, 1, 0.5) and a translation. Normals
// transform by the inverse transpose diag(0.5, 1, 2), then are normalised:
// (1,1,0) -> (1,2,0)/sqrt5, (0,0,1) -> (0,0,1), (1,0,1) -> (0.5,0,2) = (1,0,4)/sqrt17.
// Positions get the scale and the translation; the normals do not see the translation.
TEST(SceneLoading, ExplicitNormalsTransformByInverseTransposeAndAreNormalised) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const int positions = buffer.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, 3);
  const float r = 1.0f / std::sqrt(2.0f);
  const int normals = buffer.floats({r, r, 0, 0, 0, 1, r, 0, r}, 3);
  json gltf = gltf_document({{{"mesh", 0}, {"scale", {2, 1, 0.5}}, {"translation", {0, 0, 7}}}}, {0});
  gltf["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", positions}, {"NORMAL", normals}}}}}}}};
  buffer.into(gltf);
  const Scene scene = load_scene(write_gltf(dir, "normals.gltf", gltf));
  ASSERT_EQ(scene.meshes.size(), 1u);
  const TriangleMesh& mesh = scene.meshes[0];
  ASSERT_EQ(mesh.positions.size(), 3u);
  ASSERT_EQ(mesh.normals.size(), 3u);
  expect_vec_near(mesh.positions[0], Vec3(0, 0, 7), 1e-6f, "p0");
  expect_vec_near(mesh.positions[1], Vec3(2, 0, 7), 1e-6f, "p1");
  expect_vec_near(mesh.positions[2], Vec3(0, 1, 7), 1e-6f, "p2");
  expect_vec_near(mesh.normals[0], Vec3(1, 2, 0) / std::sqrt(5.0f), 1e-5f, "n0");
  expect_vec_near(mesh.normals[1], Vec3(0, 0, 1), 1e-5f, "n1");
  expect_vec_near(mesh.normals[2], Vec3(1, 0, 4) / std::sqrt(17.0f), 1e-5f, "n2");
  for (const Vec3& n : mesh.normals) EXPECT_NEAR(n.norm(), 1.0f, 1e-6f);
}

// The hit of the ray from `origin` along `direction` (normalised here).
SurfaceHit hit_of(const Scene& scene, const Vec3& origin, const Vec3& direction) {
  const RayTracer tracer(scene);
  const std::optional<SurfaceHit> hit = tracer.intersect({origin, direction.normalized()});
  EXPECT_TRUE(hit.has_value());
  return hit.value_or(SurfaceHit{});
}

// A flat quad in the z = 0 plane, counter-clockwise seen from +Z (face normal +Z), under
// a 90-degree turn about +X, which takes (x, y, 0) to (x, 0, y). No NORMAL attribute: glTF
// says flat shading, so the mesh keeps no vertex normals and a hit's shading normal is the
// face's, (0, -1, 0) or (0, 1, 0), turned towards the ray.
TEST(SceneLoading, WithoutNormalsAHitIsShadedWithTheFaceNormal) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const int positions = buffer.floats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, 3);
  const int indices = buffer.indices({0, 1, 2, 0, 2, 3});
  json gltf = gltf_document({{{"mesh", 0}, {"rotation", {kS, 0, 0, kS}}}}, {0});
  gltf["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", positions}}}, {"indices", indices}}}}}};
  buffer.into(gltf);
  const Scene scene = load_scene(write_gltf(dir, "quad.gltf", gltf));
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_TRUE(scene.meshes[0].normals.empty());
  const SurfaceHit below = hit_of(scene, Vec3(0.3f, -5, 0.6f), Vec3(0, 1, 0));
  expect_vec_near(below.position, Vec3(0.3f, 0, 0.6f), 1e-5f, "position");
  expect_vec_near(below.normal, Vec3(0, -1, 0), 1e-6f, "normal from below");
  const SurfaceHit above = hit_of(scene, Vec3(0.3f, 5, 0.6f), Vec3(0, -1, 0));
  expect_vec_near(above.normal, Vec3(0, 1, 0), 1e-6f, "normal from above");
}

// An octahedron (vertices +-X, +-Y, +-Z, outward winding) without normals, under a node
// with translation (5, 0, 0) and scale `scale`; returns the loaded scene.
Scene load_octahedron(const testing::TemporaryDirectory& dir, const Vec3& scale) {
  const std::vector<float> vertices = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  // Faces (X, Y, Z) with X in {0, 1}, Y in {2, 3}, Z in {4, 5}; (+X, +Y, +Z) is
  // counter-clockwise seen from outside, and each negative axis flips the orientation.
  std::vector<uint16_t> faces;
  for (int sx = 0; sx < 2; ++sx)
    for (int sy = 0; sy < 2; ++sy)
      for (int sz = 0; sz < 2; ++sz) {
        const uint16_t x = uint16_t(sx), y = uint16_t(2 + sy), z = uint16_t(4 + sz);
        if ((sx + sy + sz) % 2 == 0)
          faces.insert(faces.end(), {x, y, z});
        else
          faces.insert(faces.end(), {x, z, y});
      }
  GltfBuffer buffer;
  const int positions = buffer.floats(vertices, 3);
  const int indices = buffer.indices(faces);
  json gltf =
      gltf_document({{{"mesh", 0}, {"translation", {5, 0, 0}}, {"scale", {scale.x(), scale.y(), scale.z()}}}}, {0});
  gltf["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", positions}}}, {"indices", indices}}}}}};
  buffer.into(gltf);
  return load_scene(write_gltf(dir, "octahedron.gltf", gltf));
}

// The octahedron scaled by (1, 2, 3) at (5, 0, 0): its face in the (+, +, +) octant lies
// in the plane x' + y'/2 + z'/3 = 1 (x' = x - 5), whose normal is (1, 1/2, 1/3). A ray
// from outside towards the face's centroid sees exactly that normal, flat over the face.
// Under scale (-1, 2, 3), a mirror (negative determinant), the solid is the same set of
// points, so the same ray must see the same normal.
TEST(SceneLoading, FlatNormalsOfScaledAndMirroredShapesAreTheFaceNormals) {
  testing::TemporaryDirectory dir;
  const Vec3 centroid = Vec3(5, 0, 0) + Vec3(1, 2, 3) / 3.0f;
  const Vec3 face_normal = Vec3(1, 0.5f, 1.0f / 3.0f).normalized();
  for (const Vec3& scale : {Vec3(1, 2, 3), Vec3(-1, 2, 3)}) {
    const Scene scene = load_octahedron(dir, scale);
    ASSERT_EQ(scene.meshes.size(), 1u);
    EXPECT_TRUE(scene.meshes[0].normals.empty());
    const Vec3 origin = centroid + 4.0f * Vec3(1, 1, 1).normalized();
    const SurfaceHit hit = hit_of(scene, origin, centroid - origin);
    expect_vec_near(hit.position, centroid, 1e-4f, "position, scale x " + std::to_string(scale.x()));
    expect_vec_near(hit.normal, face_normal, 1e-5f, "normal, scale x " + std::to_string(scale.x()));
    expect_vec_near(hit.geometric_normal, face_normal, 1e-5f, "geometric normal");
  }
}
// ---------------------------------------------------------------------------------------
// 2. Materials.
// ---------------------------------------------------------------------------------------

// A scene of one sphere per material, so that every material is used.
json spheres_with_materials(const json& materials) {
  std::vector<json> nodes;
  std::vector<int> roots;
  for (int i = 0; i < int(materials.size()); ++i) {
    json node = sphere_node(0.5, i);
    node["translation"] = {2.0 * i, 0, 0};
    nodes.push_back(node);
    roots.push_back(i);
  }
  json gltf = gltf_document(nodes, roots);
  gltf["materials"] = materials;
  return gltf;
}

// R0 = ((ior - 1)/(ior + 1))^2: ior 1.5 -> (0.5/2.5)^2 = 0.04; ior 2 -> (1/3)^2 = 1/9.
// No extension also means ior 1.5, so 0.04. baseColorFactor (linear) becomes Rd.
TEST(SceneMaterials, IorExtensionGivesSchlickR0) {
  testing::TemporaryDirectory dir;
  const json materials = {
      quiet_material({{"extensions", {{"KHR_materials_ior", {{"ior", 1.5}}}}}}),
      quiet_material({{"extensions", {{"KHR_materials_ior", {{"ior", 2.0}}}}}}),
      quiet_material({{"pbrMetallicRoughness", {{"baseColorFactor", {0.25, 0.5, 0.75, 1.0}}}}}),
  };
  testing::CapturedWarnings warnings;
  const Scene scene = load_scene(write_gltf(dir, "ior.gltf", spheres_with_materials(materials)));
  ASSERT_EQ(scene.materials.size(), 3u);
  EXPECT_NEAR(scene.materials[0].R0, 0.04f, 1e-6f);
  EXPECT_NEAR(scene.materials[1].R0, 1.0f / 9.0f, 1e-6f);
  EXPECT_NEAR(scene.materials[2].R0, 0.04f, 1e-6f);
  expect_vec_near(scene.materials[2].Rd.matrix(), Vec3(0.25f, 0.5f, 0.75f), 1e-6f, "Rd");
  EXPECT_TRUE(warnings.messages.empty()) << warnings.messages.front();
}

// extras.glaze {"R0": 0.1, "Rd": [0.5, 0.6, 0.7]} wins over baseColorFactor and ior 2.
TEST(SceneMaterials, GlazeExtrasOverrideBaseColorAndIor) {
  testing::TemporaryDirectory dir;
  const json materials =
      json::array({quiet_material({{"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.3, 0.4, 1.0}}}},
                                   {"extensions", {{"KHR_materials_ior", {{"ior", 2.0}}}}},
                                   {"extras", {{"glaze", {{"R0", 0.1}, {"Rd", {0.5, 0.6, 0.7}}}}}}})});
  const Scene scene = load_scene(write_gltf(dir, "extras.gltf", spheres_with_materials(materials)));
  ASSERT_EQ(scene.materials.size(), 1u);
  EXPECT_NEAR(scene.materials[0].R0, 0.1f, 1e-6f);
  expect_vec_near(scene.materials[0].Rd.matrix(), Vec3(0.5f, 0.6f, 0.7f), 1e-6f, "Rd");
  // Scene::material_at of an untextured material is the constant.
  const PolishedMaterial at = scene.material_at(0, Vec2(0.3f, 0.9f));
  EXPECT_NEAR(at.R0(), 0.1f, 1e-6f);
  expect_vec_near(at.Rd().matrix(), Vec3(0.5f, 0.6f, 0.7f), 1e-6f, "material_at Rd");
}

// The coat is a perfect mirror: metallicFactor or roughnessFactor > 0 is counted in the
// scene's one warning about what glaze ignores; both 0 is silent. A material without the
// factors has glTF's defaults (1, 1) and is counted too.
TEST(SceneMaterials, MetallicOrRoughnessWarnsAndZeroDoesNot) {
  testing::TemporaryDirectory dir;
  auto warnings_for = [&](const json& material, const std::string& name) {
    testing::CapturedWarnings warnings;
    load_scene(write_gltf(dir, name, spheres_with_materials(json::array({material}))));
    return warnings.messages;
  };
  const auto quiet = warnings_for(quiet_material(), "quiet.gltf");
  EXPECT_TRUE(quiet.empty()) << quiet.front();

  const auto metallic =
      warnings_for(quiet_material({{"pbrMetallicRoughness", {{"metallicFactor", 0.5}}}}), "metal.gltf");
  ASSERT_EQ(metallic.size(), 1u);
  EXPECT_NE(metallic[0].find("materials with metallic/roughness: 1"), std::string::npos) << metallic[0];

  const auto rough =
      warnings_for(quiet_material({{"pbrMetallicRoughness", {{"roughnessFactor", 0.25}}}}), "rough.gltf");
  ASSERT_EQ(rough.size(), 1u);
  EXPECT_NE(rough[0].find("materials with metallic/roughness: 1"), std::string::npos) << rough[0];

  const auto defaults = warnings_for(json::object({{"name", "defaults"}}), "defaults.gltf");
  EXPECT_EQ(defaults.size(), 1u);
}

// Rd is a reflectance in [0, 1] and R0 too: Rd > 1, R0 < 0 and R0 > 1 are errors that
// name the parameter.
TEST(SceneMaterials, OutOfRangeReflectancesAreErrors) {
  testing::TemporaryDirectory dir;
  auto error_for = [&](const json& glaze_extras, const std::string& name) -> std::string {
    try {
      load_scene(write_gltf(
          dir, name, spheres_with_materials(json::array({quiet_material({{"extras", {{"glaze", glaze_extras}}}})}))));
    } catch (const Error& e) {
      return e.what();
    }
    return "(no error)";
  };
  const std::string rd = error_for({{"Rd", {1.5, 0.5, 0.5}}}, "rd.gltf");
  EXPECT_NE(rd.find("Rd"), std::string::npos) << rd;
  const std::string negative = error_for({{"R0", -0.1}}, "negative.gltf");
  EXPECT_NE(negative.find("R0"), std::string::npos) << negative;
  const std::string above = error_for({{"R0", 1.2}}, "above.gltf");
  EXPECT_NE(above.find("R0"), std::string::npos) << above;
  // The bounds themselves are allowed.
  EXPECT_NO_THROW(load_scene(write_gltf(dir, "edges.gltf",
                                        spheres_with_materials(json::array({quiet_material(
                                            {{"extras", {{"glaze", {{"R0", 1.0}, {"Rd", {1.0, 0.0, 1.0}}}}}}})})))));
}

// A 2x2 8-bit sRGB PNG (written byte by byte here) as baseColorTexture:
//   row 0: (128, 64, 10)  (255, 0, 0)
//   row 1: (0, 255, 0)    (0, 0, 255)
// Texels decode with the sRGB formula: 128 -> 0.2158605, 64 -> 0.0512695, 10 ->
// 10/255/12.92 = 0.0030353 (the linear segment). At a texel centre uv ((i + 0.5)/2,
// (j + 0.5)/2) the bilinear lookup is that texel alone, so material_at gives
// Rd = baseColorFactor (0.5, 1, 0.8) x texel.
TEST(SceneMaterials, BaseColorTexturePngIsLinearisedAndMultipliesTheFactor) {
  testing::TemporaryDirectory dir;
  const std::vector<unsigned char> png = encode_png(2, 2, {128, 64, 10, 255, 0, 0, 0, 255, 0, 0, 0, 255});
  std::ofstream(dir.file("texture.png"), std::ios::binary).write(reinterpret_cast<const char*>(png.data()), png.size());

  GltfBuffer buffer;
  const int positions = buffer.floats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, 3);
  const int uvs = buffer.floats({0, 1, 1, 1, 1, 0, 0, 0}, 2);
  const int indices = buffer.indices({0, 1, 2, 0, 2, 3});
  json gltf = gltf_document({{{"mesh", 0}}}, {0});
  gltf["meshes"] = {
      {{"primitives",
        {{{"attributes", {{"POSITION", positions}, {"TEXCOORD_0", uvs}}}, {"indices", indices}, {"material", 0}}}}}};
  gltf["materials"] = json::array({quiet_material(
      {{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 1.0, 0.8, 1.0}}, {"baseColorTexture", {{"index", 0}}}}}})});
  gltf["textures"] = {{{"source", 0}}};
  gltf["images"] = {{{"uri", "texture.png"}}};
  buffer.into(gltf);
  const Scene scene = load_scene(write_gltf(dir, "textured.gltf", gltf));

  // Hand-computed constants, checked against the formula written out above.
  EXPECT_NEAR(srgb_decode(128), 0.2158605, 1e-6);
  EXPECT_NEAR(srgb_decode(64), 0.0512695, 1e-6);
  EXPECT_NEAR(srgb_decode(10), 0.0030353, 1e-6);

  ASSERT_EQ(scene.textures.size(), 1u);
  const Image& image = scene.textures[0].image;
  ASSERT_EQ(image.width, 2);
  ASSERT_EQ(image.height, 2);
  expect_vec_near(image.at(0, 0).matrix(), Vec3(0.2158605f, 0.0512695f, 0.0030353f), 1e-5f, "texel (0,0)");
  expect_vec_near(image.at(1, 0).matrix(), Vec3(1, 0, 0), 1e-6f, "texel (1,0)");
  expect_vec_near(image.at(0, 1).matrix(), Vec3(0, 1, 0), 1e-6f, "texel (0,1)");
  expect_vec_near(image.at(1, 1).matrix(), Vec3(0, 0, 1), 1e-6f, "texel (1,1)");

  ASSERT_EQ(scene.materials.size(), 1u);
  EXPECT_EQ(scene.materials[0].texture, 0);
  expect_vec_near(scene.material_at(0, Vec2(0.25f, 0.25f)).Rd().matrix(),
                  Vec3(0.5f * 0.2158605f, 1.0f * 0.0512695f, 0.8f * 0.0030353f), 1e-5f, "Rd at texel (0,0)");
  expect_vec_near(scene.material_at(0, Vec2(0.75f, 0.25f)).Rd().matrix(), Vec3(0.5f, 0, 0), 1e-5f, "Rd at texel (1,0)");
  expect_vec_near(scene.material_at(0, Vec2(0.25f, 0.75f)).Rd().matrix(), Vec3(0, 1, 0), 1e-5f, "Rd at texel (0,1)");
  expect_vec_near(scene.material_at(0, Vec2(0.75f, 0.75f)).Rd().matrix(), Vec3(0, 0, 0.8f), 1e-5f, "Rd at texel (1,1)");
  EXPECT_NEAR(scene.material_at(0, Vec2(0.25f, 0.25f)).R0(), 0.04f, 1e-6f);
}

// ---------------------------------------------------------------------------------------
// 3. Cameras.
// ---------------------------------------------------------------------------------------

// A sphere and a perspective camera "front" (yfov 60 degrees, aspect 2) at (5, 1, 0)
// turned 90 degrees about +Y, which takes the camera's -Z to world -X; plus a second
// camera "side". Optionally a film size in the scene's extras.
json camera_scene(const json& film = nullptr) {
  json camera_node = {{"camera", 0}, {"rotation", {0, kS, 0, kS}}, {"translation", {5, 1, 0}}};
  json side_node = {{"camera", 1}, {"translation", {0, 0, 5}}};
  json gltf = gltf_document({sphere_node(1.0), camera_node, side_node}, {0, 1, 2});
  const double yfov = 60.0 * std::numbers::pi / 180.0;
  gltf["cameras"] = {{{"name", "front"},
                      {"type", "perspective"},
                      {"perspective", {{"yfov", yfov}, {"aspectRatio", 2.0}, {"znear", 0.1}}}},
                     {{"name", "side"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}}}}};
  if (!film.is_null()) gltf["scenes"][0]["extras"] = {{"glaze", {{"film", film}}}};
  return gltf;
}

// No film: 512 high with aspect 2 -> 1024 x 512; fl_y = (512/2)/tan(30 deg) = 256 sqrt(3)
// = 443.405; square pixels; principal point at the centre (512, 256).
void expect_intrinsics(const PinholeCamera& camera, int width, int height, float focal, float cx, float cy,
                       float focal_tolerance, float centre_tolerance) {
  EXPECT_EQ(camera.width, width);
  EXPECT_EQ(camera.height, height);
  EXPECT_NEAR(camera.fl_y, focal, focal_tolerance);
  EXPECT_NEAR(camera.fl_x, focal, focal_tolerance);  // square pixels
  EXPECT_NEAR(camera.cx, cx, centre_tolerance);
  EXPECT_NEAR(camera.cy, cy, centre_tolerance);
}

TEST(SceneCameras, DefaultFilmIs512HighWithTheCameraAspect) {
  testing::TemporaryDirectory dir;
  const Scene scene = load_scene(write_gltf(dir, "camera.gltf", camera_scene()));
  ASSERT_EQ(scene.cameras.size(), 2u);
  const CameraSpec& spec = scene.camera("front");
  EXPECT_NEAR(spec.yfov, kPi / 3.0f, 1e-6f);
  EXPECT_NEAR(spec.aspect, 2.0f, 1e-6f);
  expect_intrinsics(scene.make_camera(spec, std::nullopt), 1024, 512, 256.0f * std::sqrt(3.0f), 512.0f, 256.0f, 1e-3f,
                    1e-4f);
}

// film {200, 100}: that size, fl_y = 50/tan(30 deg) = 50 sqrt(3); a resolution argument
// (--res 64x48) overrides the film: fl_y = 24 sqrt(3), centre (32, 24).
TEST(SceneCameras, SceneFilmAndResolutionArgumentSetTheSize) {
  testing::TemporaryDirectory dir;
  const Scene scene = load_scene(write_gltf(dir, "film.gltf", camera_scene({{"width", 200}, {"height", 100}})));
  ASSERT_TRUE(scene.film.has_value());
  expect_intrinsics(scene.make_camera(scene.camera("front"), std::nullopt), 200, 100, 50.0f * std::sqrt(3.0f), 100.0f,
                    50.0f, 1e-4f, 1e-5f);
  expect_intrinsics(scene.make_camera(scene.camera("front"), std::pair{64, 48}), 64, 48, 24.0f * std::sqrt(3.0f), 32.0f,
                    24.0f, 1e-4f, 1e-5f);
}

// Rays of "front" (pose Ry(90): camera x -> world (0,0,-1), y -> (0,1,0), z -> (1,0,0)):
// through the centre, camera -Z = world (-1, 0, 0) from (5, 1, 0). Through pixel point
// (0.5, 0.5) of the 1024x512 film, camera-space (a, b, -1) with a = (0.5 - 512)/fl,
// b = -(0.5 - 256)/fl, fl = 256 sqrt(3); rotated: a (0,0,-1) + b (0,1,0) - (1,0,0)
// = (-1, b, -a), normalised.
TEST(SceneCameras, GeneratedRaysFollowThePoseAndIntrinsics) {
  testing::TemporaryDirectory dir;
  const Scene scene = load_scene(write_gltf(dir, "camera.gltf", camera_scene()));
  const PinholeCamera camera = scene.make_camera(scene.camera("front"), std::nullopt);
  const Ray centre = camera.generate_ray(512.0f, 256.0f);
  expect_vec_near(centre.origin, Vec3(5, 1, 0), 1e-5f, "origin");
  expect_vec_near(centre.direction, Vec3(-1, 0, 0), 1e-6f, "centre direction");

  const float fl = 256.0f * std::sqrt(3.0f);
  const float a = (0.5f - 512.0f) / fl, b = -(0.5f - 256.0f) / fl;
  const Ray corner = camera.generate_ray(0.5f, 0.5f);
  expect_vec_near(corner.origin, Vec3(5, 1, 0), 1e-5f, "origin");
  expect_vec_near(corner.direction, Vec3(-1, b, -a).normalized(), 1e-5f, "corner direction");
  EXPECT_NEAR(corner.direction.norm(), 1.0f, 1e-6f);
  // Top-left pixel: up (+Y) and to the camera's left (camera -X = world +Z).
  EXPECT_GT(corner.direction.y(), 0.0f);
  EXPECT_GT(corner.direction.z(), 0.0f);
}

// An unknown camera name is an error that names it and lists the cameras there are.
TEST(SceneCameras, UnknownCameraNameListsTheCameras) {
  testing::TemporaryDirectory dir;
  const Scene scene = load_scene(write_gltf(dir, "camera.gltf", camera_scene()));
  try {
    scene.camera("nope");
    FAIL() << "no error for an unknown camera";
  } catch (const Error& e) {
    const std::string message = without_directory(e.what(), dir);
    EXPECT_NE(message.find("nope"), std::string::npos) << message;
    EXPECT_NE(message.find("front"), std::string::npos) << message;
    EXPECT_NE(message.find("side"), std::string::npos) << message;
  }
}

// ---------------------------------------------------------------------------------------
// 4. Environment extras.
// ---------------------------------------------------------------------------------------

json environment_scene(const json& environment) {
  json gltf = gltf_document({sphere_node(1.0)}, {0});
  gltf["scenes"][0]["extras"] = {{"glaze", {{"environment", environment}}}};
  return gltf;
}

// A relative "file" is relative to the .gltf's directory (here DIR/sub/); scale,
// rotation and to_world are read as given.
TEST(SceneEnvironment, FileIsResolvedBesideTheSceneAndOptionsAreRead) {
  testing::TemporaryDirectory dir;
  const json environment = {
      {"file", "env.exr"}, {"scale", 2}, {"rotation", 90}, {"to_world", {{1, 0, 0}, {0, -1, 0}, {0, 0, -1}}}};
  const Scene scene = load_scene(write_gltf(dir, "sub/scene.gltf", environment_scene(environment)));
  ASSERT_TRUE(scene.environment.has_value());
  EXPECT_EQ(std::filesystem::path(scene.environment->source).lexically_normal(),
            (dir.path() / "sub" / "env.exr").lexically_normal());
  EXPECT_FLOAT_EQ(scene.environment->options.scale, 2.0f);
  EXPECT_FLOAT_EQ(scene.environment->options.rotation_degrees, 90.0f);
  Mat3 expected;
  expected << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  EXPECT_TRUE(scene.environment->options.to_world.isApprox(expected, 1e-7f)) << scene.environment->options.to_world;
  // A rows-versus-columns mix-up would not show with a symmetric matrix: check one that is not.
  const json rotated = {{"file", "env.exr"}, {"to_world", {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}}}};
  const Scene scene2 = load_scene(write_gltf(dir, "sub/scene2.gltf", environment_scene(rotated)));
  EXPECT_FLOAT_EQ(scene2.environment->options.to_world(0, 1), 1.0f);
  EXPECT_FLOAT_EQ(scene2.environment->options.to_world(1, 0), -1.0f);
  EXPECT_FLOAT_EQ(scene2.environment->options.scale, 1.0f);  // defaults
  EXPECT_FLOAT_EQ(scene2.environment->options.rotation_degrees, 0.0f);
}

// {"procedural": "blue-room"} -> source "procedural:blue-room"; width/height set the
// generated map's resolution.
TEST(SceneEnvironment, ProceduralEnvironmentGivesProceduralSource) {
  testing::TemporaryDirectory dir;
  const Scene scene = load_scene(write_gltf(dir, "blue.gltf", environment_scene({{"procedural", "blue-room"}})));
  ASSERT_TRUE(scene.environment.has_value());
  EXPECT_EQ(scene.environment->source, "procedural:blue-room");
  const Scene small = load_scene(
      write_gltf(dir, "small.gltf", environment_scene({{"procedural", "constant"}, {"width", 16}, {"height", 8}})));
  EXPECT_EQ(small.environment->source, "procedural:constant");
  EXPECT_EQ(small.environment->width, 16);
  EXPECT_EQ(small.environment->height, 8);
}

// ---------------------------------------------------------------------------------------
// 5. The ray tracer.
// ---------------------------------------------------------------------------------------

Scene unit_sphere_scene() {
  Scene scene;
  scene.materials.push_back(SceneMaterial{"white", 0.04f, RGB::Ones(), -1});
  scene.spheres.push_back(Sphere{"unit", Vec3::Zero(), 1.0f, 0});
  return scene;
}

// From (0, 0, 5) along -Z: hit at distance 4, point (0, 0, 1), normal (0, 0, 1). Off
// axis from (0.3, 0.4, 5): z = sqrt(1 - 0.25) = 0.8660254, distance 5 - z, normal = the
// point; the point lies exactly on the surface (|p| = 1 to float rounding).
TEST(RayTracer, SphereHitFromOutside) {
  const Scene scene = unit_sphere_scene();
  const RayTracer tracer(scene);
  const auto hit = tracer.intersect({Vec3(0, 0, 5), Vec3(0, 0, -1)});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->distance, 4.0f, 1e-6f);
  expect_vec_near(hit->position, Vec3(0, 0, 1), 1e-6f, "position");
  expect_vec_near(hit->normal, Vec3(0, 0, 1), 1e-6f, "normal");
  expect_vec_near(hit->geometric_normal, Vec3(0, 0, 1), 1e-6f, "geometric normal");
  EXPECT_EQ(hit->material, 0);

  const auto off = tracer.intersect({Vec3(0.3f, 0.4f, 5), Vec3(0, 0, -1)});
  ASSERT_TRUE(off.has_value());
  const float z = std::sqrt(0.75f);
  EXPECT_NEAR(off->distance, 5.0f - z, 1e-6f);
  expect_vec_near(off->position, Vec3(0.3f, 0.4f, z), 1e-6f, "position");
  expect_vec_near(off->normal, Vec3(0.3f, 0.4f, z), 1e-6f, "normal");
  EXPECT_NEAR(off->position.norm(), 1.0f, 1e-6f);
  EXPECT_NEAR(off->normal.norm(), 1.0f, 1e-6f);

  // Nothing behind the ray, and nothing beyond max_distance.
  EXPECT_FALSE(tracer.intersect({Vec3(0, 0, 5), Vec3(0, 0, 1)}).has_value());
  EXPECT_FALSE(tracer.intersect({Vec3(0, 0, 5), Vec3(0, 0, -1)}, 3.9f).has_value());
}

// From the centre along +X: the far side at distance 1, point (1, 0, 0), the outward
// normal (1, 0, 0) turned to face the ray: (-1, 0, 0). From (0.5, 0, 0) along +Y: y =
// sqrt(0.75), normal -(0.5, sqrt(0.75), 0).
TEST(RayTracer, SphereHitFromInsideHasNormalFacingTheRay) {
  const Scene scene = unit_sphere_scene();
  const RayTracer tracer(scene);
  const auto hit = tracer.intersect({Vec3(0, 0, 0), Vec3(1, 0, 0)});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->distance, 1.0f, 1e-6f);
  expect_vec_near(hit->position, Vec3(1, 0, 0), 1e-6f, "position");
  expect_vec_near(hit->normal, Vec3(-1, 0, 0), 1e-6f, "normal");
  expect_vec_near(hit->geometric_normal, Vec3(-1, 0, 0), 1e-6f, "geometric normal");

  const auto off = tracer.intersect({Vec3(0.5f, 0, 0), Vec3(0, 1, 0)});
  ASSERT_TRUE(off.has_value());
  const float y = std::sqrt(0.75f);
  EXPECT_NEAR(off->distance, y, 1e-6f);
  expect_vec_near(off->position, Vec3(0.5f, y, 0), 1e-6f, "position");
  expect_vec_near(off->normal, Vec3(-0.5f, -y, 0), 1e-6f, "normal");
}

// The batched intersection (SIMD lanes for a lone sphere) agrees with the one-ray
// intersection: hit or miss, normal facing the ray, texture coordinates of the outward
// normal in the sphere's own frame; for rays from outside, inside and grazing the
// silhouette, and for a batch shorter than the lanes.
TEST(RayTracer, BatchedSphereHitsMatchOneRayAtATime) {
  Scene scene = unit_sphere_scene();
  scene.spheres.front().center = Vec3(0.2f, -0.1f, 0.3f);
  scene.spheres.front().rotation = Eigen::AngleAxisf(0.7f, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const RayTracer tracer(scene);
  Pcg32 rng(5);
  for (int batch = 0; batch < 200; ++batch) {
    const int count = batch % 2 ? kLanes : 1 + batch % kLanes;
    std::array<Ray, kLanes> rays;
    for (int k = 0; k < count; ++k) {
      const Vec3 origin =
          batch % 3 == 0 ? Vec3(0.2f, -0.1f, 0.3f) + 0.5f * Vec3(rng.next_float(), rng.next_float(), rng.next_float())
                         : Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, 4.0f);
      const Vec3 target = Vec3(0.2f, -0.1f, 0.3f) +
                          2.2f * Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
      rays[k] = {origin, (target - origin).normalized()};
    }
    SurfaceHits hits;
    tracer.intersect(rays.data(), count, hits, true);
    for (int k = 0; k < count; ++k) {
      const auto one = tracer.intersect(rays[k]);
      ASSERT_EQ(hits.hit[k] != 0, one.has_value()) << "batch " << batch << " lane " << k;
      if (!one) continue;
      expect_vec_near(hits.normal[k], one->normal, 1e-6f, "normal");
      EXPECT_EQ(hits.material[k], one->material);
      EXPECT_NEAR(hits.uv[k].x(), one->uv.x(), 1e-6f);
      EXPECT_NEAR(hits.uv[k].y(), one->uv.y(), 1e-6f);
    }
  }
}

// A ray passing 1e-3 outside the silhouette misses; one passing 1e-3 inside hits, at
// z = sqrt(1 - 0.999^2) = 0.0447102.
TEST(RayTracer, GrazingRaysMissOutsideAndHitInside) {
  const Scene scene = unit_sphere_scene();
  const RayTracer tracer(scene);
  EXPECT_FALSE(tracer.intersect({Vec3(0, 1.001f, 5), Vec3(0, 0, -1)}).has_value());
  EXPECT_FALSE(tracer.occluded({Vec3(0, 1.001f, 5), Vec3(0, 0, -1)}));
  const auto hit = tracer.intersect({Vec3(0, 0.999f, 5), Vec3(0, 0, -1)});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->distance, 5.0f - 0.0447102f, 1e-4f);
  EXPECT_NEAR(hit->position.norm(), 1.0f, 1e-6f);
}

// From (0, 0, 5) along -Z the sphere starts at distance 4: a segment of length 10 is
// blocked, one of length 3.9 is not; a ray pointing away is not.
TEST(RayTracer, OccludedOnlyWhenTheSegmentReachesTheSphere) {
  const Scene scene = unit_sphere_scene();
  const RayTracer tracer(scene);
  EXPECT_TRUE(tracer.occluded({Vec3(0, 0, 5), Vec3(0, 0, -1)}, 10.0f));
  EXPECT_TRUE(tracer.occluded({Vec3(0, 0, 5), Vec3(0, 0, -1)}));
  EXPECT_FALSE(tracer.occluded({Vec3(0, 0, 5), Vec3(0, 0, -1)}, 3.9f));
  EXPECT_FALSE(tracer.occluded({Vec3(0, 0, 5), Vec3(0, 0, 1)}));
}

// The quad (0,0,0) (2,0,0) (2,2,0) (0,2,0), triangles (0,1,2) (0,2,3), uvs (0,0) (1,0)
// (1,1) (0,1), and per-vertex normals n0 = (0,0,1), n1 = (1,0,1)/sqrt2,
// n2 = (0,1,1)/sqrt2, n3 = (-1,0,1)/sqrt2.
// Point (1.5, 0.5) in triangle (0,1,2): x = 2(b1 + b2), y = 2 b2 -> b2 = 0.25, b1 = 0.5,
// b0 = 0.25; uv = 0.5 (1,0) + 0.25 (1,1) = (0.75, 0.25); normal ∝ 0.25 n0 + 0.5 n1 + 0.25 n2
// = (0.5/sqrt2, 0.25/sqrt2, 0.25 + 0.75/sqrt2).
// Point (0.5, 1.5) in triangle (0,2,3): x = 2 b2', y = 2 b2' + 2 b3 -> b2' = 0.25,
// b3 = 0.5, b0 = 0.25; uv = 0.25 (1,1) + 0.5 (0,1) = (0.25, 0.75); normal ∝
// 0.25 n0 + 0.25 n2 + 0.5 n3 = (-0.5/sqrt2, 0.25/sqrt2, 0.25 + 0.75/sqrt2).
TEST(RayTracer, TriangleHitInterpolatesUvAndShadingNormal) {
  Scene scene;
  scene.materials.push_back(SceneMaterial{"white", 0.04f, RGB::Ones(), -1});
  TriangleMesh quad;
  quad.positions = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
  const float r = 1.0f / std::sqrt(2.0f);
  quad.normals = {{0, 0, 1}, {r, 0, r}, {0, r, r}, {-r, 0, r}};
  quad.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  scene.meshes.push_back(quad);
  const RayTracer tracer(scene);

  const auto first = tracer.intersect({Vec3(1.5f, 0.5f, 3), Vec3(0, 0, -1)});
  ASSERT_TRUE(first.has_value());
  EXPECT_NEAR(first->distance, 3.0f, 1e-5f);
  expect_vec_near(first->position, Vec3(1.5f, 0.5f, 0), 1e-5f, "position");
  EXPECT_NEAR(first->uv.x(), 0.75f, 1e-5f);
  EXPECT_NEAR(first->uv.y(), 0.25f, 1e-5f);
  const Vec3 n_first = Vec3(0.5f * r, 0.25f * r, 0.25f + 0.75f * r).normalized();
  expect_vec_near(first->normal, n_first, 1e-5f, "shading normal");
  expect_vec_near(first->geometric_normal, Vec3(0, 0, 1), 1e-6f, "geometric normal");

  const auto second = tracer.intersect({Vec3(0.5f, 1.5f, 3), Vec3(0, 0, -1)});
  ASSERT_TRUE(second.has_value());
  EXPECT_NEAR(second->uv.x(), 0.25f, 1e-5f);
  EXPECT_NEAR(second->uv.y(), 0.75f, 1e-5f);
  const Vec3 n_second = Vec3(-0.5f * r, 0.25f * r, 0.25f + 0.75f * r).normalized();
  expect_vec_near(second->normal, n_second, 1e-5f, "shading normal");

  // From below, the surface is two-sided: both normals turn to face the ray.
  const auto below = tracer.intersect({Vec3(1.5f, 0.5f, -3), Vec3(0, 0, 1)});
  ASSERT_TRUE(below.has_value());
  expect_vec_near(below->geometric_normal, Vec3(0, 0, -1), 1e-6f, "geometric normal from below");
  expect_vec_near(below->normal, -n_first, 1e-5f, "shading normal from below");
  EXPECT_NEAR(below->uv.x(), 0.75f, 1e-5f);

  EXPECT_FALSE(tracer.intersect({Vec3(2.5f, 0.5f, 3), Vec3(0, 0, -1)}).has_value());  // beside the quad
}

// The batched form on a scene Embree traverses (not a lone sphere): the rays given, one
// at a time, and the lanes past `count` a copy of the last one.
TEST(RayTracer, BatchedMeshHitsMatchOneRayAtATime) {
  Scene scene;
  scene.materials.push_back(SceneMaterial{"white", 0.04f, RGB::Ones(), -1});
  TriangleMesh quad;
  quad.positions = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
  quad.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  scene.meshes.push_back(quad);
  const RayTracer tracer(scene);
  Pcg32 rng(6);
  for (int count : {1, 5, kLanes}) {
    std::array<Ray, kLanes> rays;
    for (int k = 0; k < count; ++k)
      rays[k] = {Vec3(3.0f * rng.next_float() - 0.5f, 3.0f * rng.next_float() - 0.5f, 3), Vec3(0, 0, -1)};
    SurfaceHits hits;
    tracer.intersect(rays.data(), count, hits, true);
    for (int k = 0; k < kLanes; ++k) {
      const auto one = tracer.intersect(rays[std::min(k, count - 1)]);
      ASSERT_EQ(hits.hit[k] != 0, one.has_value()) << "count " << count << " lane " << k;
      if (one) expect_vec_near(hits.normal[k], one->normal, 0.0f, "normal");
    }
  }
}

// A quad (0,0,0) (1,0,0) (1,1,0) (0,1,0), counter-clockwise seen from +Z, with explicit
// NORMAL (0, 0, 1), under a node with scale (-1, 1, 1) (a mirror, as exporters write for
// mirrored copies). The normal matrix diag(-1, 1, 1)^-T keeps (0, 0, 1), and glTF says a
// negative determinant flips the winding, so the front is still +Z. A ray from above at
// (-0.25, 0.75, 2) must see both normals facing it, (0, 0, 1); from below, both (0, 0, -1):
// the shading normal must never end up on the other side of the surface from the
// geometric normal.
TEST(RayTracer, MirroredMeshKeepsShadingNormalOnTheSideOfTheRay) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const int positions = buffer.floats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, 3);
  const int normals = buffer.floats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, 3);
  const int indices = buffer.indices({0, 1, 2, 0, 2, 3});
  json gltf = gltf_document({{{"mesh", 0}, {"scale", {-1, 1, 1}}}}, {0});
  gltf["meshes"] = {
      {{"primitives", {{{"attributes", {{"POSITION", positions}, {"NORMAL", normals}}}, {"indices", indices}}}}}};
  buffer.into(gltf);
  const Scene scene = load_scene(write_gltf(dir, "mirrored.gltf", gltf));
  ASSERT_EQ(scene.meshes.size(), 1u);
  for (const Vec3& n : scene.meshes[0].normals) expect_vec_near(n, Vec3(0, 0, 1), 1e-6f, "loaded normal");
  const RayTracer tracer(scene);
  const auto above = tracer.intersect({Vec3(-0.25f, 0.75f, 2), Vec3(0, 0, -1)});
  ASSERT_TRUE(above.has_value());
  EXPECT_NEAR(above->distance, 2.0f, 1e-5f);
  expect_vec_near(above->geometric_normal, Vec3(0, 0, 1), 1e-6f, "geometric normal from above");
  expect_vec_near(above->normal, Vec3(0, 0, 1), 1e-6f, "shading normal from above");
  const auto below = tracer.intersect({Vec3(-0.25f, 0.75f, -2), Vec3(0, 0, 1)});
  ASSERT_TRUE(below.has_value());
  expect_vec_near(below->geometric_normal, Vec3(0, 0, -1), 1e-6f, "geometric normal from below");
  expect_vec_near(below->normal, Vec3(0, 0, -1), 1e-6f, "shading normal from below");
}

// One analytic sphere and nothing else is a single convex object; two spheres, a sphere
// with a mesh, or a mesh alone are not. Also through load_scene.
TEST(RayTracer, SingleConvexObjectIsExactlyOneSphere) {
  Scene one = unit_sphere_scene();
  EXPECT_TRUE(one.is_single_convex_object());
  Scene two = unit_sphere_scene();
  two.spheres.push_back(Sphere{"second", Vec3(3, 0, 0), 1.0f, 0});
  EXPECT_FALSE(two.is_single_convex_object());
  Scene with_mesh = unit_sphere_scene();
  TriangleMesh triangle;
  triangle.positions = {{0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
  triangle.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  triangle.triangles = {{0, 1, 2}};
  with_mesh.meshes.push_back(triangle);
  EXPECT_FALSE(with_mesh.is_single_convex_object());
  Scene mesh_only = with_mesh;
  mesh_only.spheres.clear();
  EXPECT_FALSE(mesh_only.is_single_convex_object());

  testing::TemporaryDirectory dir;
  EXPECT_TRUE(
      load_scene(write_gltf(dir, "one.gltf", gltf_document({sphere_node(1.0)}, {0}))).is_single_convex_object());
  json second = sphere_node(1.0);
  second["translation"] = {3, 0, 0};
  EXPECT_FALSE(load_scene(write_gltf(dir, "two.gltf", gltf_document({sphere_node(1.0), second}, {0, 1})))
                   .is_single_convex_object());
}

// ---------------------------------------------------------------------------------------
// 6. Bad scenes: a glaze::Error naming the fault from load_scene, and from the command a
// clear "glaze: error:" with exit status 1, never a crash.
// ---------------------------------------------------------------------------------------

// A valid triangle scene with a camera and a small constant environment, for the
// command line; the tests below break one thing in it.
json renderable_triangle_scene(GltfBuffer& buffer) {
  const int positions = buffer.floats({-1, -1, 0, 1, -1, 0, 0, 1, 0}, 3);
  const int indices = buffer.indices({0, 1, 2});
  json gltf = gltf_document({{{"mesh", 0}}, {{"camera", 0}, {"translation", {0, 0, 5}}}}, {0, 1});
  gltf["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", positions}}}, {"indices", indices}}}}}};
  gltf["cameras"] = {{{"name", "main"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}};
  gltf["scenes"][0]["extras"] = {
      {"glaze", {{"environment", {{"procedural", "constant"}, {"width", 16}, {"height", 8}}}}}};
  buffer.into(gltf);
  return gltf;
}

// The unbroken scene renders: the failures below are due to the one fault each.
TEST(BadScene, TheUnbrokenSceneRenders) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const std::string path = write_gltf(dir, "good.gltf", renderable_triangle_scene(buffer));
  EXPECT_NO_THROW(load_scene(path));
  const CommandResult run =
      run_glaze("render " + quoted(path) + " --out " + quoted(dir.file("good.exr")) + " --res 8x8 --spp 1", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(std::filesystem::exists(dir.file("good.exr")));
}

// The buffer is an external missing.bin that does not exist: the error names it.
TEST(BadScene, MissingBufferFile) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = renderable_triangle_scene(buffer);
  gltf["buffers"][0]["uri"] = "missing.bin";
  const std::string path = write_gltf(dir, "bad.gltf", gltf);
  expect_load_error(dir, path, {"bad.gltf", "missing.bin"});
  testing::expect_render_refused(dir, path, "missing.bin");
}

// The same buffer as a real .bin file that is too short (truncated): an error, no crash.
TEST(BadScene, TruncatedBufferFile) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = renderable_triangle_scene(buffer);
  const std::vector<unsigned char>& bytes = buffer.bytes();
  std::ofstream(dir.file("short.bin"), std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), 20);
  gltf["buffers"][0]["uri"] = "short.bin";
  const std::string path = write_gltf(dir, "bad.gltf", gltf);
  expect_load_error(dir, path, {"bad.gltf"});
  testing::expect_render_refused(dir, path, "bad.gltf");
}

// POSITION refers to accessor 7 of 2: the error says "accessor".
TEST(BadScene, AccessorIndexOutOfRange) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = renderable_triangle_scene(buffer);
  gltf["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7;
  const std::string path = write_gltf(dir, "bad.gltf", gltf);
  expect_load_error(dir, path, {"accessor", "7"});
  testing::expect_render_refused(dir, path, "accessor");

  gltf = renderable_triangle_scene(buffer);
  gltf["meshes"][0]["primitives"][0]["indices"] = 9;  // the index accessor too
  const std::string indices_path = write_gltf(dir, "bad_indices.gltf", gltf);
  expect_load_error(dir, indices_path, {"accessor"});
  testing::expect_render_refused(dir, indices_path, "accessor");
}

// Three vertices, an index 5: "out of range".
TEST(BadScene, IndexValueNotBelowVertexCount) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const int positions = buffer.floats({-1, -1, 0, 1, -1, 0, 0, 1, 0}, 3);
  const int indices = buffer.indices({0, 1, 5});
  json gltf = renderable_triangle_scene(buffer);  // appends its own accessors after ours
  gltf["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = positions;
  gltf["meshes"][0]["primitives"][0]["indices"] = indices;
  const std::string path = write_gltf(dir, "bad.gltf", gltf);
  expect_load_error(dir, path, {"index 5", "out of range"});
  testing::expect_render_refused(dir, path, "out of range");

  // Exactly the vertex count (3) is one too many.
  GltfBuffer buffer3;
  const int positions3 = buffer3.floats({-1, -1, 0, 1, -1, 0, 0, 1, 0}, 3);
  const int indices3 = buffer3.indices({0, 1, 3});
  json gltf3 = renderable_triangle_scene(buffer3);
  gltf3["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = positions3;
  gltf3["meshes"][0]["primitives"][0]["indices"] = indices3;
  expect_load_error(dir, write_gltf(dir, "bad3.gltf", gltf3), {"out of range"});
}

// Node 0 -> node 2 -> node 0: a cycle. Also a node that is its own child.
TEST(BadScene, NodeHierarchyWithACycle) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = renderable_triangle_scene(buffer);
  gltf["nodes"].push_back({{"children", {0}}});  // node 2
  gltf["nodes"][0]["children"] = {2};
  const std::string path = write_gltf(dir, "bad.gltf", gltf);
  expect_load_error(dir, path, {"cycle"});
  testing::expect_render_refused(dir, path, "cycle");

  gltf = renderable_triangle_scene(buffer);
  gltf["nodes"][1]["children"] = {1};
  const std::string self = write_gltf(dir, "self.gltf", gltf);
  expect_load_error(dir, self, {"cycle"});
  testing::expect_render_refused(dir, self, "cycle");
}

// A file without "scenes" (every root node is drawn) whose nodes form a cycle 0 -> 1 -> 0,
// node 0 carrying a sphere: no node is a root, but the fault is the cycle, and the error
// should say so rather than that there is no geometry.
TEST(BadScene, NodeCycleInAFileWithoutScenes) {
  testing::TemporaryDirectory dir;
  json sphere = sphere_node(1.0);
  sphere["children"] = {1};
  json gltf = {{"asset", {{"version", "2.0"}}}};
  gltf["nodes"] = std::vector<json>{sphere, {{"children", {0}}}};
  const std::string path = write_gltf(dir, "loop.gltf", gltf);
  expect_load_error(dir, path, {"cycle"});
}

// baseColorTexture whose image nothere.png does not exist: the error names the file.
TEST(BadScene, MissingTextureImage) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const int uvs = buffer.floats({0, 0, 1, 0, 0.5, 1}, 2);
  json gltf = renderable_triangle_scene(buffer);
  gltf["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = uvs;
  gltf["meshes"][0]["primitives"][0]["material"] = 0;
  gltf["materials"] = json::array({quiet_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}})});
  gltf["textures"] = {{{"source", 0}}};
  gltf["images"] = {{{"uri", "nothere.png"}}};
  const std::string path = write_gltf(dir, "bad.gltf", gltf);
  expect_load_error(dir, path, {"image", "nothere.png"});
  testing::expect_render_refused(dir, path, "nothere.png");
}

// --camera nope on a good scene: the error names it and lists the camera "main".
TEST(BadScene, UnknownCameraOnTheCommandLine) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const std::string path = write_gltf(dir, "good.gltf", renderable_triangle_scene(buffer));
  testing::expect_render_refused(dir, path, "nope", "--camera nope");
  const CommandResult run =
      run_glaze("render " + quoted(path) + " --out " + quoted(dir.file("x.exr")) + " --camera nope", dir);
  EXPECT_NE(without_directory(run.err, dir).find("main"), std::string::npos) << run.err;
}

// A scene path that does not exist.
TEST(BadScene, NonExistentScenePath) {
  testing::TemporaryDirectory dir;
  const std::string path = dir.file("absent.gltf");
  expect_load_error(dir, path, {"absent.gltf", "no such"});
  testing::expect_render_refused(dir, path, "absent.gltf");
}

// A .gltf that is not JSON, and an empty one.
TEST(BadScene, FileThatIsNotJson) {
  testing::TemporaryDirectory dir;
  const std::string path = write_text(dir, "text.gltf", "this is not { json at all, just some words\n");
  expect_load_error(dir, path, {"text.gltf", "glTF"});
  testing::expect_render_refused(dir, path, "text.gltf");
  const std::string empty = write_text(dir, "empty.gltf", "");
  expect_load_error(dir, empty, {"empty.gltf"});
  testing::expect_render_refused(dir, empty, "empty.gltf");
}

// ---------------------------------------------------------------------------------------
// 7. Capture sets: glaze render --captures.
// ---------------------------------------------------------------------------------------

// Sphere of radius 0.5 at (0.1, 0.2, 0.3), material R0 0.05, Rd (0.6, 0.5, 0.4), and
// three cameras 4 units from its centre, each looking straight at it:
//   cam_a at (0.1, 0.2, 4.3), no rotation (looks along -Z);
//   cam_b at (4.1, 0.2, 0.3), Ry(+90) (camera -Z -> world -X);
//   cam_c at (0.1, 4.2, 0.3), Rx(-90) (camera -Z -> world -Y).
// Camera-to-world matrices by hand (columns are the camera axes in world space):
//   Ry(90) = [[0,0,1],[0,1,0],[-1,0,0]], Rx(-90) = [[1,0,0],[0,0,1],[0,-1,0]].
// yfov 0.7 rad; at 32x32 fl = 16/tan(0.35). The sphere subtends asin(0.5/4) = 7.2 deg
// around the image centre, so the centre pixel sees it and the corners (about 26 deg off
// axis) see the background, black in a capture set.
TEST(CaptureSet, RenderCapturesWritesTransformsAndViews) {
  testing::TemporaryDirectory dir;
  json sphere = sphere_node(0.5, 0);
  sphere["translation"] = {0.1, 0.2, 0.3};
  const std::vector<json> nodes = {sphere,
                                   {{"camera", 0}, {"translation", {0.1, 0.2, 4.3}}},
                                   {{"camera", 1}, {"translation", {4.1, 0.2, 0.3}}, {"rotation", {0, kS, 0, kS}}},
                                   {{"camera", 2}, {"translation", {0.1, 4.2, 0.3}}, {"rotation", {-kS, 0, 0, kS}}}};
  json gltf = gltf_document(nodes, {0, 1, 2, 3});
  gltf["materials"] = json::array({quiet_material({{"extras", {{"glaze", {{"R0", 0.05}, {"Rd", {0.6, 0.5, 0.4}}}}}}})});
  json cameras = json::array();
  for (const char* name : {"cam_a", "cam_b", "cam_c"})
    cameras.push_back({{"name", name}, {"type", "perspective"}, {"perspective", {{"yfov", 0.7}, {"znear", 0.1}}}});
  gltf["cameras"] = cameras;
  gltf["scenes"][0]["extras"] = {
      {"glaze", {{"environment", {{"procedural", "constant"}, {"width", 16}, {"height", 8}}}}}};
  const std::string scene = write_gltf(dir, "sphere.gltf", gltf);
  const std::filesystem::path out = dir.path() / "captures";

  const CommandResult run = run_glaze(
      "render " + quoted(scene) + " --captures " + quoted(out.string()) + " --holdout cam_b --res 32x32 --spp 2", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;

  const auto read_json = [](const std::filesystem::path& path) {
    std::ifstream stream(path);
    EXPECT_TRUE(stream.good()) << path;
    return json::parse(stream);
  };
  const auto expect_pose = [](const json& matrix, const std::array<std::array<float, 4>, 4>& expected,
                              const std::string& what) {
    ASSERT_EQ(matrix.size(), 4u) << what;
    for (int r = 0; r < 4; ++r) {
      ASSERT_EQ(matrix[r].size(), 4u) << what;
      for (int c = 0; c < 4; ++c)
        EXPECT_NEAR(matrix[r][c].get<double>(), expected[r][c], 1e-5) << what << " (" << r << "," << c << ")";
    }
  };
  const std::array<std::array<float, 4>, 4> pose_a = {
      {{1, 0, 0, 0.1f}, {0, 1, 0, 0.2f}, {0, 0, 1, 4.3f}, {0, 0, 0, 1}}};
  const std::array<std::array<float, 4>, 4> pose_b = {
      {{0, 0, 1, 4.1f}, {0, 1, 0, 0.2f}, {-1, 0, 0, 0.3f}, {0, 0, 0, 1}}};
  const std::array<std::array<float, 4>, 4> pose_c = {
      {{1, 0, 0, 0.1f}, {0, 0, 1, 4.2f}, {0, -1, 0, 0.3f}, {0, 0, 0, 1}}};
  const double fl = 16.0 / std::tan(0.35);

  // The training set: cam_a and cam_c, in scene order.
  const json transforms = read_json(out / "transforms.json");
  EXPECT_EQ(transforms["w"], 32);
  EXPECT_EQ(transforms["h"], 32);
  EXPECT_NEAR(transforms["fl_x"].get<double>(), fl, 1e-3);
  EXPECT_NEAR(transforms["fl_y"].get<double>(), fl, 1e-3);
  EXPECT_NEAR(transforms["cx"].get<double>(), 16.0, 1e-6);
  EXPECT_NEAR(transforms["cy"].get<double>(), 16.0, 1e-6);
  ASSERT_EQ(transforms["frames"].size(), 2u);
  expect_pose(transforms["frames"][0]["transform_matrix"], pose_a, "cam_a");
  expect_pose(transforms["frames"][1]["transform_matrix"], pose_c, "cam_c");

  const json& object = transforms["object"];
  EXPECT_EQ(object["type"], "sphere");
  ASSERT_EQ(object["center"].size(), 3u);
  EXPECT_NEAR(object["center"][0].get<double>(), 0.1, 1e-6);
  EXPECT_NEAR(object["center"][1].get<double>(), 0.2, 1e-6);
  EXPECT_NEAR(object["center"][2].get<double>(), 0.3, 1e-6);
  EXPECT_NEAR(object["radius"].get<double>(), 0.5, 1e-6);

  ASSERT_TRUE(transforms.contains("material"));
  EXPECT_NEAR(transforms["material"]["R0"].get<double>(), 0.05, 1e-6);
  ASSERT_EQ(transforms["material"]["Rd"].size(), 3u);
  EXPECT_NEAR(transforms["material"]["Rd"][0].get<double>(), 0.6, 1e-6);
  EXPECT_NEAR(transforms["material"]["Rd"][1].get<double>(), 0.5, 1e-6);
  EXPECT_NEAR(transforms["material"]["Rd"][2].get<double>(), 0.4, 1e-6);

  ASSERT_TRUE(transforms.contains("environment"));
  EXPECT_EQ(transforms["environment"]["file"], "environment.exr");
  EXPECT_TRUE(std::filesystem::exists(out / "environment.exr"));
  EXPECT_NEAR(transforms["environment"].value("scale", -1.0), 1.0, 1e-9);
  EXPECT_NEAR(transforms["environment"].value("rotation", -1.0), 0.0, 1e-9);

  // The typed reader gives back the same set: what invert-fit reads.
  const CaptureSet set = read_transforms(out.string());
  ASSERT_TRUE(std::holds_alternative<CaptureSphere>(set.object));
  EXPECT_TRUE(std::get<CaptureSphere>(set.object).center.isApprox(Vec3(0.1f, 0.2f, 0.3f), 1e-6f));
  EXPECT_NEAR(std::get<CaptureSphere>(set.object).radius, 0.5f, 1e-6f);
  ASSERT_TRUE(set.material.has_value());
  EXPECT_EQ(set.material->material.R0(), 0.05f);
  EXPECT_TRUE((set.material->material.Rd() == RGB(0.6f, 0.5f, 0.4f)).all());
  EXPECT_EQ(set.material->texture, "");
  ASSERT_TRUE(set.environment.has_value());
  EXPECT_EQ(set.environment->file, (out / "environment.exr").string());
  EXPECT_EQ(set.environment->procedural, "constant");
  EXPECT_EQ(set.environment->options.scale, 1.0f);
  EXPECT_TRUE(set.environment->options.to_world == Mat3::Identity());
  ASSERT_TRUE(set.renderer.has_value());
  EXPECT_EQ(set.renderer->integrator, CaptureRenderer::Integrator::path);
  EXPECT_EQ(set.renderer->spp, 2);

  // The held-out set: cam_b alone; its environment entry still leads to the map.
  const json holdout = read_json(out / "holdout" / "transforms.json");
  ASSERT_EQ(holdout["frames"].size(), 1u);
  expect_pose(holdout["frames"][0]["transform_matrix"], pose_b, "cam_b");
  EXPECT_EQ(holdout["w"], 32);
  ASSERT_TRUE(holdout.contains("environment"));
  EXPECT_TRUE(std::filesystem::exists(out / "holdout" / holdout["environment"]["file"].get<std::string>()))
      << holdout["environment"];

  // Every view: background corners exactly 0, the object at the centre > 0.
  std::vector<std::filesystem::path> views;
  for (const json& frame : transforms["frames"]) views.push_back(out / frame["file_path"].get<std::string>());
  for (const json& frame : holdout["frames"]) views.push_back(out / "holdout" / frame["file_path"].get<std::string>());
  ASSERT_EQ(views.size(), 3u);
  for (const auto& view : views) {
    ASSERT_TRUE(std::filesystem::exists(view)) << view;
    const Image image = read_image(view.string());
    ASSERT_EQ(image.width, 32) << view;
    ASSERT_EQ(image.height, 32) << view;
    for (const auto& [x, y] : {std::pair{0, 0}, std::pair{31, 0}, std::pair{0, 31}, std::pair{31, 31}})
      for (int c = 0; c < 3; ++c) EXPECT_EQ(image.at(x, y)[c], 0.0f) << view << " corner " << x << "," << y;
    for (int c = 0; c < 3; ++c) EXPECT_GT(image.at(16, 16)[c], 0.0f) << view << " centre";
  }
}

// An unknown --holdout name fails before anything is rendered.
TEST(CaptureSet, UnknownHoldoutCameraIsAnError) {
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  const std::string scene = write_gltf(dir, "good.gltf", renderable_triangle_scene(buffer));
  const CommandResult run = run_glaze(
      "render " + quoted(scene) + " --captures " + quoted(dir.file("caps")) + " --holdout nope --res 8x8 --spp 1", dir);
  EXPECT_FALSE(run.crashed) << run.err;
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(without_directory(run.err, dir).find("nope"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "caps" / "transforms.json"));
}

}  // namespace
}  // namespace glaze
