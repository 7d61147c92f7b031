// fuzz_support.h: what the fuzz targets (fuzz_gltf, fuzz_transforms, fuzz_image) and the
// seed corpus maker (fuzz_corpus) share: a scratch folder per process, the fixture files
// the inputs refer to by name, and the setup that makes glaze refuse big inputs itself.
//
// A target writes each input as a file into its scratch folder beside the fixtures, so
// that relative URIs and file paths in the input (buffer.bin, tex.png, view_000.exr, ...)
// resolve to small valid files. The corpus maker writes the same fixtures' names into its
// seeds, so that mutations start from inputs that load.
#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

namespace glaze::fuzz {

// The fixture glTF buffer (buffer.bin): a unit quad in the z = 0 plane facing +z, as
// float POSITION (VEC3), NORMAL (VEC3), TEXCOORD_0 (VEC2) and unsigned-short indices.
struct QuadBufferLayout {
  static constexpr size_t positions = 0, normals = 48, uvs = 96, indices = 128, size = 140;
  static constexpr int vertices = 4, index_count = 6;
};
std::vector<unsigned char> quad_buffer();

// Every target's setup, called from LLVMFuzzerInitialize: silences warnings (a fuzz run
// would print millions), sets GLAZE_MEMORY_LIMIT to 1G unless it is set, and creates
// the scratch folder (under /dev/shm when there is one), removed at normal exit.
// `name` names the folder: glaze_fuzz_NAME_PID.
std::filesystem::path initialize_target(const std::string& name);

// A property the target checks does not hold: prints "fuzz finding: WHAT" and aborts,
// which the driver (or libFuzzer) records as a crash with the input.
[[noreturn]] void finding(const std::string& what);

// A clean refusal (glaze::Error): printed when GLAZE_FUZZ_VERBOSE is set (to see why
// seeds are refused), ignored otherwise.
void refused(const std::exception& error);

// Writes `size` bytes as `path`.
void write_bytes(const std::filesystem::path& path, const uint8_t* data, size_t size);

// The fixtures each target's inputs refer to, written into `dir`:
// glTF: buffer.bin (quad_buffer) and tex.png (4x4).
void write_gltf_fixtures(const std::filesystem::path& dir);
// Capture sets: view_000..003.exr (4x4), mask_000.png, env.exr (16x8) and sphere.gltf.
void write_capture_fixtures(const std::filesystem::path& dir);

// The extensions fuzz_image picks by its input's first byte (modulo their count).
extern const std::vector<std::string> kImageExtensions;

}  // namespace glaze::fuzz
