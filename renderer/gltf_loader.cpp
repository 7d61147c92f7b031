// gltf_loader.cpp: glTF 2.0 (.gltf, .glb) -> Scene, with tinygltf (docs/design.md §4).
//
// Every index the file contains is checked before it is followed, so that a malformed
// file gives a glaze::Error naming the element at fault instead of undefined behaviour.
// Images are decoded by OpenImageIO (tinygltf's own decoder is bypassed) so that EXR
// textures work and 8-bit ones are linearised from sRGB like every other image in glaze.
// Draco-compressed primitives are decoded here with the Draco library (Debian's tinygltf
// is built without it). What a file uses that glaze does not model is counted and
// reported in one warning per scene; what glaze cannot read at all (a required extension
// it does not know, meshopt-compressed buffers) is refused by name.
#include "renderer/error.h"
#include "renderer/scene.h"

#include <tiny_gltf.h>

#include <draco/compression/decode.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>

namespace glaze {
namespace {

using tinygltf::Value;

// The extensions glaze reads (docs/guide.md lists what it does with the rest of glTF).
const std::set<std::string> kSupportedExtensions = {"KHR_materials_ior", "KHR_texture_transform",
                                                    "KHR_draco_mesh_compression", "KHR_mesh_quantization"};

class GltfLoader {
 public:
  explicit GltfLoader(const std::string& path) : path_(path) {}

  Scene load() {
    read_model();
    scene_.path = path_;
    load_materials();
    const int scene_index = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (model_.scenes.empty()) {
      // A file without scenes: every root node is part of the scene.
      std::set<int> children;
      for (const auto& node : model_.nodes) children.insert(node.children.begin(), node.children.end());
      bool any_root = false;
      for (int i = 0; i < static_cast<int>(model_.nodes.size()); ++i) {
        if (children.count(i)) continue;
        any_root = true;
        visit_node(i, Eigen::Affine3f::Identity());
      }
      if (!any_root && !model_.nodes.empty()) fail("every node is some node's child: the node hierarchy has a cycle");
    } else {
      if (scene_index >= static_cast<int>(model_.scenes.size()))
        fail("defaultScene " + std::to_string(scene_index) + " does not exist");
      const tinygltf::Scene& scene = model_.scenes[scene_index];
      for (int node : scene.nodes) visit_node(node, Eigen::Affine3f::Identity());
      read_scene_extras(scene.extras);
    }
    if (scene_.meshes.empty() && scene_.spheres.empty())
      fail("the scene contains no geometry (no mesh and no glaze sphere)");
    warn_about_ignored_features();
    return std::move(scene_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw Error(path_ + ": " + what); }

  std::filesystem::path directory() const { return std::filesystem::path(path_).parent_path(); }

  void read_model() {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path_, ec))
      throw Error(path_ + ": no such scene file (expected a .gltf or .glb glTF 2.0 file)");
    std::ifstream stream(path_, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
    if (!stream.good() && !stream.eof()) fail("cannot be read");
    const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
    without_draco_indices(bytes, binary);
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&GltfLoader::decode_image, this);
    std::string error, warning;
    const std::string base = directory().string();
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
    const bool ok =
        binary ? loader.LoadBinaryFromMemory(&model_, &error, &warning, data, unsigned(bytes.size()), base)
               : loader.LoadASCIIFromString(&model_, &error, &warning, bytes.data(), unsigned(bytes.size()), base);
    if (!warning.empty()) warn(path_ + ": " + warning);
    // Before any other error: an unknown required extension explains the rest.
    std::string unsupported;
    for (const std::string& extension : model_.extensionsRequired)
      if (!kSupportedExtensions.count(extension)) unsupported.append(unsupported.empty() ? "" : ", ").append(extension);
    if (!unsupported.empty()) {
      std::string supported;
      for (const std::string& extension : kSupportedExtensions)
        supported.append(supported.empty() ? "" : ", ").append(extension);
      fail("requires glTF extensions that glaze does not support: " + unsupported + " (glaze reads " + supported +
           "; convert the file without the others, e.g. `gltf-transform copy IN OUT` decompresses meshopt and "
           "`gltf-transform png IN OUT` re-encodes KTX2/Basis textures)");
    }
    if (!ok) fail("cannot be loaded as glTF 2.0: " + (error.empty() ? std::string("unknown error") : error));
  }

