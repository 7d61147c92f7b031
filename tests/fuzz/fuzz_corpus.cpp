// fuzz_corpus OUT: writes the fuzz targets' seed corpus, built in code (never a
// third-party file): OUT/gltf, OUT/transforms and OUT/image, one valid input a file.
//
// gltf: sphere nodes with cameras and an environment; textured quads reading the fixtures
// (buffer.bin, tex.png) and data URIs, with COLOR_0, a second texture coordinate set,
// KHR_texture_transform and each sampler mode; an image in a bufferView; a Draco-compressed
// primitive (as tests/gltf_test.cpp encodes it); a .glb form of each file whose buffer
// is a data URI; and the repository's scenes/*.gltf with their images pointed at tex.png.
// transforms: write_transforms of small sets (sphere and glTF objects, shared and
// per-frame intrinsics, masks, environments, materials, path and sh renderers).
// image: write_image / write_picture of small images in every format fuzz_image reads,
// with alpha and with non-finite texels, and encode_png's output; byte 0 picks the format.
#include "renderer/capture_set.h"
#include "renderer/image.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/gltf_builder.h"

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

namespace glaze::fuzz {
namespace {

using testing::base64;
using testing::GltfBuffer;
using testing::json;
namespace fs = std::filesystem;

std::vector<unsigned char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_text(const fs::path& path, const std::string& text) {
  write_bytes(path, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

// ------------------------------------------------------------------------------ glTF

// The .glb form of `gltf`, whose buffer 0 (a data URI, if any) becomes the BIN chunk.
std::vector<unsigned char> glb(json gltf, const std::vector<unsigned char>& bin) {
  if (!bin.empty()) gltf["buffers"][0] = {{"byteLength", bin.size()}};
  std::string text = gltf.dump();
  while (text.size() % 4) text += ' ';
  std::vector<unsigned char> chunk = bin;
  while (chunk.size() % 4) chunk.push_back(0);
  std::vector<unsigned char> out;
  const auto put32 = [&](uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
  };
  const uint32_t total = uint32_t(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + chunk.size()));
  put32(0x46546C67), put32(2), put32(total);        // "glTF", version 2
  put32(uint32_t(text.size())), put32(0x4E4F534A);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  if (!bin.empty()) {
    put32(uint32_t(chunk.size())), put32(0x004E4942);  // "BIN"
    out.insert(out.end(), chunk.begin(), chunk.end());
  }
  return out;
}

json environment_extras(const std::string& procedural) {
  return {{"glaze", {{"environment", {{"procedural", procedural}, {"width", 16}, {"height", 8}}}}}};
}

// Two spheres, a perspective and an orthographic camera, a procedural environment.
json spheres() {
  json camera_node = {{"camera", 0}, {"translation", {0, 0, 4}}};
  json ortho_node = {{"camera", 1}, {"translation", {4, 0, 0}}, {"rotation", {0, testing::kS, 0, testing::kS}}};
  json gltf = testing::gltf_document({testing::sphere_node(1.0, 0),
                                      {{"translation", {2, 0, 0}}, {"scale", {0.5, 0.5, 0.5}}, {"children", {3}}},
                                      camera_node,
                                      testing::sphere_node(0.5, 1),
                                      ortho_node},
                                     {0, 1, 2, 4});
  gltf["materials"] = {testing::quiet_material({{"extras", {{"glaze", {{"R0", 0.04}, {"Rd", {0.8, 0.2, 0.1}}}}}}}),
                       testing::quiet_material()};
  gltf["cameras"] = {
      {{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"aspectRatio", 1.0}, {"znear", 0.1}}}},
      {{"type", "orthographic"}, {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"znear", 0}, {"zfar", 9}}}}};
  gltf["scenes"][0]["extras"] = environment_extras("office");
  gltf["scenes"][0]["extras"]["glaze"]["film"] = {{"width", 4}, {"height", 4}};
  return gltf;
}

