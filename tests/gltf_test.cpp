// Tests of glTF files as other tools write them (docs/design.md §4, docs/guide.md's table of
// glTF features): winding against the normals, meshes without normals, texture coordinate
// sets, KHR_texture_transform, COLOR_0, sampler wrap modes, required extensions, Draco and
// meshopt compression, and the one warning about what glaze ignores.
//
// Every file is built here (tests/gltf_builder.h). Expectations come from the file's own
// numbers: which texel of a 2 x 2 texture of four known colours a coordinate falls in,
// what a vertex colour times a base colour is, or a second file that describes the same
// surface the plain way.
#include "gltf_builder.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"
#include "test_support.h"

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace glaze {
namespace {

using namespace testing;  // gltf_builder.h

// ---------------------------------------------------------------------------------------
// A unit box, its faces' normals, and renders of its variants.
// ---------------------------------------------------------------------------------------

// The box [-0.5, 0.5]^3 as 6 faces of 4 vertices each, counter-clockwise seen from
// outside, with each face's outward normal at its vertices.
struct Box {
  std::vector<float> positions, normals;
  std::vector<uint16_t> indices;
  Box() {
    for (int axis = 0; axis < 3; ++axis)
      for (int sign = -1; sign <= 1; sign += 2) {
        Vec3 n = Vec3::Zero();
        n[axis] = float(sign);
        const Vec3 u = Vec3::Unit((axis + 1) % 3), v = n.cross(u);  // u x v = n: counter-clockwise from outside
        const uint16_t first = uint16_t(positions.size() / 3);
        for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
          const Vec3 p = 0.5f * (n + float(a) * u + float(b) * v);
          positions.insert(positions.end(), {p.x(), p.y(), p.z()});
          normals.insert(normals.end(), {n.x(), n.y(), n.z()});
        }
        indices.insert(indices.end(), {first, uint16_t(first + 1), uint16_t(first + 2), first, uint16_t(first + 2),
                                       uint16_t(first + 3)});
      }
  }
};

enum class BoxVariant { reference, reversed_winding, without_normals };

// The box, rotated so that three faces show, in a procedural room; rendered by `integrator`.
std::string write_box(const TemporaryDirectory& dir, BoxVariant variant) {
  Box box;
  if (variant == BoxVariant::reversed_winding)
    for (size_t t = 0; t < box.indices.size(); t += 3) std::swap(box.indices[t + 1], box.indices[t + 2]);
  GltfBuffer buffer;
  json attributes = {{"POSITION", buffer.floats(box.positions, 3)}};
  if (variant != BoxVariant::without_normals) attributes["NORMAL"] = buffer.floats(box.normals, 3);
  const int indices = buffer.indices(box.indices);
  json gltf = gltf_document({{{"mesh", 0}, {"rotation", {0.2798, 0.3647, 0.1159, 0.8805}}}}, {0});
  gltf["meshes"] = {{{"primitives", {{{"attributes", attributes}, {"indices", indices}, {"material", 0}}}}}};
  gltf["materials"] = {quiet_material({{"pbrMetallicRoughness", {{"baseColorFactor", {0.7, 0.3, 0.2, 1.0}}}}})};
  gltf["scenes"][0]["extras"] = {
      {"glaze", {{"environment", {{"procedural", "office"}, {"width", 64}, {"height", 32}}}}}};
  buffer.into(gltf);
  const char* names[] = {"reference.gltf", "reversed.gltf", "flat.gltf"};
  return write_gltf(dir, names[int(variant)], gltf);
}

Image render_box(const TemporaryDirectory& dir, BoxVariant variant, const std::string& integrator) {
  const std::string scene = write_box(dir, variant);
  const std::string out = dir.file("box_" + std::to_string(int(variant)) + "_" + integrator + ".exr");
  const std::string samples = integrator == "path" ? " --spp 16 --seed 3" : "";
  const CommandResult run = run_glaze("render " + scene + " --integrator " + integrator +
                                          " --look-from 0,0.4,3 --res 32x32" + samples + " --out " + out,
                                      dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return read_image(out);
}

// A box wound against its normals and a box without normals are the same surface as the
// reference box: a flat face with its outward normal. Both integrators must render them
// the same, pixel for pixel up to float rounding (the path tracer's samples follow the
// same random streams, so the noise is the same too). Before glTF's rules were followed,
// the reversed box rendered black and the box without normals had curved highlights.
TEST(GltfSurfaces, ReversedWindingAndMissingNormalsRenderAsTheReferenceBox) {
  TemporaryDirectory dir;
  for (const std::string integrator : {"sh", "path"}) {
    const Image reference = render_box(dir, BoxVariant::reference, integrator);
    ASSERT_EQ(reference.width, 32);
    double mean = 0.0;
    for (float v : reference.pixels) mean += v;
    ASSERT_GT(mean / reference.pixels.size(), 0.01) << "the reference box is lit";
    for (const BoxVariant variant : {BoxVariant::reversed_winding, BoxVariant::without_normals}) {
      const Image image = render_box(dir, variant, integrator);
      ASSERT_EQ(image.pixels.size(), reference.pixels.size());
      double largest = 0.0;
      for (size_t i = 0; i < image.pixels.size(); ++i)
        largest = std::max(largest, double(std::abs(image.pixels[i] - reference.pixels[i])) /
                                        std::max(1e-3, double(reference.pixels[i])));
      EXPECT_LT(largest, 1e-3) << integrator << " variant " << int(variant);
    }
  }
}

// ---------------------------------------------------------------------------------------
// Texture coordinates, transforms, vertex colours and samplers, read at one hit.
// ---------------------------------------------------------------------------------------

// The 2 x 2 texture: red, green on the top row, blue, white below (uv (0, 0) is the
// top-left; 8-bit 255 decodes to exactly 1).
const RGB kRed(1, 0, 0), kGreen(0, 1, 0), kBlue(0, 0, 1), kWhite(1, 1, 1);

struct QuadOptions {
  std::vector<float> uv0 = {0.25f, 0.25f}, uv1 = {0.75f, 0.25f};  // the same at every vertex
  json texture_info = json::object();                             // baseColorTexture, index added
  json sampler = json();                                          // none: glTF's default
  std::vector<float> color;                                       // COLOR_0 at every vertex, or none
};

// A quad in the z = 0 plane over [-1, 1]^2 whose material reads the 2 x 2 texture;
// returns the file's path.
std::string write_textured_quad(const TemporaryDirectory& dir, const QuadOptions& options, const std::string& name) {
  GltfBuffer buffer;
  const auto repeat = [](const std::vector<float>& value) {
    std::vector<float> out;
    for (int k = 0; k < 4; ++k) out.insert(out.end(), value.begin(), value.end());
    return out;
  };
  json attributes = {{"POSITION", buffer.floats({-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0}, 3)},
                     {"TEXCOORD_0", buffer.floats(repeat(options.uv0), 2)},
                     {"TEXCOORD_1", buffer.floats(repeat(options.uv1), 2)}};
  if (!options.color.empty()) attributes["COLOR_0"] = buffer.floats(repeat(options.color), int(options.color.size()));
  const int indices = buffer.indices({0, 1, 2, 0, 2, 3});
  json gltf = gltf_document({{{"mesh", 0}}}, {0});
  gltf["meshes"] = {{{"primitives", {{{"attributes", attributes}, {"indices", indices}, {"material", 0}}}}}};
  json texture_info = options.texture_info;
  texture_info["index"] = 0;
  gltf["materials"] = {quiet_material({{"pbrMetallicRoughness", {{"baseColorTexture", texture_info}}}})};
  gltf["textures"] = {{{"source", 0}}};
  if (!options.sampler.is_null()) {
    gltf["samplers"] = {options.sampler};
    gltf["textures"][0]["sampler"] = 0;
  }
  const std::vector<unsigned char> rgb = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
  const std::vector<unsigned char> png = encode_png(2, 2, rgb);
  gltf["images"] = {{{"uri", "data:image/png;base64," + base64(png)}}};
  buffer.into(gltf);
  return write_gltf(dir, name, gltf);
}

// The base colour where the ray down -Z through the centre meets the textured quad.
RGB base_colour_at_the_centre(const TemporaryDirectory& dir, const QuadOptions& options, const std::string& name) {
  const Scene scene = load_scene(write_textured_quad(dir, options, name));
  const RayTracer tracer(scene);
  const std::optional<SurfaceHit> hit = tracer.intersect({Vec3(0, 0, 5), Vec3(0, 0, -1)});
  EXPECT_TRUE(hit.has_value());
  if (!hit) return RGB::Zero();
  return scene.material_at(hit->material, hit->uv, hit->color).Rd();
}

void expect_rgb_near(const RGB& actual, const RGB& expected, const std::string& what) {
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(actual[c], expected[c], 1e-5f) << what << " channel " << c;
}

TEST(GltfTextures, TexCoordPicksTheSet) {
  TemporaryDirectory dir;
  expect_rgb_near(base_colour_at_the_centre(dir, {}, "set0.gltf"), kRed, "TEXCOORD_0 (0.25, 0.25)");
  QuadOptions set1;
  set1.texture_info = {{"texCoord", 1}};
  expect_rgb_near(base_colour_at_the_centre(dir, set1, "set1.gltf"), kGreen, "TEXCOORD_1 (0.75, 0.25)");
}

// KHR_texture_transform: uv' = T R S uv with R = [[cos, sin], [-sin, cos]]. From set 0's
// (0.25, 0.25): offset (0, 0.5) gives (0.25, 0.75), blue; rotation pi/2 gives
// (0.25, -0.25), which repeats to (0.25, 0.75), blue; scale (3, 1) gives (0.75, 0.25),
// green; and the transform's own texCoord 1 with offset (0, 0.5) gives (0.75, 0.75), white.
TEST(GltfTextures, TextureTransformMovesTheLookup) {
  TemporaryDirectory dir;
  const auto transformed = [&](const json& transform, const std::string& name) {
    QuadOptions options;
    options.texture_info = {{"extensions", {{"KHR_texture_transform", transform}}}};
    return base_colour_at_the_centre(dir, options, name);
  };
  expect_rgb_near(transformed({{"offset", {0.0, 0.5}}}, "offset.gltf"), kBlue, "offset");
  expect_rgb_near(transformed({{"rotation", M_PI / 2}}, "rotation.gltf"), kBlue, "rotation");
  expect_rgb_near(transformed({{"scale", {3.0, 1.0}}}, "scale.gltf"), kGreen, "scale");
  expect_rgb_near(transformed({{"offset", {0.0, 0.5}}, {"texCoord", 1}}, "override.gltf"), kWhite, "texCoord");
}

// COLOR_0 multiplies the texture (red here): RGB and RGBA vertex colours alike.
TEST(GltfTextures, VertexColourMultipliesTheBaseColour) {
  TemporaryDirectory dir;
  QuadOptions options;
  options.color = {0.5f, 0.25f, 1.0f};
  expect_rgb_near(base_colour_at_the_centre(dir, options, "rgb.gltf"), RGB(0.5f, 0, 0), "COLOR_0 RGB");
  options.color = {0.25f, 1.0f, 1.0f, 0.5f};
  expect_rgb_near(base_colour_at_the_centre(dir, options, "rgba.gltf"), RGB(0.25f, 0, 0), "COLOR_0 RGBA");
}

// With the nearest filter, u = 1.25 is red when repeating (0.25), green when clamped
// (the last column); u = 1.75 is red when mirrored (0.25), green when repeating (0.75).
TEST(GltfTextures, SamplerWrapModesAndNearestFilter) {
  TemporaryDirectory dir;
  const auto at = [&](float u, int wrap, const std::string& name) {
    QuadOptions options;
    options.uv0 = {u, 0.25f};
    options.sampler = {{"magFilter", 9728}, {"wrapS", wrap}, {"wrapT", 10497}};
    return base_colour_at_the_centre(dir, options, name);
  };
  expect_rgb_near(at(1.25f, 10497, "repeat.gltf"), kRed, "repeat 1.25");
  expect_rgb_near(at(1.25f, 33071, "clamp.gltf"), kGreen, "clamp 1.25");
  expect_rgb_near(at(1.75f, 33648, "mirror.gltf"), kRed, "mirrored 1.75");
  expect_rgb_near(at(1.75f, 10497, "repeat2.gltf"), kGreen, "repeat 1.75");
  // Linear (the default) halfway between the columns' centres blends them evenly.
  QuadOptions linear;
  linear.uv0 = {0.5f, 0.25f};
  expect_rgb_near(base_colour_at_the_centre(dir, linear, "linear.gltf"), RGB(0.5f, 0.5f, 0), "linear");
}

TEST(GltfTextures, AMissingTexCoordSetIsAnErrorNamingIt) {
  TemporaryDirectory dir;
  QuadOptions options;
  options.texture_info = {{"texCoord", 2}};
  expect_load_error(dir, write_textured_quad(dir, options, "missing.gltf"), {"TEXCOORD_2"});
}

// ---------------------------------------------------------------------------------------
// Extensions: required ones glaze does not read, Draco, meshopt; the summary warning.
// ---------------------------------------------------------------------------------------

json one_triangle(GltfBuffer& buffer) {
  json gltf = gltf_document({{{"mesh", 0}}}, {0});
  gltf["meshes"] = {
      {{"primitives", {{{"attributes", {{"POSITION", buffer.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, 3)}}}}}}}};
  gltf["scenes"][0]["extras"] = {{"glaze", {{"environment", {{"procedural", "office"}}}}}};
  return gltf;
}

TEST(GltfExtensions, ARequiredUnsupportedExtensionExits1NamingIt) {
  TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = one_triangle(buffer);
  gltf["extensionsUsed"] = {"KHR_texture_basisu", "KHR_texture_transform", "EXT_meshopt_compression"};
  gltf["extensionsRequired"] = {"KHR_texture_basisu", "KHR_texture_transform", "EXT_meshopt_compression"};
  buffer.into(gltf);
  const std::string scene = write_gltf(dir, "basisu.gltf", gltf);
  const CommandResult run = run_glaze("render " + scene + " --res 8x8 --spp 1 --out " + dir.file("x.exr"), dir);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_FALSE(run.crashed);
  // Exactly the two unsupported ones, in the file's order; the supported one is not listed.
  EXPECT_NE(run.err.find("does not support: KHR_texture_basisu, EXT_meshopt_compression ("), std::string::npos)
      << run.err;
}

TEST(GltfExtensions, MeshoptCompressedDataIsRefusedByName) {
  TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = one_triangle(buffer);
  buffer.into(gltf);
  gltf["bufferViews"][0]["extensions"] = {
      {"EXT_meshopt_compression", {{"buffer", 0}, {"byteLength", 36}, {"byteStride", 12}, {"count", 3}}}};
  gltf["extensionsUsed"] = {"EXT_meshopt_compression"};
  expect_load_error(dir, write_gltf(dir, "meshopt.gltf", gltf), {"EXT_meshopt_compression"});
}

// A triangle pair compressed with the Draco library's own encoder (sequential, lossless
// for float positions) loads as the same surface as the uncompressed pair: the same hit
// at the same place with the same normal.
TEST(GltfExtensions, DracoCompressedPrimitiveDecodesToTheSameSurface) {
  TemporaryDirectory dir;
  const std::vector<Vec3> corners = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  const std::vector<std::array<int, 3>> faces = {{0, 1, 2}, {0, 2, 3}};
  draco::TriangleSoupMeshBuilder builder;
  builder.Start(int(faces.size()));
  const int position = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  for (size_t f = 0; f < faces.size(); ++f)
    builder.SetAttributeValuesForFace(position, draco::FaceIndex(uint32_t(f)), corners[faces[f][0]].data(),
                                      corners[faces[f][1]].data(), corners[faces[f][2]].data());
  std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
  ASSERT_TRUE(mesh);
  draco::Encoder encoder;
  encoder.SetEncodingMethod(draco::MESH_SEQUENTIAL_ENCODING);
  draco::EncoderBuffer encoded;
  ASSERT_TRUE(encoder.EncodeMeshToBuffer(*mesh, &encoded).ok());

  GltfBuffer buffer;
  const int view = buffer.view(encoded.data(), encoded.size());
  const int positions = buffer.accessor({{"componentType", 5126},
                                         {"count", mesh->num_points()},
                                         {"type", "VEC3"},
                                         {"min", {-1, -1, 0}},
                                         {"max", {1, 1, 0}}});
  const int indices = buffer.accessor({{"componentType", 5125}, {"count", 6}, {"type", "SCALAR"}});
  json gltf = gltf_document({{{"mesh", 0}, {"translation", {0, 0, -2}}}}, {0});
  const int unique_id =
      int(mesh->attribute(mesh->GetNamedAttributeId(draco::GeometryAttribute::POSITION))->unique_id());
  gltf["meshes"] = {
      {{"primitives",
        {{{"attributes", {{"POSITION", positions}}},
          {"indices", indices},
          {"extensions",
           {{"KHR_draco_mesh_compression", {{"bufferView", view}, {"attributes", {{"POSITION", unique_id}}}}}}}}}}}};
  gltf["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  gltf["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  buffer.into(gltf);
  const Scene scene = load_scene(write_gltf(dir, "draco.gltf", gltf));
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].triangles.size(), 2u);
  const RayTracer tracer(scene);
  for (const Vec2& at : {Vec2(0.5f, -0.5f), Vec2(-0.5f, 0.5f), Vec2(0.9f, 0.9f)}) {
    const std::optional<SurfaceHit> hit = tracer.intersect({Vec3(at.x(), at.y(), 3), Vec3(0, 0, -1)});
    ASSERT_TRUE(hit.has_value()) << at.transpose();
    EXPECT_NEAR(hit->distance, 5.0f, 1e-5f);
    EXPECT_NEAR(hit->normal.z(), 1.0f, 1e-6f);
  }
  EXPECT_FALSE(tracer.intersect({Vec3(1.5f, 0, 3), Vec3(0, 0, -1)}).has_value()) << "outside the quad";
}

