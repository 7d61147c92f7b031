// hostile_gltf_test.cpp: glTF files written to break the loader (issue 42): counts and
// offsets that wrap 64-bit sums, texture coordinates of 3e38 and NaN, hierarchies
// 100,000 nodes deep, JSON nested 100,000 levels, indices of 1e300 or 2^32, cameras
// turned away by a negative scale. Each must end in a glaze::Error naming what is wrong
// (exit status 1 from the command line), a warning, or a correct result: never a crash,
// undefined behaviour or a silent default.
#include "gltf_builder.h"

#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/memory_budget.h"
#include "renderer/scene.h"
#include "renderer/texture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace glaze {
namespace {

using testing::CommandResult;
using testing::expect_clear_failure;
using testing::GltfBuffer;
using testing::json;
using testing::quoted;
using testing::run_glaze;

// One triangle (POSITION accessor 0, TEXCOORD_0 accessor 1, indices accessor 2) with a
// 2x2 PNG texture, seen by a camera at (0, 0, 3) under a constant environment.
json textured_triangle(GltfBuffer& buffer, const std::vector<float>& uvs = {0, 0, 1, 0, 0, 1}) {
  const int positions = buffer.floats({-1, -1, 0, 1, -1, 0, 0, 1, 0}, 3);
  const int texcoords = buffer.floats(uvs, 2);
  const int indices = buffer.indices({0, 1, 2});
  json gltf = testing::gltf_document({{{"mesh", 0}}, {{"camera", 0}, {"translation", {0, 0, 3}}}}, {0, 1});
  json primitive = {
      {"attributes", {{"POSITION", positions}, {"TEXCOORD_0", texcoords}}}, {"indices", indices}, {"material", 0}};
  gltf["meshes"] = json::array({{{"primitives", json::array({primitive})}}});
  gltf["materials"] =
      json::array({testing::quiet_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}})});
  gltf["textures"] = json::array({{{"source", 0}}});
  const std::vector<unsigned char> png = testing::encode_png(2, 2, {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255});
  gltf["images"] = json::array({{{"uri", "data:image/png;base64," + testing::base64(png)}}});
  gltf["cameras"] = json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}});
  gltf["scenes"][0]["extras"] = {
      {"glaze", {{"environment", {{"procedural", "constant"}, {"width", 16}, {"height", 8}}}}}};
  buffer.into(gltf);
  return gltf;
}

// Loads `gltf` (written to a file), expecting an Error that mentions every word.
void expect_refused(const json& gltf, const std::vector<std::string>& words) {
  testing::TemporaryDirectory dir;
  testing::expect_load_error(dir, testing::write_gltf(dir, "hostile.gltf", gltf), words);
}

constexpr uint64_t kWrapsVec3 = 6148914691236517206u;  // (2^64 + 2) / 3: count * 3 wraps to 2
constexpr uint64_t kWrapsVec2 = 9223372036854775809u;  // 2^63 + 1: count * 2 wraps to 2

// 1.1: accessor counts beyond their bufferView, including counts whose byte sizes wrap
// modulo 2^64 (the old check passed them and wrote past a 2-float vector).
TEST(HostileGltf, AccessorCountBeyondItsView) {
  const std::vector<std::pair<int, uint64_t>> cases = {
      {0, kWrapsVec3}, {0, uint64_t(1e9)}, {0, 4},  // POSITION VEC3 (the view holds 3)
      {1, kWrapsVec2}, {1, uint64_t(1e9)}, {1, 4},  // TEXCOORD_0 VEC2
      {2, kWrapsVec2}, {2, uint64_t(1e9)}, {2, 5},  // indices SCALAR u16 (the view holds 3 + 1 padding)
  };
  for (const auto& [accessor, count] : cases) {
    SCOPED_TRACE("accessor " + std::to_string(accessor) + " count " + std::to_string(count));
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["accessors"][accessor]["count"] = count;
    expect_refused(gltf, {"accessor"});
  }
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = textured_triangle(buffer);
  gltf["accessors"][0]["count"] = kWrapsVec3;
  testing::expect_render_refused(dir, testing::write_gltf(dir, "wraps.gltf", gltf), "accessor");
  GltfBuffer fresh;
  gltf = textured_triangle(fresh);
  gltf["accessors"][1]["count"] = 4;
  testing::expect_render_refused(dir, testing::write_gltf(dir, "long.gltf", gltf), "accessor 1");
}

