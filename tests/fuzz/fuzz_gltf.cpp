// fuzz_gltf: glTF and .glb files through load_scene, and the small scenes that load
// through texture lookups and one path-traced pass.
//
// The input is written as scene.gltf, or scene.glb when it starts with the binary magic,
// beside the fixtures buffer.bin and tex.png (fuzz_support.h). glaze::Error is a clean
// refusal; any other exception, a sanitizer report or a non-finite value is a finding.
// A scene with fewer than 2,000 triangles must give finite texture values at every vertex
// and triangle centroid, and a finite 4x4 image at 1 sample per pixel under a constant
// 16x8 environment (the file's own environment is not loaded: that is fuzz_image's part).
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/path_tracer.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/scene.h"
#include "tests/fuzz/fuzz_support.h"

#include <algorithm>
#include <cstring>
#include <filesystem>

namespace {

std::filesystem::path scratch;

using namespace glaze;

void check_textures(const Scene& scene) {
  for (const TriangleMesh& mesh : scene.meshes) {
    if (mesh.uvs.empty()) continue;
    const auto check = [&](const Vec2& uv) {
      const PolishedMaterial material = scene.material_at(mesh.material, uv);
      if (!material.Rd().allFinite() || !std::isfinite(material.R0()))
        fuzz::finding("mesh '" + mesh.name + "': material not finite at a texture coordinate");
    };
    for (const Vec2& uv : mesh.uvs) check(uv);
    for (const auto& t : mesh.triangles) check((mesh.uvs[t[0]] + mesh.uvs[t[1]] + mesh.uvs[t[2]]) / 3.0f);
  }
}

Environment constant_environment() {
  Image radiance(16, 8);
  std::fill(radiance.pixels.begin(), radiance.pixels.end(), 1.0f);
  return Environment(std::move(radiance), EnvironmentOptions{}, "constant");
}

void check_render(const Scene& scene) {
  static const Environment environment = constant_environment();
  PinholeCamera camera;
  if (!scene.cameras.empty()) {
    camera = scene.make_camera(scene.cameras.front(), std::pair{4, 4});
  } else {
    Eigen::Affine3f pose = Eigen::Affine3f::Identity();
    pose.translation() = Vec3(0, 0, 4);
    camera = PinholeCamera::from_vertical_fov("front", pose, 0.5f, 4, 4);
  }
  const RayTracer tracer(scene);
  const PathTracer path_tracer(scene, tracer, environment, PathTracerOptions{});
  RenderOptions options;
  options.spp = 1;
  options.threads = 1;
  ProgressiveRender render(path_tracer, camera, options);
  render.add_pass();
  size_t non_finite = 0;
  render.mean(&non_finite);
  if (non_finite > 0) fuzz::finding(std::to_string(non_finite) + " pixel values of the 4x4 render are not finite");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  scratch = glaze::fuzz::initialize_target("gltf");
  glaze::fuzz::write_gltf_fixtures(scratch);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const bool binary = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  const std::filesystem::path path = scratch / (binary ? "scene.glb" : "scene.gltf");
  glaze::fuzz::write_bytes(path, data, size);
  try {
    const Scene scene = load_scene(path.string());
    size_t triangles = 0;
    for (const TriangleMesh& mesh : scene.meshes) triangles += mesh.triangles.size();
    if (triangles >= 2000) return 0;
    check_textures(scene);
    check_render(scene);
  } catch (const glaze::Error& e) {
    glaze::fuzz::refused(e);
  }
  std::filesystem::remove(path);
  return 0;
}
