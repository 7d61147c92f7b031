// scene.h: what a glTF scene becomes (docs/design.md §4): world-space triangle meshes and
// analytic spheres, polished materials (with optional diffuse textures), cameras, the
// environment and the film size. Loaded by load_scene() (gltf_loader.cpp); turned into
// Embree geometry by RayTracer.
#pragma once

#include "renderer/camera.h"
#include "renderer/environment.h"
#include "renderer/material.h"
#include "renderer/texture.h"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace glaze {

// KHR_texture_transform's affine map of texture coordinates, uv' = T R S uv: the first two
// columns are R S, the third is T.
using UvTransform = Eigen::Matrix<float, 2, 3>;

struct SceneMaterial {
  std::string name;
  float R0 = 0.04f;
  RGB Rd = RGB::Ones();  // factor; times the texture and the vertex colour where there are
  int texture = -1;      // index into Scene::textures, or -1
  int texcoord = 0;      // the TEXCOORD_n set the texture reads
  UvTransform uv_transform = UvTransform::Identity();
};

struct TriangleMesh {
  std::string name;
  std::vector<Vec3> positions;  // world space
  std::vector<Vec3> normals;    // world space, unit, per vertex; empty: flat (the face's normal)
  std::vector<Vec2> uvs;        // per vertex, the set the material's texture reads, or empty
  std::vector<RGB> colors;      // per vertex (COLOR_0), multiplying the base colour, or empty
  std::vector<std::array<uint32_t, 3>> triangles;
  int material = 0;
};

// An analytic sphere. Its texture coordinates are the lat-long (u, v) of docs/design.md §3 of
// the surface normal turned into the sphere's own frame (the node's rotation).
struct Sphere {
  std::string name;
  Vec3 center;
  float radius;
  int material;
  Mat3 rotation = Mat3::Identity();  // sphere frame -> world
};

// A camera as the file gives it. `name` is what the command line shows and takes: the
// node's name, else the glTF camera's, else camera_N (N the camera's index), made unique
// with a _K suffix (K the count of cameras before it). `camera_name`, the glTF camera's
// own name, is taken too where it names one camera node only.
struct CameraSpec {
  std::string name;
  std::string camera_name;  // the glTF camera object's name, or empty
  Eigen::Affine3f camera_to_world;
  Projection projection = Projection::perspective;
  float yfov = 0.0f;    // perspective: vertical field of view, radians
  float ymag = 0.0f;    // orthographic: half the view's height, world units
  float aspect = 0.0f;  // width / height (orthographic: xmag / ymag), 0 if the file does not say
};

struct EnvironmentSpec {
  std::string source;  // file path (resolved) or procedural:NAME
  EnvironmentOptions options;
  int width = 1024, height = 512;  // of a procedural map
};

// The largest coordinate a scene may have. Embree refuses rays and vertices beyond about
// 1.8e18 (by an assertion, which aborts), and float positions have lost all precision
// long before: scenes, cameras and capture sets are checked against this when read.
inline constexpr float kLargestCoordinate = 1e15f;

struct Scene {
  std::string path;
  std::vector<SceneMaterial> materials;
  std::vector<Texture> textures;
  std::vector<TriangleMesh> meshes;
  std::vector<Sphere> spheres;
  std::vector<CameraSpec> cameras;
  std::optional<EnvironmentSpec> environment;
  std::optional<std::pair<int, int>> film;  // scene.extras.glaze.film

  // The camera that `name` names: a camera's name, else a glTF camera's own name used by
  // one node only. Throws glaze::Error listing the names there are when there is none,
  // and the nodes' names when the glTF camera is used by several.
  const CameraSpec& camera(const std::string& name) const;
  // Film size: `resolution` if given, else the scene's film, else 512 high with the
  // camera's aspect ratio (1 when unknown). Pixels are square: the vertical field of view
  // (perspective) or height (orthographic) is kept, the horizontal follows the film.
  PinholeCamera make_camera(const CameraSpec& spec, std::optional<std::pair<int, int>> resolution) const;

  // The material at a surface point with texture coordinate uv.
  // `color` is the interpolated vertex colour (COLOR_0), white where there is none.
  PolishedMaterial material_at(int material, const Vec2& uv, const RGB& color = RGB::Ones()) const;

  // One analytic sphere and nothing else: nothing can shadow or reflect the object onto
  // itself, so one bounce and no occlusion rays are exact (docs/design.md §6).
  bool is_single_convex_object() const { return meshes.empty() && spheres.size() == 1; }
};

// Loads a .gltf or .glb file. Throws glaze::Error naming the file and the element at
// fault (missing buffer, index out of range, missing texture, cyclic nodes, ...).
Scene load_scene(const std::string& path);

}  // namespace glaze