// 1.2: offsets near 2^64 (the old sum wrapped and passed), and ranges past the buffer.
TEST(HostileGltf, OffsetsThatWrapOrLeaveTheBuffer) {
  {
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["accessors"][0]["byteOffset"] = uint64_t(-4);
    expect_refused(gltf, {"accessors[0].byteOffset", "18446744073709551612"});
  }
  {
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["bufferViews"][0]["byteOffset"] = uint64_t(-8);
    expect_refused(gltf, {"bufferViews[0].byteOffset"});
  }
  {  // In range for a JSON number, far past the buffer: the view check refuses it.
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["bufferViews"][1]["byteOffset"] = uint64_t(1) << 52;
    expect_refused(gltf, {"accessor 1", "bufferView 1", "4503599627370496"});
  }
  {  // An accessor starting past the end of its view, with one element.
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["accessors"][0]["byteOffset"] = 40;
    gltf["accessors"][0]["count"] = 1;
    expect_refused(gltf, {"accessor 0", "byteOffset 40", "bufferView 0"});
  }
  {  // The texture's PNG in a bufferView that starts past the buffer's end: tinygltf hands
     // the callback a pointer beyond the buffer, which must never be read.
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    const std::vector<unsigned char> png = testing::encode_png(1, 1, {10, 20, 30});
    const int view = buffer.view(png.data(), png.size());
    buffer.into(gltf);
    gltf["images"][0] = {{"bufferView", view}, {"mimeType", "image/png"}};
    gltf["bufferViews"][view]["byteOffset"] = buffer.bytes().size() + 4096;
    expect_refused(gltf, {"image 0", "bufferView " + std::to_string(view)});
  }
}

// 1.3: texture coordinates far outside the image or not finite read inside it. Every
// float beyond 2^24 is a whole (even) number, so repeating and mirroring read as at 0,
// clamping as at 0 or 1; NaN and Inf read as at 0.
TEST(HostileGltf, TextureLookupAtHugeAndNonFiniteCoordinates) {
  Texture texture;
  texture.image = Image(4, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) texture.image.set(x, y, RGB(float(x + 1), float(10 * (y + 1)), 0.5f));
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<float> hostile = {1e30f, -1e30f, 3e38f, -3e38f, nan, inf, -inf};
  for (const Wrap wrap : {Wrap::repeat, Wrap::clamp, Wrap::mirrored_repeat}) {
    for (const bool nearest : {false, true}) {
      texture.wrap_u = texture.wrap_v = wrap;
      texture.nearest = nearest;
      for (const float u : hostile) {
        SCOPED_TRACE("wrap " + std::to_string(int(wrap)) + " nearest " + std::to_string(nearest) + " u " +
                     std::to_string(u));
        const bool finite = std::isfinite(u);
        const float expected_u = !finite ? 0.0f : wrap != Wrap::clamp ? 0.0f : u < 0 ? 0.0f : 1.0f;
        const RGB got = texture.lookup(Vec2(u, 0.25f)), expected = texture.lookup(Vec2(expected_u, 0.25f));
        ASSERT_TRUE(got.allFinite());
        for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(got[c], expected[c]);
        const RGB got_v = texture.lookup(Vec2(0.3f, u)), expected_v = texture.lookup(Vec2(0.3f, expected_u));
        for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(got_v[c], expected_v[c]);
        EXPECT_TRUE(texture.lookup(Vec2(u, u)).allFinite());
      }
    }
  }
}

