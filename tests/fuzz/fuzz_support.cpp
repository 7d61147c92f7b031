#include "tests/fuzz/fuzz_support.h"

#include "renderer/error.h"
#include "renderer/image.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

// AddressSanitizer's defaults for every fuzz binary (ASAN_OPTIONS still overrides each key):
// an allocation above 2 GiB is a finding (glaze must refuse it first, under its 1 GiB
// limit), reported as an error instead of returning null. Unused without the sanitizer.
extern "C" const char* __asan_default_options() { return "max_allocation_size_mb=2048:allocator_may_return_null=0"; }

namespace glaze::fuzz {

const std::vector<std::string> kImageExtensions = {".exr", ".hdr", ".pfm", ".png", ".jpg", ".tif"};

std::vector<unsigned char> quad_buffer() {
  using L = QuadBufferLayout;
  const float positions[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  const float normals[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  const float uvs[] = {0, 1, 1, 1, 1, 0, 0, 0};
  const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
  std::vector<unsigned char> bytes(L::size, 0);
  std::memcpy(bytes.data() + L::positions, positions, sizeof positions);
  std::memcpy(bytes.data() + L::normals, normals, sizeof normals);
  std::memcpy(bytes.data() + L::uvs, uvs, sizeof uvs);
  std::memcpy(bytes.data() + L::indices, indices, sizeof indices);
  return bytes;
}

std::filesystem::path initialize_target(const std::string& name) {
  set_warning_sink([](const std::string&) {});
  setenv("GLAZE_MEMORY_LIMIT", "1G", 0);
  const std::filesystem::path shm = "/dev/shm";
  const std::filesystem::path base = std::filesystem::is_directory(shm) ? shm : std::filesystem::temp_directory_path();
  static std::filesystem::path dir;  // static: the atexit handler below removes it
  dir = base / ("glaze_fuzz_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::atexit([] {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  });
  return dir;
}

void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz finding: %s\n", what.c_str());
  std::abort();
}

void refused(const std::exception& error) {
  static const bool verbose = std::getenv("GLAZE_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "refused: %s\n", error.what());
}

void write_bytes(const std::filesystem::path& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

namespace {

// A width x height image of smooth positive colours.
Image gradient(int width, int height) {
  Image image(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      image.set(x, y, RGB(0.1f + 0.8f * float(x) / float(width), 0.1f + 0.8f * float(y) / float(height), 0.5f));
  return image;
}

std::vector<uint8_t> checker_srgb(int width, int height) {
  std::vector<uint8_t> srgb;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) srgb.push_back(uint8_t((x + y) % 2 ? 230 : 40 + 60 * c));
  return srgb;
}

}  // namespace

void write_gltf_fixtures(const std::filesystem::path& dir) {
  const std::vector<unsigned char> buffer = quad_buffer();
  write_bytes(dir / "buffer.bin", buffer.data(), buffer.size());
  write_picture((dir / "tex.png").string(), 4, 4, checker_srgb(4, 4));
}

void write_capture_fixtures(const std::filesystem::path& dir) {
  for (int k = 0; k < 4; ++k) write_image((dir / ("view_00" + std::to_string(k) + ".exr")).string(), gradient(4, 4));
  const std::vector<uint8_t> mask(4 * 4 * 3, 255);
  write_picture((dir / "mask_000.png").string(), 4, 4, mask);
  write_image((dir / "env.exr").string(), gradient(16, 8));
  const std::string sphere =
      R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
          "nodes": [{"extras": {"glaze": {"sphere": {"radius": 1.0, "material": 0}}}}],
          "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0}}]})";
  write_bytes(dir / "sphere.gltf", reinterpret_cast<const uint8_t*>(sphere.data()), sphere.size());
}

}  // namespace glaze::fuzz