  // One warning listing what the file uses that glaze does not model, with counts.
  void warn_about_ignored_features() {
    for (const auto& node : model_.nodes)
      if (node.skin >= 0) ++ignored_["skinned nodes"];
    for (const auto& mesh : model_.meshes)
      for (const auto& primitive : mesh.primitives)
        if (!primitive.targets.empty()) ++ignored_["primitives with morph targets"];
    if (!model_.animations.empty()) ignored_["animations"] += int(model_.animations.size());
    if (!model_.lights.empty()) ignored_["punctual lights (KHR_lights_punctual)"] = int(model_.lights.size());
    // Extensions the file declares that no count above names (EXT_mesh_gpu_instancing, ...).
    for (const std::string& extension : model_.extensionsUsed) {
      const bool counted = std::any_of(ignored_.begin(), ignored_.end(), [&](const auto& entry) {
        return entry.first.find(extension) != std::string::npos;
      });
      if (!kSupportedExtensions.count(extension) && !counted) ignored_["extension " + extension] = 1;
    }
    if (ignored_.empty()) return;
    std::string list;
    for (const auto& [feature, count] : ignored_)
      list += (list.empty() ? "" : "; ") + feature + ": " + std::to_string(count);
    warn(path_ + ": glaze does not model, and ignores: " + list +
         ". Its material is a smooth dielectric coat (R0, from KHR_materials_ior) over a diffuse base "
         "(baseColor); see docs/guide.md for each glTF feature.");
  }

  // tinygltf, built without Draco, refuses a primitive whose indices accessor has no
  // bufferView, which is how Draco-compressed primitives are written. Their indices come
  // from the Draco data, so the reference is dropped from the JSON (the .glb's JSON chunk)
  // before tinygltf reads it. Files without Draco are handed over untouched.
  void without_draco_indices(std::string& bytes, bool binary) const {
    const std::string_view draco = "KHR_draco_mesh_compression";
    if (bytes.find(draco) == std::string::npos) return;
    size_t json_begin = 0, json_size = bytes.size();
    if (binary) {
      uint32_t chunk_size = 0, chunk_type = 0;
      if (bytes.size() < 20) fail("the .glb file is truncated");
      std::memcpy(&chunk_size, bytes.data() + 12, 4);
      std::memcpy(&chunk_type, bytes.data() + 16, 4);
      if (chunk_type != 0x4E4F534Au || 20 + size_t(chunk_size) > bytes.size())
        fail("the .glb file's first chunk is not its JSON");
      json_begin = 20, json_size = chunk_size;
    }
    nlohmann::json document =
        nlohmann::json::parse(bytes.begin() + json_begin, bytes.begin() + json_begin + json_size, nullptr, false);
    if (!document.is_object() || !document.contains("meshes") || !document["meshes"].is_array()) return;
    for (auto& mesh : document["meshes"])
      if (mesh.is_object() && mesh.contains("primitives") && mesh["primitives"].is_array())
        for (auto& primitive : mesh["primitives"])
          if (primitive.is_object() && primitive.contains("extensions") && primitive["extensions"].is_object() &&
              primitive["extensions"].contains(draco))
            primitive.erase("indices");
    std::string text = document.dump();
    if (!binary) {
      bytes = std::move(text);
      return;
    }
    text.append((4 - text.size() % 4) % 4, ' ');  // chunks are 4-byte aligned, JSON padded with spaces
    const std::string rest = bytes.substr(json_begin + json_size);
    const uint32_t chunk_size = uint32_t(text.size()), total = uint32_t(12 + 8 + text.size() + rest.size());
    std::string glb = bytes.substr(0, 20);
    std::memcpy(glb.data() + 8, &total, 4);
    std::memcpy(glb.data() + 12, &chunk_size, 4);
    glb.append(text).append(rest);
    bytes = std::move(glb);
  }

  // tinygltf hands every image's bytes here (external file, data URI or .glb chunk).
  static bool decode_image(tinygltf::Image* image, const int index, std::string* error, std::string*, int, int,
                           const unsigned char* bytes, int size, void* self_pointer) {
    auto* self = static_cast<GltfLoader*>(self_pointer);
    std::string hint = image->uri;
    if (hint.empty() || hint.starts_with("data:")) {
      hint = image->mimeType == "image/jpeg" ? "image.jpg" : image->mimeType == "image/png" ? "image.png" : "image.exr";
    }
    try {
      self->decoded_[index] = read_image_from_memory(bytes, static_cast<size_t>(size), hint);
    } catch (const Error& e) {
      if (error) *error = std::string("image ") + std::to_string(index) + ": " + e.what();
      return false;
    }
    return true;
  }

  static const Value* member(const Value& object, const char* key) {
    return object.IsObject() && object.Has(key) ? &object.Get(key) : nullptr;
  }

  double number(const Value& value, const std::string& what) const {
    if (!value.IsNumber()) fail(what + " must be a number");
    const double n = value.GetNumberAsDouble();
    if (!std::isfinite(n)) fail(what + " must be finite");
    return n;
  }

  RGB rgb(const Value& value, const std::string& what) const {
    if (!value.IsArray() || value.ArrayLen() != 3) fail(what + " must be an array of 3 numbers");
    return {float(number(value.Get(0), what)), float(number(value.Get(1), what)), float(number(value.Get(2), what))};
  }

