// gltf_builder.h: glTF files written by tests (buffers as base64 data URIs, PNG
// textures from a minimal encoder of our own), so that every scene a test loads is built
// in code from numbers the test knows, never a third-party sample file.
#pragma once

#include "test_support.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace glaze::testing {

using nlohmann::json;

inline const float kS = std::sqrt(0.5f);  // sin 45 = cos 45: quaternions of 90-degree turns

inline std::string base64(const std::vector<unsigned char>& bytes) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t n = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8) | bytes[i + 2];
    for (int k = 3; k >= 0; --k) out += alphabet[(n >> (6 * k)) & 63];
  }
  if (i + 1 == bytes.size()) {
    const uint32_t n = uint32_t(bytes[i]) << 16;
    out += alphabet[(n >> 18) & 63];
    out += alphabet[(n >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const uint32_t n = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8);
    out += alphabet[(n >> 18) & 63];
    out += alphabet[(n >> 12) & 63];
    out += alphabet[(n >> 6) & 63];
    out += '=';
  }
  return out;
}

// Collects vertex data into one buffer and describes it with bufferViews and accessors.
class GltfBuffer {
 public:
  // VEC4 / VEC3 / VEC2 / SCALAR float accessor over `values`; returns its index.
  int floats(const std::vector<float>& values, int components) {
    const char* type = components == 4 ? "VEC4" : components == 3 ? "VEC3" : components == 2 ? "VEC2" : "SCALAR";
    return add(values.data(), values.size() * sizeof(float), 5126, type, values.size() / components);
  }
  // SCALAR unsigned-short index accessor; returns its index.
  int indices(const std::vector<uint16_t>& values) {
    return add(values.data(), values.size() * sizeof(uint16_t), 5123, "SCALAR", values.size());
  }
  // Writes buffers, bufferViews and accessors into `gltf`; the buffer as a data URI.
  void into(json& gltf) const {
    gltf["buffers"] = json::array(
        {{{"byteLength", bytes_.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes_)}}});
    gltf["bufferViews"] = views_;
    gltf["accessors"] = accessors_;
  }
  const std::vector<unsigned char>& bytes() const { return bytes_; }
  // A bufferView over `size` raw bytes (compressed data, for instance); returns its index.
  int view(const void* data, size_t size) {
    while (bytes_.size() % 4) bytes_.push_back(0);
    const size_t offset = bytes_.size();
    bytes_.resize(offset + size);
    std::memcpy(bytes_.data() + offset, data, size);
    views_.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}});
    return static_cast<int>(views_.size()) - 1;
  }
  // Any accessor description (an accessor of Draco-compressed data has no bufferView).
  int accessor(const json& description) {
    accessors_.push_back(description);
    return static_cast<int>(accessors_.size()) - 1;
  }

 private:
  int add(const void* data, size_t size, int component_type, const char* type, size_t count) {
    accessors_.push_back(
        {{"bufferView", view(data, size)}, {"componentType", component_type}, {"count", count}, {"type", type}});
    return static_cast<int>(accessors_.size()) - 1;
  }
  std::vector<unsigned char> bytes_;
  json views_ = json::array(), accessors_ = json::array();
};

// A glTF document with one scene whose root nodes are `roots`. (std::vector, not json,
// for the lists: a one-element braced list of a json value would be a copy, not an array.)
inline json gltf_document(const std::vector<json>& nodes, const std::vector<int>& roots) {
  json scene = json::object();
  scene["nodes"] = roots;
  json gltf = {{"asset", {{"version", "2.0"}}}, {"scene", 0}};
  gltf["scenes"] = json::array({scene});
  gltf["nodes"] = nodes;
  return gltf;
}

// A node carrying a glaze sphere.
inline json sphere_node(double radius, int material = -1) {
  json sphere = {{"radius", radius}};
  if (material >= 0) sphere["material"] = material;
  return {{"extras", {{"glaze", {{"sphere", sphere}}}}}};
}

// A material that triggers no warning (metallic and roughness 0), with extra fields.
inline json quiet_material(json extra = json::object()) {
  json material = {{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"roughnessFactor", 0.0}}}};
  for (auto& [key, value] : extra.items()) {
    if (key == "pbrMetallicRoughness")
      material["pbrMetallicRoughness"].update(value);
    else
      material[key] = value;
  }
  return material;
}

inline std::string write_text(const TemporaryDirectory& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

inline std::string write_gltf(const TemporaryDirectory& dir, const std::string& name, const json& gltf) {
  return write_text(dir, name, gltf.dump(2));
}

// --- A minimal PNG encoder (stored deflate blocks), independent of the image code. ---

inline uint32_t crc32(const unsigned char* data, size_t size, uint32_t crc = 0) {
  crc = ~crc;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

inline void put_be32(std::vector<unsigned char>& out, uint32_t v) {
  for (int k = 3; k >= 0; --k) out.push_back(static_cast<unsigned char>(v >> (8 * k)));
}

inline void png_chunk(std::vector<unsigned char>& out, const char* type, const std::vector<unsigned char>& data) {
  put_be32(out, static_cast<uint32_t>(data.size()));
  std::vector<unsigned char> typed(type, type + 4);
  typed.insert(typed.end(), data.begin(), data.end());
  out.insert(out.end(), typed.begin(), typed.end());
  put_be32(out, crc32(typed.data(), typed.size()));
}

// An 8-bit RGB PNG of `width` x `height` pixels, `rgb` row-major from the top.
inline std::vector<unsigned char> encode_png(int width, int height, const std::vector<unsigned char>& rgb) {
  std::vector<unsigned char> raw;  // each row: filter type 0, then the pixels
  for (int y = 0; y < height; ++y) {
    raw.push_back(0);
    raw.insert(raw.end(), rgb.begin() + y * width * 3, rgb.begin() + (y + 1) * width * 3);
  }
  std::vector<unsigned char> zlib = {0x78, 0x01, 0x01};  // zlib header; one final stored block
  const uint16_t length = static_cast<uint16_t>(raw.size()), complement = static_cast<uint16_t>(~length);
  zlib.insert(zlib.end(),
              {uint8_t(length & 0xff), uint8_t(length >> 8), uint8_t(complement & 0xff), uint8_t(complement >> 8)});
  zlib.insert(zlib.end(), raw.begin(), raw.end());
  uint32_t a = 1, b = 0;  // Adler-32
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  put_be32(zlib, (b << 16) | a);

  std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<unsigned char> header;
  put_be32(header, uint32_t(width));
  put_be32(header, uint32_t(height));
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8 bits, RGB, deflate, no filter, no interlace
  png_chunk(png, "IHDR", header);
  png_chunk(png, "IDAT", zlib);
  png_chunk(png, "IEND", {});
  return png;
}

// The sRGB decoding formula (IEC 61966-2-1), written out here for the expectations.
inline double srgb_decode(int byte) {
  const double c = byte / 255.0;
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

// load_scene must throw glaze::Error mentioning every one of `words`.
inline void expect_load_error(const TemporaryDirectory& dir, const std::string& path,
                              const std::vector<std::string>& words) {
  try {
    load_scene(path);
    ADD_FAILURE() << path << ": loaded without error";
  } catch (const Error& e) {
    const std::string message = without_directory(e.what(), dir);
    for (const std::string& word : words)
      EXPECT_NE(message.find(word), std::string::npos) << "'" << word << "' not in: " << message;
  } catch (const std::exception& e) {
    ADD_FAILURE() << path << ": threw a non-glaze exception: " << e.what();
  }
}

}  // namespace glaze::testing