// The fixture quad (buffer.bin) textured with tex.png: `texture_info` and `sampler` as given.
json fixture_quad(const json& texture_info, const json& sampler) {
  using L = QuadBufferLayout;
  json gltf = testing::gltf_document({{{"mesh", 0}, {"translation", {0, 0, -1}}}}, {0});
  gltf["buffers"] = {{{"uri", "buffer.bin"}, {"byteLength", L::size}}};
  const auto view = [](size_t offset, size_t length) {
    return json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}};
  };
  gltf["bufferViews"] = {view(L::positions, 48), view(L::normals, 48), view(L::uvs, 32), view(L::indices, 12)};
  gltf["accessors"] = {{{"bufferView", 0},
                        {"componentType", 5126},
                        {"count", 4},
                        {"type", "VEC3"},
                        {"min", {-1, -1, 0}},
                        {"max", {1, 1, 0}}},
                       {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                       {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
                       {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}};
  gltf["meshes"] = {
      {{"primitives",
        {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}}, {"indices", 3}, {"material", 0}}}}}};
  json info = texture_info;
  info["index"] = 0;
  gltf["materials"] = {testing::quiet_material({{"pbrMetallicRoughness", {{"baseColorTexture", info}}}})};
  gltf["textures"] = {{{"source", 0}}};
  if (!sampler.is_null()) {
    gltf["samplers"] = {sampler};
    gltf["textures"][0]["sampler"] = 0;
  }
  gltf["images"] = {{{"uri", "tex.png"}}};
  return gltf;
}

// A quad in a data-URI buffer with two texture coordinate sets and COLOR_0, whose 2x2
// texture is a PNG in a bufferView; `bin` receives the buffer (for the .glb form).
json data_uri_quad(std::vector<unsigned char>& bin) {
  GltfBuffer buffer;
  json attributes = {{"POSITION", buffer.floats({-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0}, 3)},
                     {"TEXCOORD_0", buffer.floats({0, 1, 1, 1, 1, 0, 0, 0}, 2)},
                     {"TEXCOORD_1", buffer.floats({0.25f, 0.25f, 0.75f, 0.25f, 0.75f, 0.75f, 0.25f, 0.75f}, 2)},
                     {"COLOR_0", buffer.floats({1, 0.5f, 0.5f, 1, 1, 1, 0.5f, 1, 1, 1, 1, 0.5f, 1, 1, 1, 1}, 4)}};
  const int indices = buffer.indices({0, 1, 2, 0, 2, 3});
  const std::vector<unsigned char> png = testing::encode_png(2, 2, {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255});
  const int image_view = buffer.view(png.data(), png.size());
  json gltf = testing::gltf_document({{{"mesh", 0}, {"rotation", {0.2798, 0.3647, 0.1159, 0.8805}}}}, {0});
  gltf["meshes"] = {{{"primitives", {{{"attributes", attributes}, {"indices", indices}, {"material", 0}}}}}};
  const json transform = {{"offset", {0.0, 0.5}}, {"rotation", 0.3}, {"scale", {2.0, 1.0}}, {"texCoord", 1}};
  gltf["materials"] = {testing::quiet_material(
      {{"pbrMetallicRoughness",
        {{"baseColorTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", transform}}}}}}}})};
  gltf["extensionsUsed"] = {"KHR_texture_transform"};
  gltf["textures"] = {{{"source", 0}, {"sampler", 0}}};
  gltf["samplers"] = {{{"magFilter", 9728}, {"wrapS", 33648}, {"wrapT", 33071}}};
  gltf["images"] = {{{"bufferView", image_view}, {"mimeType", "image/png"}}};
  gltf["scenes"][0]["extras"] = environment_extras("blue_room");
  buffer.into(gltf);
  bin = buffer.bytes();
  return gltf;
}