// 1.3 through the renderer: vertex UVs of 3e38 and 1e30, and a KHR_texture_transform
// that takes ordinary UVs to 3e38, render with finite pixels.
TEST(HostileGltf, HugeTextureCoordinatesRender) {
  testing::TemporaryDirectory dir;
  GltfBuffer huge;
  const std::string huge_path =
      testing::write_gltf(dir, "huge.gltf", textured_triangle(huge, {3e38f, -3e38f, 1e30f, 3e38f, -1e30f, 0.5f}));
  GltfBuffer transformed;
  json gltf = textured_triangle(transformed);
  gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {
      {"KHR_texture_transform", {{"offset", {3e38, -3e38}}, {"scale", {1e30, 1e30}}}}};
  const std::string transformed_path = testing::write_gltf(dir, "transformed.gltf", gltf);
  for (const std::string& path : {huge_path, transformed_path}) {
    SCOPED_TRACE(path);
    const CommandResult run =
        run_glaze("render " + quoted(path) + " --out " + quoted(dir.file("out.exr")) + " --res 8x8 --spp 1", dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const Image image = read_image(dir.file("out.exr"));
    ASSERT_EQ(image.width, 8);
    for (float v : image.pixels) EXPECT_TRUE(std::isfinite(v));
  }
}

// 1.4: a chain of 100,000 nodes ends in a sphere at the sum of their translations.
TEST(HostileGltf, HundredThousandNestedNodes) {
  constexpr int kDepth = 100000;
  std::vector<json> nodes(kDepth);
  for (int i = 0; i < kDepth; ++i) {
    nodes[i] = {{"translation", {1, 2, -1}}};
    if (i + 1 < kDepth) nodes[i]["children"] = {i + 1};
  }
  nodes.back()["extras"] = {{"glaze", {{"sphere", {{"radius", 0.5}}}}}};
  testing::TemporaryDirectory dir;
  const std::string path = testing::write_text(dir, "deep.gltf", testing::gltf_document(nodes, {0}).dump());
  const Scene scene = load_scene(path);
  ASSERT_EQ(scene.spheres.size(), 1u);
  testing::expect_vec_near(scene.spheres[0].center, Vec3(kDepth, 2 * kDepth, -kDepth), 0.0f);

  // The same chain with a cycle at depth 50,000: the cycle's message.
  nodes.resize(50001);
  nodes.back()["children"] = {25000};
  testing::expect_load_error(dir, testing::write_text(dir, "cycle.gltf", testing::gltf_document(nodes, {0}).dump()),
                             {"node 25000", "cycle"});
}

// 1.4: extras nested 100,000 levels deep (as text: json's own dump() recurses) are
// refused before tinygltf's recursive walk sees them.
TEST(HostileGltf, DeeplyNestedExtras) {
  json gltf = testing::gltf_document({testing::sphere_node(1.0)}, {0});
  gltf["nodes"][0]["extras"]["deep"] = "DEEP";
  std::string text = gltf.dump();
  text.replace(text.find("\"DEEP\""), 6, std::string(100000, '[') + std::string(100000, ']'));
  testing::TemporaryDirectory dir;
  const std::string path = testing::write_text(dir, "deep.gltf", text);
  testing::expect_load_error(dir, path, {"deep.gltf", "nested deeper than 100"});
  testing::expect_render_refused(dir, path, "nested deeper than 100");
}

// 1.5: indices that are not whole numbers in range are refused with their JSON path
// (tinygltf skipped 1e300 and "0", giving the default material, and wrapped 2^32 to 0).
TEST(HostileGltf, IndicesThatAreNotIndices) {
  for (const json& material : {json(1e300), json(4294967296u), json(-2), json(2.5), json("0")}) {
    SCOPED_TRACE(material.dump());
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["meshes"][0]["primitives"][0]["material"] = material;
    expect_refused(gltf, {"meshes[0].primitives[0].material", "must be an index", material.dump()});
  }
  {
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 4294967296u;
    expect_refused(gltf, {"texCoord", "4294967296"});
  }
  {
    GltfBuffer buffer;
    json gltf = textured_triangle(buffer);
    gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {
        {"KHR_texture_transform", {{"texCoord", 1e300}}}};
    expect_refused(gltf, {"KHR_texture_transform.texCoord", "1e+300"});
  }
  for (const json& material : {json(1e300), json(4294967296u)}) {
    json gltf = testing::gltf_document({testing::sphere_node(1.0)}, {0});
    gltf["materials"] = json::array({testing::quiet_material()});
    gltf["nodes"][0]["extras"]["glaze"]["sphere"]["material"] = material;
    expect_refused(gltf, {"extras.glaze.sphere.material", material.dump()});
  }
  testing::TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = textured_triangle(buffer);
  gltf["meshes"][0]["primitives"][0]["material"] = 4294967296u;
  testing::expect_render_refused(dir, testing::write_gltf(dir, "material.gltf", gltf), "material");
}

// 1.5: environment sides that are not whole numbers in [1, 65536], and a map too large
// for the memory limit.
TEST(HostileGltf, EnvironmentSides) {
  const auto with_environment = [](const json& width, const json& height) {
    json gltf = testing::gltf_document({testing::sphere_node(1.0)}, {0});
    gltf["scenes"][0]["extras"] = {
        {"glaze", {{"environment", {{"procedural", "constant"}, {"width", width}, {"height", height}}}}}};
    return gltf;
  };
  expect_refused(with_environment(1e10, 8), {"environment.width", "10000000000"});
  expect_refused(with_environment(16, 0.5), {"environment.height", "0.5"});
  expect_refused(with_environment(4294967312u, 8), {"environment.width", "4294967312"});  // 2^32 + 16
  const uint64_t limit = memory_limit();
  set_memory_limit(uint64_t(1) << 20);
  expect_refused(with_environment(4096, 2048), {"environment", "4096x2048", "memory"});
  set_memory_limit(limit);
  testing::TemporaryDirectory dir;
  testing::expect_render_refused(dir, testing::write_gltf(dir, "env.gltf", with_environment(1e10, 8)), "width");
}

// 6.3: a camera node scaled by (-1, 1, -1) (determinant +1: a half turn) looks away
// from the sphere at the origin: two warnings. Unscaled: none. Mirrored (det < 0): its
// own warning.
TEST(HostileGltf, CameraTurnedByNegativeScale) {
  const auto camera_warnings = [](const json& scale) {
    json camera = {{"camera", 0}, {"translation", {0, 0, 4}}, {"scale", scale}};
    json gltf = testing::gltf_document({testing::sphere_node(1.0), camera}, {0, 1});
    gltf["cameras"] = json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}});
    testing::TemporaryDirectory dir;
    const std::string path = testing::write_gltf(dir, "camera.gltf", gltf);
    testing::CapturedWarnings warnings;
    load_scene(path);
    std::string all;
    for (const std::string& message : warnings.messages) all += message + "\n";
    return all;
  };
  const std::string turned = camera_warnings({-1, 1, -1});
  EXPECT_NE(turned.find("negative scale"), std::string::npos) << turned;
  EXPECT_NE(turned.find("sees none of the scene"), std::string::npos) << turned;
  EXPECT_EQ(camera_warnings({1, 1, 1}), "");
  const std::string mirrored = camera_warnings({-1, 1, 1});
  EXPECT_NE(mirrored.find("mirrors"), std::string::npos) << mirrored;
  EXPECT_EQ(mirrored.find("sees none"), std::string::npos) << mirrored;
}

// Found by fuzzing: a camera at 1e38 made Embree abort on an assertion. Cameras and
// geometry beyond 1e15 are refused, naming them.
TEST(HostileGltf, CoordinatesBeyondWhatEmbreeTakes) {
  testing::TemporaryDirectory dir;
  GltfBuffer far_camera;
  json gltf = textured_triangle(far_camera);
  gltf["nodes"][1]["translation"] = {0, 1e38, 4};
  testing::expect_render_refused(dir, testing::write_gltf(dir, "camera.gltf", gltf), "lies beyond +-1e15");
  GltfBuffer far_sphere;
  gltf = textured_triangle(far_sphere);
  json sphere = testing::sphere_node(1.0);
  sphere["translation"] = {0, 0, -1e20};
  gltf["nodes"].push_back(sphere);
  gltf["scenes"][0]["nodes"].push_back(2);
  testing::expect_render_refused(dir, testing::write_gltf(dir, "sphere.gltf", gltf), "reaches beyond +-1e15");
}

}  // namespace
}  // namespace glaze
