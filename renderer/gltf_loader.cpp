// gltf_loader.cpp: glTF 2.0 (.gltf, .glb) -> Scene, with tinygltf (docs/design.md §4).
//
// Every index the file contains is checked before it is followed, so that a malformed
// file gives a glaze::Error naming the element at fault instead of undefined behaviour:
// the JSON is parsed first with its depth bounded and every index and size in it checked
// to be a whole number in range (tinygltf recurses over deep JSON and casts numbers
// without checking), byte ranges are checked without overflow before anything is read or
// allocated, and the node hierarchy is walked without recursion.
// Images are decoded by OpenImageIO (tinygltf's own decoder is bypassed) so that EXR
// textures work and 8-bit ones are linearised from sRGB like every other image in glaze.
// Draco-compressed primitives are decoded here with the Draco library (Debian's tinygltf
// is built without it). What a file uses that glaze does not model is counted and
// reported in one warning per scene; what glaze cannot read at all (a required extension
// it does not know, meshopt-compressed buffers) is refused by name.
#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/input_file.h"
#include "renderer/json_input.h"
#include "renderer/memory_budget.h"
#include "renderer/scene.h"

#include <tiny_gltf.h>

#include <draco/compression/decode.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <nlohmann/json.hpp>

#include <climits>
#include <filesystem>
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
        visit_tree(i);
      }
      if (!any_root && !model_.nodes.empty()) fail("every node is some node's child: the node hierarchy has a cycle");
    } else {
      if (scene_index >= static_cast<int>(model_.scenes.size()))
        fail("defaultScene " + std::to_string(scene_index) + " does not exist");
      const tinygltf::Scene& scene = model_.scenes[scene_index];
      for (int node : scene.nodes) visit_tree(node);
      read_scene_extras(scene.extras);
    }
    if (scene_.meshes.empty() && scene_.spheres.empty())
      fail("the scene contains no geometry (no mesh and no glaze sphere)");
    warn_about_blind_cameras();
    warn_about_ignored_features();
    return std::move(scene_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw Error(path_ + ": " + what); }

  std::filesystem::path directory() const { return std::filesystem::path(path_).parent_path(); }

  void read_model() {
    std::string bytes = read_whole_file(path_, "glTF scene (a .gltf or .glb file)");
    const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
    const auto [json_begin, json_size] = json_chunk(bytes, binary);
    nlohmann::json document;
    try {
      document = parse_json_limited(std::string_view(bytes).substr(json_begin, json_size), path_);
    } catch (const Error& e) {
      throw Error(e.what() + std::string(" (a glTF 2.0 scene was expected)"));
    }
    check_numbers(document);
    if (without_draco_indices(document)) replace_json(bytes, binary, json_begin, json_size, document.dump());
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&GltfLoader::decode_image, this);
    loader.SetFsCallbacks({&file_exists, &unexpanded_path, &read_uri_file, &tinygltf::WriteWholeFile, nullptr});
    std::string error, warning;
    const std::string base = directory().string();
    if (bytes.size() > UINT_MAX) fail("is larger than 4 GiB, which tinygltf cannot read");
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

  // A camera with every mesh and sphere behind it renders the environment only; the
  // usual cause is a wrong rotation or scale in the file, so it is worth a warning. Each
  // piece of geometry is bounded by a sphere, so that the test errs towards silence.
  void warn_about_blind_cameras() const {
    std::vector<std::pair<Vec3, float>> bounds;  // centre, radius
    for (const Sphere& sphere : scene_.spheres) bounds.emplace_back(sphere.center, sphere.radius);
    for (const TriangleMesh& mesh : scene_.meshes) {
      Eigen::AlignedBox3f box;
      for (const Vec3& p : mesh.positions) box.extend(p);
      bounds.emplace_back(box.center(), 0.5f * box.diagonal().norm());
    }
    for (const CameraSpec& camera : scene_.cameras) {
      const Vec3 eye = camera.camera_to_world.translation();
      const Vec3 forward = -camera.camera_to_world.linear().col(2);  // a glTF camera looks along its -Z
      const bool sees_some = std::any_of(bounds.begin(), bounds.end(), [&](const auto& bound) {
        return (bound.first - eye).dot(forward) + bound.second > 0.0f;
      });
      if (!sees_some)
        warn(path_ + ": camera '" + camera.name +
             "' sees none of the scene: every mesh and sphere lies behind it (check its node's rotation and scale)");
    }
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

  // Where the JSON is in `bytes`: all of a .gltf, the first chunk of a .glb.
  std::pair<size_t, size_t> json_chunk(const std::string& bytes, bool binary) const {
    if (!binary) return {0, bytes.size()};
    uint32_t chunk_size = 0, chunk_type = 0;
    if (bytes.size() < 20) fail("the .glb file is truncated");
    std::memcpy(&chunk_size, bytes.data() + 12, 4);
    std::memcpy(&chunk_type, bytes.data() + 16, 4);
    if (chunk_type != 0x4E4F534Au || chunk_size > bytes.size() - 20)
      fail("the .glb file's first chunk is not its JSON");
    return {20, chunk_size};
  }

  // Replaces the JSON of `bytes` (at json_begin, json_size) by `text`.
  static void replace_json(std::string& bytes, bool binary, size_t json_begin, size_t json_size, std::string text) {
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

  // tinygltf, built without Draco, refuses a primitive whose indices accessor has no
  // bufferView, which is how Draco-compressed primitives are written. Their indices come
  // from the Draco data, so the reference is dropped from the JSON before tinygltf reads
  // it. Returns whether anything was dropped (files without Draco are handed over untouched).
  static bool without_draco_indices(nlohmann::json& document) {
    const std::string draco = "KHR_draco_mesh_compression";
    bool changed = false;
    if (!document.is_object() || !document.contains("meshes") || !document["meshes"].is_array()) return false;
    for (auto& mesh : document["meshes"])
      if (mesh.is_object() && mesh.contains("primitives") && mesh["primitives"].is_array())
        for (auto& primitive : mesh["primitives"])
          if (primitive.is_object() && primitive.contains("extensions") && primitive["extensions"].is_object() &&
              primitive["extensions"].contains(draco))
            changed |= primitive.erase("indices") > 0;
    return changed;
  }

  // Checks every index and size in the glTF JSON that tinygltf or glaze will read before
  // tinygltf reads it: tinygltf casts integers to int without a check (2^32 becomes 0)
  // and silently skips an index that is not an integer (a material of 1e300 or "0" would
  // become the default material). Indices must be whole numbers in [0, 2^31 - 1], sizes
  // and offsets whole numbers in [0, 2^53]. Under "extras" only glaze's own object is
  // checked, under "extensions" only the extensions glaze reads. Iterative: the JSON is
  // at most kMaxJsonDepth deep, but wide.
  void check_numbers(const nlohmann::json& document) const {
    static const std::set<std::string> kIndexKeys = {
        "scene",      "nodes",  "children", "mesh",   "camera", "skin",     "material", "indices", "attributes",
        "bufferView", "buffer", "sampler",  "source", "index",  "texCoord", "joints",   "skeleton"};
    static const std::set<std::string> kSizeKeys = {"count", "byteOffset", "byteLength", "byteStride"};
    constexpr int64_t kMaxIndex = INT_MAX, kMaxSize = int64_t(1) << 53;
    const auto require = [&](const nlohmann::json& value, int64_t highest, const std::string& where) {
      if (value.is_number() && integer_from(value.get<double>(), 0, highest)) return;
      fail(where + " must be " +
           (highest == kMaxIndex ? "an index (a whole number from 0 to 2147483647)" : "a whole number from 0 to 2^53") +
           ", not " + json_excerpt(value));
    };
    struct Pending {
      const nlohmann::json* value;
      std::string where;
      bool glaze_extras;  // tinygltf hands these on with every integer cast to int
    };
    std::vector<Pending> pending = {{&document, "", false}};
    while (!pending.empty()) {
      const auto [value, where, glaze_extras] = std::move(pending.back());
      pending.pop_back();
      if (value->is_array()) {
        for (size_t i = 0; i < value->size(); ++i)
          pending.push_back({&(*value)[i], where + "[" + std::to_string(i) + "]", glaze_extras});
        continue;
      }
      if (glaze_extras && value->is_number_integer() && !integer_from(value->get<double>(), INT_MIN, INT_MAX))
        fail(where + " must be below 2^31 (as a whole number), not " + json_excerpt(*value));
      if (!value->is_object()) continue;
      for (const auto& [key, member] : value->items()) {
        const std::string path = where.empty() ? key : where + "." + key;
        if (key == "extras" || key == "extensions") {  // only what glaze reads
          if (!member.is_object()) continue;
          for (const auto& [name, extension] : member.items())
            if (key == "extras" ? name == "glaze" : kSupportedExtensions.count(name) > 0)
              pending.push_back({&extension, path + "." + name, glaze_extras || key == "extras"});
        } else if (kSizeKeys.count(key)) {
          require(member, kMaxSize, path);
        } else if (kIndexKeys.count(key) && !member.is_structured()) {
          require(member, kMaxIndex, path);
        } else if ((key == "attributes" || key == "nodes" || key == "children" || key == "joints") &&
                   member.is_structured()) {
          // Lists and maps of indices; "nodes" at the top is the list of node objects.
          for (const auto& [name, entry] : member.items()) {
            const std::string entry_path = path + (member.is_array() ? "[" + name + "]" : "." + name);
            if (entry.is_structured())
              pending.push_back({&entry, entry_path, glaze_extras});
            else
              require(entry, kMaxIndex, entry_path);
          }
        } else {
          pending.push_back({&member, path, glaze_extras});
        }
      }
    }
  }

  // tinygltf's file access for buffer and image URIs: FIFOs and devices are refused
  // (tinygltf's own would open them, and block or read forever), sizes are checked
  // against the memory limit, and paths are taken as they are (no shell-like expansion).
  static bool file_exists(const std::string& path, void*) {
    std::error_code ec;
    return std::filesystem::exists(path, ec);
  }
  static std::string unexpanded_path(const std::string& path, void*) { return path; }
  static bool read_uri_file(std::vector<unsigned char>* out, std::string* error, const std::string& path, void*) {
    try {
      const std::string bytes = read_whole_file(path, "glTF buffer or image");
      out->assign(bytes.begin(), bytes.end());
      return true;
    } catch (const Error& e) {
      if (error) *error += e.what();
      return false;
    }
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
      if (image->bufferView >= 0) {  // tinygltf passes the view's bytes without checking its range
        const Bytes view = self->view_bytes(image->bufferView, "image " + std::to_string(index));
        bytes = view.data, size = view.size > size_t(INT_MAX) ? -1 : int(view.size);
      }
      if (size < 0) throw Error("its data is larger than 2 GiB");
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

  // A whole number in [lowest, highest] (an int cast of any other double is undefined).
  int64_t integer(const Value& value, int64_t lowest, int64_t highest, const std::string& what) const {
    const std::optional<int64_t> result =
        value.IsNumber() ? integer_from(value.GetNumberAsDouble(), lowest, highest) : std::nullopt;
    if (!result) {
      char shown[64] = "not a number";
      if (value.IsNumber()) std::snprintf(shown, sizeof shown, "%.17g", value.GetNumberAsDouble());
      fail(what + " must be a whole number from " + std::to_string(lowest) + " to " + std::to_string(highest) +
           ", not " + (value.IsString() ? "\"" + value.Get<std::string>() + "\"" : std::string(shown)));
    }
    return *result;
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
      material.texcoord = int(integer(*texcoord, 0, INT_MAX, where + ".texCoord"));
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

  // Adds what the hierarchy below node `root` carries. Depth first with an explicit stack:
  // a chain of 100,000 nodes must not overflow the call stack. Nodes shared by several
  // parents are visited once per path, so the visits are capped (a tree of shared nodes
  // 60 levels deep has 2^60 paths).
  void visit_tree(int root) {
    struct Frame {
      int node;
      Eigen::Affine3f world;
      bool negative_scale;  // some node on the path from the root has a negative scale
      size_t next_child = 0;
    };
    std::vector<Frame> stack;
    const auto enter = [&](int index, const Eigen::Affine3f& parent, bool negative_scale) {
      if (index < 0 || index >= static_cast<int>(model_.nodes.size()))
        fail("node index " + std::to_string(index) + " does not exist");
      if (++node_visits_ > kMaxNodeVisits)
        fail("the node hierarchy has more than " + std::to_string(kMaxNodeVisits) +
             " node visits (nodes shared by many parents repeat their subtrees); flatten it");
      if (!on_path_.insert(index).second)
        fail("node " + std::to_string(index) + " is its own ancestor (the node hierarchy has a cycle)");
      const tinygltf::Node& node = model_.nodes[index];
      const std::string what = "node " + std::to_string(index) + (node.name.empty() ? "" : " '" + node.name + "'");
      const Eigen::Affine3f world = parent * local_transform(node, what);
      if (!world.matrix().allFinite()) fail(what + ": transform is not finite");
      negative_scale |= std::any_of(node.scale.begin(), node.scale.end(), [](double s) { return s < 0.0; });
      if (node.mesh >= 0) add_mesh(node.mesh, world, what);
      if (node.camera >= 0) add_camera(node.camera, node.name, world, negative_scale, what);
      if (const Value* glaze = member(node.extras, "glaze"))
        if (const Value* sphere = member(*glaze, "sphere")) add_sphere(*sphere, world, what);
      stack.push_back({index, world, negative_scale});
    };
    enter(root, Eigen::Affine3f::Identity(), false);
    while (!stack.empty()) {
      Frame& top = stack.back();
      const std::vector<int>& children = model_.nodes[top.node].children;
      if (top.next_child == children.size()) {
        on_path_.erase(top.node);
        stack.pop_back();
        continue;
      }
      const Eigen::Affine3f parent = top.world;  // `top` moves when the stack grows
      enter(children[top.next_child++], parent, top.negative_scale);
    }
  }

  void add_camera(int index, const std::string& node_name, const Eigen::Affine3f& world, bool negative_scale,
                  const std::string& what) {
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
    // Two negative scale components (det > 0) are a half turn that nothing reports:
    // (-1, 1, -1) makes the camera look along +Z.
    if (negative_scale && world.linear().determinant() >= 0.0f)
      warn(path_ + ": " + what + ": a negative scale on the camera's node or its parents turns the camera (it " +
           "looks along the transformed -Z axis); if it looks the wrong way, use a rotation instead");
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
    const int material_number =
        material ? int(integer(*material, 0, INT_MAX, what + " extras.glaze.sphere.material")) : -1;
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
    const AccessorData data = accessor_data(index, what);
    const int components = data.components;
    require_components(components, allowed, what + ": accessor " + std::to_string(index));
    if (components_found) *components_found = components;
    require_memory(saturating_mul(data.count, components * sizeof(float)),
                   what + " (accessor " + std::to_string(index) + ")");
    std::vector<float> values(data.count * components);
    const bool normalized = accessor.normalized;
    for_each_component(data, [&](size_t element, int component, const unsigned char* p) {
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
    const AccessorData data = accessor_data(index, what);
    require_memory(saturating_mul(data.count, sizeof(uint32_t)), what + " (accessor " + std::to_string(index) + ")");
    std::vector<uint32_t> indices(data.count);
    for_each_component(data, [&](size_t element, int, const unsigned char* p) {
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

  // Bytes inside a buffer: a bufferView, or where an accessor's elements lie.
  struct Bytes {
    const unsigned char* data;
    size_t size;
  };

  // The bytes of bufferView `index`, checked to lie inside its buffer. Accessors, Draco
  // data and images all read through here. No sum is formed: an offset near 2^64 would wrap.
  Bytes view_bytes(int index, const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.bufferViews.size()))
      fail(what + ": bufferView " + std::to_string(index) + " does not exist");
    const tinygltf::BufferView& view = model_.bufferViews[index];
    if (view.extensions.count("EXT_meshopt_compression") || view.extensions.count("KHR_meshopt_compression"))
      fail(what +
           ": its data is compressed with EXT_meshopt_compression, which glaze cannot decode "
           "(decompress the file first, e.g. `gltf-transform copy IN OUT`)");
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model_.buffers.size()))
      fail(what + ": bufferView " + std::to_string(index) + " refers to buffer " + std::to_string(view.buffer) +
           ", which does not exist");
    const std::vector<unsigned char>& data = model_.buffers[view.buffer].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      fail(what + ": bufferView " + std::to_string(index) + " (byteOffset " + std::to_string(view.byteOffset) +
           ", byteLength " + std::to_string(view.byteLength) + ") reaches past the end of buffer " +
           std::to_string(view.buffer) + " (" + std::to_string(data.size()) +
           " bytes; is the .bin file missing or truncated?)");
    return {data.data() + view.byteOffset, view.byteLength};
  }

  // Where accessor `index`'s elements lie: `count` elements of `components` components
  // of `component_size` bytes, one every `stride` bytes from `base`, all checked to lie
  // inside its bufferView without forming a product that could wrap.
  struct AccessorData {
    const unsigned char* base;
    size_t count, stride, component_size;
    int components;
  };
  AccessorData accessor_data(int index, const std::string& what) const {
    const tinygltf::Accessor& accessor = accessor_at(index, what);
    const std::string subject = what + ": accessor " + std::to_string(index);
    const Bytes view = view_bytes(accessor.bufferView, subject);
    const int stride = accessor.ByteStride(model_.bufferViews[accessor.bufferView]);
    const int component_size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(accessor.componentType));
    const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
    if (stride <= 0 || component_size <= 0 || components <= 0) fail(subject + " has an invalid layout");
    const size_t element_size = size_t(component_size) * components;
    const bool fits = accessor.byteOffset <= view.size &&
                      (accessor.count == 0 ||
                       (element_size <= view.size - accessor.byteOffset &&
                        accessor.count - 1 <= (view.size - accessor.byteOffset - element_size) / size_t(stride)));
    if (!fits)
      fail(subject + ": " + std::to_string(accessor.count) + " elements of " + std::to_string(element_size) +
           " bytes, " + std::to_string(stride) + " bytes apart from byteOffset " + std::to_string(accessor.byteOffset) +
           ", do not fit in bufferView " + std::to_string(accessor.bufferView) + " (" + std::to_string(view.size) +
           " bytes)");
    return {view.data + accessor.byteOffset, accessor.count, size_t(stride), size_t(component_size), components};
  }

  static void for_each_component(const AccessorData& data,
                                 const std::function<void(size_t, int, const unsigned char*)>& visit) {
    for (size_t e = 0; e < data.count; ++e)
      for (int c = 0; c < data.components; ++c) visit(e, c, data.base + e * data.stride + c * data.component_size);
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
      const auto view_index =
          loader_.integer(*view_value, 0, INT_MAX, what_ + " KHR_draco_mesh_compression.bufferView");
      const Bytes view = loader_.view_bytes(int(view_index), what_ + " KHR_draco_mesh_compression");
      draco::DecoderBuffer buffer;
      buffer.Init(reinterpret_cast<const char*>(view.data), view.size);
      draco::Decoder decoder;
      auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
      if (!decoded.ok())
        loader_.fail(what_ + ": its KHR_draco_mesh_compression data cannot be decoded (" +
                     decoded.status().error_msg_string() + ")");
      draco_ = std::move(decoded).value();
      for (const std::string& key : attributes->Keys())
        draco_attributes_[key] = int(
            loader_.integer(attributes->Get(key), 0, INT_MAX, what_ + " KHR_draco_mesh_compression.attributes." + key));
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
      const auto width = integer(*w, 1, 65536, "scene extras.glaze.film.width");
      const auto height = integer(*h, 1, 65536, "scene extras.glaze.film.height");
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
        const std::string where = "scene extras.glaze.environment";
        if (const Value* w = member(*environment, "width")) spec.width = int(integer(*w, 1, 65536, where + ".width"));
        if (const Value* h = member(*environment, "height"))
          spec.height = int(integer(*h, 1, 65536, where + ".height"));
        require_memory(saturating_mul(uint64_t(spec.width) * uint64_t(spec.height), sizeof(RGB)),
                       where + " (a procedural map of " + std::to_string(spec.width) + "x" +
                           std::to_string(spec.height) + " texels)");
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
      if (const Value* format = member(*environment, "format")) {
        if (!format->IsString()) fail("scene extras.glaze.environment.format must be a string");
        spec.options.format =
            parse_environment_format(format->Get<std::string>(), path_ + ": scene extras.glaze.environment");
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
  static constexpr int64_t kMaxNodeVisits = 1000000;
  std::set<int> on_path_;
  int64_t node_visits_ = 0;
  int default_material_ = -1;
};

}  // namespace

Scene load_scene(const std::string& path) { return GltfLoader(path).load(); }

}  // namespace glaze