// A triangle pair compressed with Draco's own encoder (as tests/gltf_test.cpp does).
json draco_quad(std::vector<unsigned char>& bin) {
  const std::vector<Vec3> corners = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  const std::vector<std::array<int, 3>> faces = {{0, 1, 2}, {0, 2, 3}};
  draco::TriangleSoupMeshBuilder builder;
  builder.Start(int(faces.size()));
  const int position = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  for (size_t f = 0; f < faces.size(); ++f)
    builder.SetAttributeValuesForFace(position, draco::FaceIndex(uint32_t(f)), corners[faces[f][0]].data(),
                                      corners[faces[f][1]].data(), corners[faces[f][2]].data());
  std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
  draco::Encoder encoder;
  encoder.SetEncodingMethod(draco::MESH_SEQUENTIAL_ENCODING);
  draco::EncoderBuffer encoded;
  if (!mesh || !encoder.EncodeMeshToBuffer(*mesh, &encoded).ok()) throw std::runtime_error("Draco encoding failed");
  GltfBuffer buffer;
  const int view = buffer.view(encoded.data(), encoded.size());
  const int positions = buffer.accessor({{"componentType", 5126},
                                         {"count", mesh->num_points()},
                                         {"type", "VEC3"},
                                         {"min", {-1, -1, 0}},
                                         {"max", {1, 1, 0}}});
  const int indices = buffer.accessor({{"componentType", 5125}, {"count", 6}, {"type", "SCALAR"}});
  const int unique_id =
      int(mesh->attribute(mesh->GetNamedAttributeId(draco::GeometryAttribute::POSITION))->unique_id());
  json gltf = testing::gltf_document({{{"mesh", 0}, {"translation", {0, 0, -2}}}}, {0});
  gltf["meshes"] = {
      {{"primitives",
        {{{"attributes", {{"POSITION", positions}}},
          {"indices", indices},
          {"extensions",
           {{"KHR_draco_mesh_compression", {{"bufferView", view}, {"attributes", {{"POSITION", unique_id}}}}}}}}}}}};
  gltf["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  gltf["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  buffer.into(gltf);
  bin = buffer.bytes();
  return gltf;
}

void write_gltf_seeds(const fs::path& out) {
  const auto save = [&](const std::string& name, const json& gltf, const std::vector<unsigned char>& bin) {
    write_text(out / (name + ".gltf"), gltf.dump(1));
    const std::vector<unsigned char> binary = glb(gltf, bin);
    write_bytes(out / (name + ".glb"), binary.data(), binary.size());
  };
  save("spheres", spheres(), {});
  const json transform = {{"extensions", {{"KHR_texture_transform", {{"offset", {0.5, 0}}, {"scale", {2, 2}}}}}}};
  save("fixture_quad", fixture_quad(json::object(), json()), {});
  save("fixture_quad_clamp_nearest", fixture_quad(transform, {{"magFilter", 9728}, {"wrapS", 33071}, {"wrapT", 33648}}),
       {});
  std::vector<unsigned char> bin;
  const json quad = data_uri_quad(bin);
  save("data_uri_quad", quad, bin);
  const json draco = draco_quad(bin);
  save("draco_quad", draco, bin);
  for (const auto& entry : fs::directory_iterator(fs::path(GLAZE_SOURCE_DIR) / "scenes")) {
    if (entry.path().extension() != ".gltf") continue;
    json scene = json::parse(std::ifstream(entry.path()));
    if (scene.contains("images"))
      for (json& image : scene["images"]) image["uri"] = "tex.png";
    write_text(out / ("scene_" + entry.path().filename().string()), scene.dump(1));
  }
}

// ------------------------------------------------------------------------ transforms

void write_transforms_seeds(const fs::path& out) {
  const fs::path scratch = out / ".scratch";
  fs::create_directories(scratch);
  const auto camera = [](int k, float fov) {
    Eigen::Affine3f pose = Eigen::Affine3f::Identity();
    pose.rotate(Eigen::AngleAxisf(float(k) * 1.2f, Vec3::UnitY()));
    pose.translate(Vec3(0, 0, 4));
    return PinholeCamera::from_vertical_fov("view_" + std::to_string(k), pose, fov, 4, 4);
  };
  const auto save = [&](const std::string& name, const CaptureSet& set) {
    write_transforms(scratch.string(), set);
    fs::rename(scratch / "transforms.json", out / (name + ".json"));
  };

  CaptureSet sphere;
  for (int k = 0; k < 3; ++k) sphere.frames.push_back({"view_00" + std::to_string(k) + ".exr", camera(k, 0.5f), ""});
  sphere.frames[0].mask_path = "mask_000.png";
  sphere.object = CaptureSphere{Vec3(0, 0.1f, 0), 1.0f};
  save("sphere_shared_intrinsics", sphere);

  CaptureSet with_everything = sphere;
  for (int k = 0; k < 3; ++k) with_everything.frames[size_t(k)].camera = camera(k, 0.4f + 0.1f * float(k));
  CaptureEnvironment environment;
  environment.file = "env.exr";
  environment.options.scale = 2.0f;
  environment.options.rotation_degrees = 30.0f;
  with_everything.environment = environment;
  with_everything.material = CaptureMaterial{PolishedMaterial(0.04f, RGB(0.8f, 0.2f, 0.1f)), ""};
  with_everything.renderer = CaptureRenderer{CaptureRenderer::Integrator::path, 16, 1, 0};
  with_everything.saturation = 100.0f;
  save("sphere_per_frame_path", with_everything);

  CaptureSet gltf = sphere;
  gltf.object = CaptureGltf{"sphere.gltf"};
  CaptureEnvironment procedural;
  procedural.procedural = "office";
  gltf.environment = procedural;
  gltf.material = CaptureMaterial{PolishedMaterial(0.05f, RGB(0.5f, 0.5f, 0.5f)), "view_003.exr"};
  gltf.renderer = CaptureRenderer{CaptureRenderer::Integrator::sh, 1, 2, 4};
  save("gltf_sh", gltf);
  fs::remove_all(scratch);

  // What nerfstudio-style tools write: OPENCV with zero distortion, keys glaze ignores.
  write_text(out / "opencv.json", R"({"camera_model": "OPENCV", "w": 4, "h": 4, "fl_x": 5.0, "fl_y": 5.0,
    "cx": 2.0, "cy": 2.0, "k1": 0, "k2": 0, "p1": 0, "p2": 0, "aabb_scale": 16,
    "frames": [{"file_path": "view_000.exr", "transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4],
    [0, 0, 0, 1]], "colmap_im_id": 1}], "object": {"type": "sphere", "center": [0, 0, 0], "radius": 1}})");
  // Lenses: OPENCV with distortion, and a fisheye frame beside it.
  write_text(out / "lenses.json", R"({"camera_model": "OPENCV", "w": 4, "h": 4, "fl_x": 5.0, "fl_y": 5.0,
    "cx": 2.0, "cy": 2.0, "k1": -0.12, "k2": 0.03, "p1": 0.001, "p2": -0.002, "k3": 0.001,
    "frames": [{"file_path": "view_000.exr", "transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4],
    [0, 0, 0, 1]]}, {"file_path": "view_001.exr", "camera_model": "OPENCV_FISHEYE", "k1": 0.05, "k2": 0, "k3": 0,
    "k4": 0.001, "p1": 0, "p2": 0, "transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 5], [0, 0, 0, 1]]}],
    "object": {"type": "sphere", "center": [0, 0, 0], "radius": 1}})");
}