// One warning per scene, with counts, instead of a line per material.
TEST(GltfExtensions, WhatGlazeIgnoresIsSummarisedInOneWarningWithCounts) {
  TemporaryDirectory dir;
  GltfBuffer buffer;
  json gltf = one_triangle(buffer);
  gltf["materials"] = json::array();
  for (int k = 0; k < 3; ++k) gltf["materials"].push_back({{"normalTexture", {{"index", 0}}}});
  gltf["materials"].push_back(quiet_material({{"emissiveFactor", {1.0, 0.5, 0.0}}}));
  gltf["materials"].push_back(quiet_material({{"extensions", {{"KHR_materials_transmission", json::object()}}}}));
  gltf["extensionsUsed"] = {"KHR_materials_transmission", "EXT_mesh_gpu_instancing"};
  buffer.into(gltf);
  CapturedWarnings warnings;
  load_scene(write_gltf(dir, "ignored.gltf", gltf));
  ASSERT_EQ(warnings.messages.size(), 1u);
  const std::string& message = warnings.messages[0];
  for (const char* expected :
       {"materials with metallic/roughness: 3", "materials with normal maps: 3", "emissive materials: 1",
        "materials with KHR_materials_transmission: 1", "extension EXT_mesh_gpu_instancing: 1"})
    EXPECT_NE(message.find(expected), std::string::npos) << expected << " in: " << message;
}

}  // namespace
}  // namespace glaze