  void load_materials() {
    for (size_t i = 0; i < model_.materials.size(); ++i) {
      const tinygltf::Material& source = model_.materials[i];
      const std::string what = "material " + std::to_string(i) + (source.name.empty() ? "" : " '" + source.name + "'");
      SceneMaterial material;
      material.name = source.name.empty() ? "material_" + std::to_string(i) : source.name;
      const auto& pbr = source.pbrMetallicRoughness;
      if (pbr.baseColorFactor.size() >= 3)
        material.Rd = RGB(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]), float(pbr.baseColorFactor[2]));
      if (pbr.baseColorTexture.index >= 0) {
        material.texture = texture(pbr.baseColorTexture.index, what);
        material.texcoord = pbr.baseColorTexture.texCoord;
        read_texture_transform(pbr.baseColorTexture.extensions, material, what);
      }
      if (pbr.metallicFactor > 0.0 || pbr.roughnessFactor > 0.0 || pbr.metallicRoughnessTexture.index >= 0)
        ++ignored_["materials with metallic/roughness"];
      if (source.normalTexture.index >= 0) ++ignored_["materials with normal maps"];
      if (source.occlusionTexture.index >= 0) ++ignored_["materials with occlusion maps"];
      if (source.emissiveTexture.index >= 0 ||
          std::any_of(source.emissiveFactor.begin(), source.emissiveFactor.end(), [](double e) { return e > 0.0; }))
        ++ignored_["emissive materials"];
      if (source.alphaMode == "BLEND" || source.alphaMode == "MASK")
        ++ignored_["materials with alphaMode " + source.alphaMode];
      for (const auto& [extension, value] : source.extensions)
        if (extension != "KHR_materials_ior") ++ignored_["materials with " + extension];
      if (const auto it = source.extensions.find("KHR_materials_ior"); it != source.extensions.end()) {
        if (const Value* ior_value = member(it->second, "ior")) {
          const double ior = number(*ior_value, what + " KHR_materials_ior.ior");
          if (ior < 1.0) fail(what + ": ior " + std::to_string(ior) + " must be >= 1");
          material.R0 = static_cast<float>(std::pow((ior - 1.0) / (ior + 1.0), 2.0));
        }
      }
      if (const Value* glaze = member(source.extras, "glaze")) {
        // Keyed by the material's parameter names (kMaterialParameters).
        const std::string R0_key(parameter_spec(MaterialParameter::R0).name);
        const std::string Rd_key(parameter_spec(MaterialParameter::Rd).name);
        if (const Value* R0 = member(*glaze, R0_key.c_str()))
          material.R0 = float(number(*R0, what + " extras.glaze." + R0_key));
        if (const Value* Rd = member(*glaze, Rd_key.c_str())) material.Rd = rgb(*Rd, what + " extras.glaze." + Rd_key);
      }
      try {
        PolishedMaterial(material.R0, material.Rd.min(1.0f));  // validates R0 and the sign of Rd
      } catch (const Error& e) {
        fail(what + ": " + e.what());
      }
      if ((material.Rd > 1.0f).any()) fail(what + ": Rd (base colour) must be in [0, 1]");
      scene_.materials.push_back(material);
    }
  }

  // KHR_texture_transform on a texture reference: uv' = T R S uv (its texCoord overrides).
  void read_texture_transform(const tinygltf::ExtensionMap& extensions, SceneMaterial& material,
                              const std::string& what) const {
    const auto it = extensions.find("KHR_texture_transform");
    if (it == extensions.end()) return;
    const std::string where = what + " KHR_texture_transform";
    const auto pair = [&](const char* key, float fallback) -> Vec2 {
      const Value* value = member(it->second, key);
      if (!value) return Vec2(fallback, fallback);
      if (!value->IsArray() || value->ArrayLen() != 2) fail(where + "." + key + " must be an array of 2 numbers");
      return {float(number(value->Get(0), where + "." + key)), float(number(value->Get(1), where + "." + key))};
    };
    const Vec2 offset = pair("offset", 0.0f), scale = pair("scale", 1.0f);
    const Value* rotation_value = member(it->second, "rotation");
    const float rotation = rotation_value ? float(number(*rotation_value, where + ".rotation")) : 0.0f;
    const float c = std::cos(rotation), s = std::sin(rotation);
    material.uv_transform << c * scale.x(), s * scale.y(), offset.x(), -s * scale.x(), c * scale.y(), offset.y();
    if (const Value* texcoord = member(it->second, "texCoord"))
      material.texcoord = int(number(*texcoord, where + ".texCoord"));
  }

  static Wrap wrap_mode(int gl_mode) {
    return gl_mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE     ? Wrap::clamp
           : gl_mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? Wrap::mirrored_repeat
                                                              : Wrap::repeat;
  }

  int texture(int index, const std::string& what) {
    if (index < 0 || index >= static_cast<int>(model_.textures.size()))
      fail(what + ": baseColorTexture index " + std::to_string(index) + " does not exist");
    const int source = model_.textures[index].source;
    if (source < 0 || source >= static_cast<int>(model_.images.size()))
      fail(what + ": texture " + std::to_string(index) + " has no image (source " + std::to_string(source) +
           "; a KTX2/Basis texture needs KHR_texture_basisu, which glaze does not read)");
    if (const auto it = texture_of_gltf_texture_.find(index); it != texture_of_gltf_texture_.end()) return it->second;
    const auto decoded = decoded_.find(source);
    if (decoded == decoded_.end()) {
      const std::string& uri = model_.images[source].uri;
      fail(what + ": texture image " + std::to_string(source) + (uri.empty() ? "" : " '" + uri + "'") +
           " was not found or could not be decoded (paths are relative to the glTF file)");
    }
    Texture texture{model_.images[source].uri.empty() ? "image " + std::to_string(source) : model_.images[source].uri,
                    decoded->second};
    if (const int sampler = model_.textures[index].sampler; sampler >= 0) {
      if (sampler >= static_cast<int>(model_.samplers.size()))
        fail(what + ": texture " + std::to_string(index) + " refers to sampler " + std::to_string(sampler) +
             ", which does not exist");
      const tinygltf::Sampler& s = model_.samplers[sampler];
      texture.wrap_u = wrap_mode(s.wrapS);
      texture.wrap_v = wrap_mode(s.wrapT);
      // Magnification decides what a close-up shows; minification (mipmaps) is left to the
      // many samples each pixel averages.
      texture.nearest = s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
    }
    size_t clamped = 0;
    for (float& v : texture.image.pixels) {
      if (!(v >= 0.0f && v <= 1.0f)) {
        v = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
        ++clamped;
      }
    }
    if (clamped)
      warn(path_ + ": texture " + texture.source + ": " + std::to_string(clamped) +
           " values outside [0, 1] clamped (Rd is a reflectance)");
    scene_.textures.push_back(std::move(texture));
    return texture_of_gltf_texture_[index] = static_cast<int>(scene_.textures.size()) - 1;
  }

  Eigen::Affine3f local_transform(const tinygltf::Node& node, const std::string& what) const {
    Eigen::Affine3f transform = Eigen::Affine3f::Identity();
    if (node.matrix.size() == 16) {
      Eigen::Matrix4f m;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m(r, c) = float(node.matrix[c * 4 + r]);  // column-major
      transform.matrix() = m;
      return transform;
    }
    if (!node.matrix.empty()) fail(what + ": matrix must have 16 numbers");
    if (node.translation.size() == 3)
      transform.translate(Vec3(float(node.translation[0]), float(node.translation[1]), float(node.translation[2])));
    if (node.rotation.size() == 4) {
      const Eigen::Quaternionf q(float(node.rotation[3]), float(node.rotation[0]), float(node.rotation[1]),
                                 float(node.rotation[2]));
      if (q.norm() < 1e-6f) fail(what + ": rotation quaternion is zero");
      transform.rotate(q.normalized());
    }
    if (node.scale.size() == 3) transform.scale(Vec3(float(node.scale[0]), float(node.scale[1]), float(node.scale[2])));
    return transform;
  }

  void visit_node(int index, const Eigen::Affine3f& parent) {
    if (index < 0 || index >= static_cast<int>(model_.nodes.size()))
      fail("node index " + std::to_string(index) + " does not exist");
    if (!on_path_.insert(index).second)
      fail("node " + std::to_string(index) + " is its own ancestor (the node hierarchy has a cycle)");
    const tinygltf::Node& node = model_.nodes[index];
    const std::string what = "node " + std::to_string(index) + (node.name.empty() ? "" : " '" + node.name + "'");
    const Eigen::Affine3f world = parent * local_transform(node, what);
    if (!world.matrix().allFinite()) fail(what + ": transform is not finite");

    if (node.mesh >= 0) add_mesh(node.mesh, world, what);
    if (node.camera >= 0) add_camera(node.camera, node.name, world, what);
    if (const Value* glaze = member(node.extras, "glaze"))
      if (const Value* sphere = member(*glaze, "sphere")) add_sphere(*sphere, world, what);
    for (int child : node.children) visit_node(child, world);
    on_path_.erase(index);
  }

  void add_camera(int index, const std::string& node_name, const Eigen::Affine3f& world, const std::string& what) {
    if (index >= static_cast<int>(model_.cameras.size()))
      fail(what + ": camera " + std::to_string(index) + " does not exist");
    const tinygltf::Camera& camera = model_.cameras[index];
    CameraSpec spec;
    spec.camera_name = camera.name;
    std::string name = !node_name.empty()     ? node_name
                       : !camera.name.empty() ? camera.name
                                              : "camera_" + std::to_string(index);
    for (const CameraSpec& existing : scene_.cameras)
      if (existing.name == name) name.append("_").append(std::to_string(scene_.cameras.size()));
    spec.name = name;
    spec.camera_to_world = camera_pose(world, what);
    if (camera.type == "perspective") {
      spec.yfov = float(camera.perspective.yfov);
      spec.aspect = float(camera.perspective.aspectRatio);
    } else if (camera.type == "orthographic") {
      const double xmag = camera.orthographic.xmag, ymag = camera.orthographic.ymag;
      if (!(xmag > 0.0 && ymag > 0.0 && std::isfinite(xmag) && std::isfinite(ymag)))
        fail(what + ": orthographic camera " + std::to_string(index) + " needs xmag and ymag > 0 (got " +
             std::to_string(xmag) + ", " + std::to_string(ymag) + ")");
      spec.projection = Projection::orthographic;
      spec.ymag = float(ymag);
      spec.aspect = float(xmag / ymag);
    } else {
      fail(what + ": camera type '" + camera.type + "' is not supported (perspective or orthographic)");
    }
    scene_.cameras.push_back(spec);
  }

  // The camera's rigid pose: scale in the hierarchy must not skew the rays. A mirroring
  // transform (determinant < 0) has no rotation that keeps every axis; the camera then
  // looks along the node's -Z with the node's +Y up, and its X axis follows from those.
  Eigen::Affine3f camera_pose(const Eigen::Affine3f& world, const std::string& what) const {
    Eigen::Affine3f pose = Eigen::Affine3f::Identity();
    pose.translation() = world.translation();
    if (world.linear().determinant() >= 0.0f) {
      pose.linear() = world.rotation();
      return pose;
    }
    warn(path_ + ": " + what + ": the camera's transform mirrors (a negative scale); the camera looks along the " +
         "node's -Z axis with its +Y up, and the picture is not mirrored");
    const Vec3 z = world.linear().col(2).normalized();
    const Vec3 y = (world.linear().col(1) - world.linear().col(1).dot(z) * z).normalized();
    pose.linear() << y.cross(z), y, z;
    return pose;
  }

  void add_sphere(const Value& sphere, const Eigen::Affine3f& world, const std::string& what) {
    const Value* radius = member(sphere, "radius");
    const Value* material = member(sphere, "material");
    if (!radius) fail(what + ": extras.glaze.sphere needs a radius");
    const float r = float(number(*radius, what + " sphere radius"));
    // The node's scale multiplies the radius; it must be uniform for a sphere to stay one.
    const Eigen::Matrix3f linear = world.linear();
    const float s0 = linear.col(0).norm(), s1 = linear.col(1).norm(), s2 = linear.col(2).norm();
    if (std::abs(s0 - s1) > 1e-4f * s0 || std::abs(s0 - s2) > 1e-4f * s0)
      fail(what + ": a glaze sphere's node must not be scaled non-uniformly");
    if (!(r * s0 > 0.0f)) fail(what + ": sphere radius must be positive");
    const int material_number = material ? int(number(*material, what + " sphere material")) : -1;
    scene_.spheres.push_back(
        {what, world.translation(), r * s0, material_index(material_number, what), world.rotation()});
  }

  int material_index(int index, const std::string& what) {
    if (index < 0) {  // glTF's default material: white base, our default coat
      if (default_material_ < 0) {
        scene_.materials.push_back(SceneMaterial{"default", 0.04f, RGB::Ones(), -1});
        default_material_ = static_cast<int>(scene_.materials.size()) - 1;
      }
      return default_material_;
    }
    if (index >= static_cast<int>(model_.materials.size()))
      fail(what + ": material " + std::to_string(index) + " does not exist");
    return index;
  }

  // Fails unless an attribute's `found` components per element are one of `allowed`;
  // `subject` names it (an accessor, a Draco attribute).
  void require_components(int found, std::initializer_list<int> allowed, const std::string& subject) const {
    if (std::find(allowed.begin(), allowed.end(), found) != allowed.end()) return;
    std::string expected;
    for (int count : allowed) expected.append(expected.empty() ? "" : " or ").append(std::to_string(count));
    fail(subject + " has the wrong type (" + std::to_string(found) + " components; expected " + expected + ")");
  }

  // Reads accessor `index` as floats, `allowed` components per element (COLOR_0: 3 or 4),
  // checking every bound on the way; `components_found` receives the count. Integer
  // components are converted as glTF says: normalised ones to [0, 1] or [-1, 1], the
  // others (KHR_mesh_quantization) to their value.
  std::vector<float> read_floats(int index, std::initializer_list<int> allowed, const std::string& what,
                                 int* components_found = nullptr) const {
    const tinygltf::Accessor& accessor = accessor_at(index, what);
    const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
    require_components(components, allowed, what + ": accessor " + std::to_string(index));
    if (components_found) *components_found = components;
    std::vector<float> values(accessor.count * components);
    const bool normalized = accessor.normalized;
    for_each_component(accessor, what, [&](size_t element, int component, const unsigned char* p) {
      float v = 0.0f;
      const auto integer = [&](auto raw, float largest) {
        std::memcpy(&raw, p, sizeof(raw));
        return normalized ? std::max(float(raw) / largest, -1.0f) : float(raw);
      };
      switch (accessor.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
          std::memcpy(&v, p, 4);
          break;
        case TINYGLTF_COMPONENT_TYPE_BYTE:
          v = integer(int8_t(), 127.0f);
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
          v = integer(uint8_t(), 255.0f);
          break;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
          v = integer(int16_t(), 32767.0f);
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
          v = integer(uint16_t(), 65535.0f);
          break;
        default:
          fail(what + ": accessor " + std::to_string(index) + " has an unsupported component type");
      }
      if (!std::isfinite(v)) fail(what + ": accessor " + std::to_string(index) + " contains a non-finite value");
      values[element * components + component] = v;
    });
    return values;
  }

  std::vector<uint32_t> read_indices(int index, const std::string& what) const {
    const tinygltf::Accessor& accessor = accessor_at(index, what);
    if (accessor.type != TINYGLTF_TYPE_SCALAR) fail(what + ": index accessor must be SCALAR");
    std::vector<uint32_t> indices(accessor.count);
    for_each_component(accessor, what, [&](size_t element, int, const unsigned char* p) {
      switch (accessor.componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
          indices[element] = *p;
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          uint16_t s;
          std::memcpy(&s, p, 2);
          indices[element] = s;
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
          std::memcpy(&indices[element], p, 4);
          break;
        default:
          fail(what + ": index accessor has an unsupported component type");
      }
    });
    return indices;
  }

  const tinygltf::Accessor& accessor_at(int index, const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size()))
      fail(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& accessor = model_.accessors[index];
    if (accessor.sparse.isSparse) fail(what + ": sparse accessors are not supported");
    return accessor;
  }

  void for_each_component(const tinygltf::Accessor& accessor, const std::string& what,
                          const std::function<void(size_t, int, const unsigned char*)>& visit) const {
    if (accessor.bufferView < 0 || accessor.bufferView >= static_cast<int>(model_.bufferViews.size()))
      fail(what + ": accessor refers to bufferView " + std::to_string(accessor.bufferView) + ", which does not exist");
    const tinygltf::BufferView& view = model_.bufferViews[accessor.bufferView];
    if (view.extensions.count("EXT_meshopt_compression") || view.extensions.count("KHR_meshopt_compression"))
      fail(what +
           ": its data is compressed with EXT_meshopt_compression, which glaze cannot decode "
           "(decompress the file first, e.g. `gltf-transform copy IN OUT`)");
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model_.buffers.size()))
      fail(what + ": bufferView " + std::to_string(accessor.bufferView) + " refers to buffer " +
           std::to_string(view.buffer) + ", which does not exist");
    const std::vector<unsigned char>& data = model_.buffers[view.buffer].data;
    const int stride = accessor.ByteStride(view);
    const int component_size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(accessor.componentType));
    const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
    if (stride <= 0 || component_size <= 0 || components <= 0) fail(what + ": accessor has an invalid layout");
    const size_t element_size = size_t(component_size) * components;
    if (accessor.count > 0) {
      const size_t last = view.byteOffset + accessor.byteOffset + (accessor.count - 1) * size_t(stride) + element_size;
      if (last > view.byteOffset + view.byteLength || view.byteOffset + view.byteLength > data.size())
        fail(what + ": accessor reads past the end of buffer " + std::to_string(view.buffer) + " (" +
             std::to_string(data.size()) + " bytes; is the .bin file missing or truncated?)");
    }
    const unsigned char* base = data.data() + view.byteOffset + accessor.byteOffset;
    for (size_t e = 0; e < accessor.count; ++e)
      for (int c = 0; c < components; ++c) visit(e, c, base + e * size_t(stride) + size_t(c) * component_size);
  }

  // A primitive's vertex attributes and indices, read from its accessors or decoded from
  // its KHR_draco_mesh_compression buffer, whichever the file gives.
  class PrimitiveSource {
   public:
    PrimitiveSource(const GltfLoader& loader, const tinygltf::Primitive& primitive, const std::string& what)
        : loader_(loader), primitive_(primitive), what_(what) {
      const auto draco = primitive.extensions.find("KHR_draco_mesh_compression");
      if (draco != primitive.extensions.end()) decode_draco(draco->second);
    }

    bool has(const std::string& attribute) const {
      return draco_ ? draco_attributes_.count(attribute) > 0 : primitive_.attributes.count(attribute) > 0;
    }

    // As read_floats; the attribute must exist (has()).
    std::vector<float> floats(const std::string& attribute, std::initializer_list<int> allowed,
                              int* components_found = nullptr) const {
      if (!draco_)
        return loader_.read_floats(primitive_.attributes.at(attribute), allowed, what_ + " " + attribute,
                                   components_found);
      const draco::PointAttribute* source = draco_->GetAttributeByUniqueId(draco_attributes_.at(attribute));
      if (!source) loader_.fail(what_ + ": the Draco data has no attribute for " + attribute);
      const int components = source->num_components();
      loader_.require_components(components, allowed, what_ + ": Draco attribute " + attribute);
      if (components_found) *components_found = components;
      std::vector<float> values(size_t(draco_->num_points()) * components);
      for (draco::PointIndex point(0); point < draco_->num_points(); ++point)
        if (!source->ConvertValue<float>(source->mapped_index(point), components,
                                         values.data() + size_t(point.value()) * components))
          loader_.fail(what_ + ": Draco attribute " + attribute + " cannot be read as numbers");
      for (float v : values)
        if (!std::isfinite(v)) loader_.fail(what_ + ": Draco attribute " + attribute + " contains a non-finite value");
      return values;
    }

    // The triangle list's vertex indices; `vertex_count` when the primitive has none.
    std::vector<uint32_t> indices(size_t vertex_count) const {
      std::vector<uint32_t> indices;
      if (draco_) {
        for (draco::FaceIndex f(0); f < draco_->num_faces(); ++f)
          for (int k = 0; k < 3; ++k) indices.push_back(draco_->face(f)[k].value());
      } else if (primitive_.indices >= 0) {
        indices = loader_.read_indices(primitive_.indices, what_ + " indices");
      } else {
        for (uint32_t v = 0; v < vertex_count; ++v) indices.push_back(v);
      }
      return indices;
    }

   private:
    void decode_draco(const Value& extension) {
      const Value* view_value = member(extension, "bufferView");
      const Value* attributes = member(extension, "attributes");
      if (!view_value || !attributes || !attributes->IsObject())
        loader_.fail(what_ + ": KHR_draco_mesh_compression needs bufferView and attributes");
      const double view_index = loader_.number(*view_value, what_ + " KHR_draco_mesh_compression.bufferView");
      if (view_index < 0 || view_index >= double(loader_.model_.bufferViews.size()))
        loader_.fail(what_ + ": KHR_draco_mesh_compression.bufferView does not exist");
      const tinygltf::BufferView& view = loader_.model_.bufferViews[size_t(view_index)];
      if (view.buffer < 0 || view.buffer >= static_cast<int>(loader_.model_.buffers.size()) ||
          view.byteOffset + view.byteLength > loader_.model_.buffers[view.buffer].data.size())
        loader_.fail(what_ + ": KHR_draco_mesh_compression's bufferView lies outside its buffer");
      draco::DecoderBuffer buffer;
      buffer.Init(reinterpret_cast<const char*>(loader_.model_.buffers[view.buffer].data.data() + view.byteOffset),
                  view.byteLength);
      draco::Decoder decoder;
      auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
      if (!decoded.ok())
        loader_.fail(what_ + ": its KHR_draco_mesh_compression data cannot be decoded (" +
                     decoded.status().error_msg_string() + ")");
      draco_ = std::move(decoded).value();
      for (const std::string& key : attributes->Keys())
        draco_attributes_[key] = int(loader_.number(attributes->Get(key), what_ + " Draco attribute " + key));
    }

    const GltfLoader& loader_;
    const tinygltf::Primitive& primitive_;
    std::string what_;
    std::unique_ptr<draco::Mesh> draco_;
    std::map<std::string, int> draco_attributes_;
  };

  void add_mesh(int index, const Eigen::Affine3f& world, const std::string& node_what) {
    if (index >= static_cast<int>(model_.meshes.size()))
      fail(node_what + ": mesh " + std::to_string(index) + " does not exist");
    const tinygltf::Mesh& mesh = model_.meshes[index];
    const Eigen::Matrix3f normal_matrix = world.linear().inverse().transpose();
    if (!normal_matrix.allFinite()) fail(node_what + ": transform is singular");
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& primitive = mesh.primitives[p];
      const std::string what = "mesh " + std::to_string(index) + (mesh.name.empty() ? "" : " '" + mesh.name + "'") +
                               " primitive " + std::to_string(p);
      if (primitive.mode != TINYGLTF_MODE_TRIANGLES) {
        ++ignored_["point, line and strip primitives"];
        continue;
      }
      const PrimitiveSource source(*this, primitive, what);
      if (!source.has("POSITION")) fail(what + " has no POSITION attribute");
      TriangleMesh out;
      out.name = what;
      out.material = material_index(primitive.material, what);
      const std::vector<float> positions = source.floats("POSITION", {3});
      const size_t vertex_count = positions.size() / 3;
      for (size_t v = 0; v < vertex_count; ++v)
        out.positions.push_back(world * Vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]));
      const std::vector<uint32_t> indices = source.indices(vertex_count);
      if (indices.size() % 3 != 0)
        fail(what + ": index count " + std::to_string(indices.size()) + " is not a multiple of 3");
      // A transform with negative determinant mirrors the mesh, which reverses the
      // winding (glTF 2.0 §3.7.4); swapping two corners keeps faces facing outwards.
      const bool mirrored = world.linear().determinant() < 0.0f;
      for (size_t t = 0; t < indices.size(); t += 3) {
        for (int k = 0; k < 3; ++k)
          if (indices[t + k] >= vertex_count)
            fail(what + ": index " + std::to_string(indices[t + k]) + " is out of range (" +
                 std::to_string(vertex_count) + " vertices)");
        if (mirrored)
          out.triangles.push_back({indices[t], indices[t + 2], indices[t + 1]});
        else
          out.triangles.push_back({indices[t], indices[t + 1], indices[t + 2]});
      }
      // Without NORMAL the mesh stays flat (glTF 2.0 §3.7.2.1): the ray tracer shades each
      // face with its own normal.
      if (source.has("NORMAL")) {
        const std::vector<float> normals = source.floats("NORMAL", {3});
        if (normals.size() != positions.size()) fail(what + ": NORMAL and POSITION counts differ");
        for (size_t v = 0; v < vertex_count; ++v) {
          const Vec3 n = normal_matrix * Vec3(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
          out.normals.push_back(n.norm() > 0.0f ? n.normalized() : Vec3(0, 1, 0));
        }
      }
      const SceneMaterial& material = scene_.materials[out.material];
      if (material.texture >= 0) {
        const std::string set = "TEXCOORD_" + std::to_string(material.texcoord);
        if (!source.has(set))
          fail(what + ": its material's texture reads " + set + ", which the primitive does not have");
        const std::vector<float> uvs = source.floats(set, {2});
        if (uvs.size() / 2 != vertex_count) fail(what + ": " + set + " and POSITION counts differ");
        for (size_t v = 0; v < vertex_count; ++v) out.uvs.push_back(Vec2(uvs[2 * v], uvs[2 * v + 1]));
      }
      if (source.has("COLOR_0")) {
        int components = 0;
        const std::vector<float> colors = source.floats("COLOR_0", {3, 4}, &components);
        if (colors.size() / components != vertex_count) fail(what + ": COLOR_0 and POSITION counts differ");
        for (size_t v = 0; v < vertex_count; ++v) {  // alpha (coverage) is not modelled
          const float* c = &colors[v * components];
          out.colors.push_back(RGB(c[0], c[1], c[2]).max(0.0f).min(1.0f));
        }
      }
      if (!out.triangles.empty()) scene_.meshes.push_back(std::move(out));
    }
  }

  void read_scene_extras(const Value& extras) {
    const Value* glaze = member(extras, "glaze");
    if (!glaze) return;
    if (const Value* film = member(*glaze, "film")) {
      const Value* w = member(*film, "width");
      const Value* h = member(*film, "height");
      if (!w || !h) fail("scene extras.glaze.film needs width and height");
      const double width = number(*w, "film width"), height = number(*h, "film height");
      if (width < 1 || height < 1 || width > 65536 || height > 65536 || width != std::floor(width) ||
          height != std::floor(height))
        fail("scene extras.glaze.film must be whole numbers of pixels in [1, 65536]");
      scene_.film = std::pair{int(width), int(height)};
    }
    if (const Value* environment = member(*glaze, "environment")) {
      EnvironmentSpec spec;
      if (const Value* file = member(*environment, "file")) {
        if (!file->IsString()) fail("scene extras.glaze.environment.file must be a string");
        const std::filesystem::path file_path = file->Get<std::string>();
        spec.source = file_path.is_absolute() ? file_path.string() : (directory() / file_path).string();
      } else if (const Value* procedural = member(*environment, "procedural")) {
        if (!procedural->IsString()) fail("scene extras.glaze.environment.procedural must be a string");
        spec.source = "procedural:" + procedural->Get<std::string>();
        if (const Value* w = member(*environment, "width")) spec.width = int(number(*w, "environment width"));
        if (const Value* h = member(*environment, "height")) spec.height = int(number(*h, "environment height"));
      } else {
        fail("scene extras.glaze.environment needs \"file\" or \"procedural\"");
      }
      if (const Value* scale = member(*environment, "scale"))
        spec.options.scale = float(number(*scale, "environment scale"));
      if (const Value* rotation = member(*environment, "rotation"))
        spec.options.rotation_degrees = float(number(*rotation, "environment rotation"));
      if (const Value* to_world = member(*environment, "to_world")) {
        if (!to_world->IsArray() || to_world->ArrayLen() != 3) fail("environment to_world must be a 3x3 array of rows");
        for (int r = 0; r < 3; ++r) {
          const Value& row = to_world->Get(r);
          if (!row.IsArray() || row.ArrayLen() != 3) fail("environment to_world must be a 3x3 array of rows");
          for (int c = 0; c < 3; ++c) spec.options.to_world(r, c) = float(number(row.Get(c), "environment to_world"));
        }
      }
      scene_.environment = spec;
    }
  }

  std::string path_;
  tinygltf::Model model_;
  Scene scene_;
  std::map<int, Image> decoded_;
  std::map<int, int> texture_of_gltf_texture_;  // a texture is an image and a sampler
  std::map<std::string, int> ignored_;          // feature -> count, for the one warning
  std::set<int> on_path_;
  int default_material_ = -1;
};

}  // namespace

Scene load_scene(const std::string& path) { return GltfLoader(path).load(); }

}  // namespace glaze