// ----------------------------------------------------------------------------- images

// A PFM file (Netpbm's float format): "PF" (RGB) or "Pf" (grey), little-endian (negative
// scale), rows from the bottom.
std::string portable_float_map(const Image& image, int channels) {
  std::string out = std::string(channels == 3 ? "PF" : "Pf") + "\n" + std::to_string(image.width) + " " +
                    std::to_string(image.height) + "\n-1.0\n";
  for (int y = image.height - 1; y >= 0; --y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < channels; ++c) {
        const float value = image.at(x, y)[c];
        out.append(reinterpret_cast<const char*>(&value), sizeof value);
      }
  return out;
}

void write_image_seeds(const fs::path& out) {
  const fs::path scratch = out / ".scratch";
  fs::create_directories(scratch);
  const auto save = [&](const std::string& name, size_t format, const std::function<void(const std::string&)>& write) {
    const std::string& extension = kImageExtensions[format];
    const fs::path file = scratch / ("image" + extension);
    try {
      write(file.string());
    } catch (const Error& e) {  // a format OpenImageIO cannot write this way: no seed
      std::fprintf(stderr, "fuzz_corpus: no %s seed for %s: %s\n", name.c_str(), extension.c_str(), e.what());
      return;
    }
    std::vector<unsigned char> bytes = read_bytes(file);
    bytes.insert(bytes.begin(), uint8_t(format));
    write_bytes(out / (name + extension), bytes.data(), bytes.size());
  };
  Image small(4, 4), wide(16, 8);
  for (Image* image : {&small, &wide})
    for (int y = 0; y < image->height; ++y)
      for (int x = 0; x < image->width; ++x) image->set(x, y, RGB(0.1f * float(x), 0.2f * float(y), 0.5f));
  Image odd = small;
  odd.set(1, 1, RGB(std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f));
  const std::vector<float> alpha(16, 0.5f);
  std::vector<uint8_t> srgb(16 * 3);
  for (size_t i = 0; i < srgb.size(); ++i) srgb[i] = uint8_t(i * 5);
  for (size_t format = 0; format < kImageExtensions.size(); ++format) {
    if (kImageExtensions[format] == ".pfm") continue;  // below: glaze writes no PFM
    save("small", format, [&](const std::string& path) { write_image(path, small); });
    save("wide", format, [&](const std::string& path) { write_image(path, wide); });
    if (kImageExtensions[format] != ".hdr")  // Radiance HDR has no alpha channel
      save("alpha", format, [&](const std::string& path) { write_image(path, small, {}, alpha); });
    save("non_finite", format, [&](const std::string& path) { write_image(path, odd); });
    save("picture", format, [&](const std::string& path) { write_picture(path, 4, 4, srgb); });
  }
  const size_t pfm =
      size_t(std::find(kImageExtensions.begin(), kImageExtensions.end(), ".pfm") - kImageExtensions.begin());
  save("colour", pfm, [&](const std::string& path) { write_text(path, portable_float_map(odd, 3)); });
  save("grey", pfm, [&](const std::string& path) { write_text(path, portable_float_map(wide, 1)); });
  const std::vector<unsigned char> png = testing::encode_png(2, 2, {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255});
  save("encode_png", 3, [&](const std::string& path) { write_bytes(path, png.data(), png.size()); });
  fs::remove_all(scratch);
}

}  // namespace
}  // namespace glaze::fuzz

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_corpus OUT (writes OUT/gltf, OUT/transforms, OUT/image)\n");
    return 2;
  }
  namespace fs = std::filesystem;
  glaze::set_warning_sink([](const std::string&) {});
  const fs::path out = argv[1];
  for (const char* kind : {"gltf", "transforms", "image"}) {
    fs::remove_all(out / kind);
    fs::create_directories(out / kind);
  }
  glaze::fuzz::write_gltf_seeds(out / "gltf");
  glaze::fuzz::write_transforms_seeds(out / "transforms");
  glaze::fuzz::write_image_seeds(out / "image");
  for (const char* kind : {"gltf", "transforms", "image"}) {
    const auto count = std::distance(fs::directory_iterator(out / kind), fs::directory_iterator());
    std::printf("fuzz_corpus: %lld %s seeds in %s\n", static_cast<long long>(count), kind, (out / kind).c_str());
  }
  return 0;
}
