// fuzz_image: image files through read_image and read_image_from_memory, and small ones
// through the environment's construction and its SH projection.
//
// Byte 0 picks the extension (kImageExtensions: .exr, .hdr, .pfm, .png, .jpg, .tif), the
// rest is the file. glaze::Error is a clean refusal; any other exception, a sanitizer
// report, or an image whose size disagrees with its pixels is a finding.
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "tests/fuzz/fuzz_support.h"

#include <filesystem>

namespace {

std::filesystem::path scratch;

using namespace glaze;

void check_size(const Image& image, const std::string& how) {
  if (image.width <= 0 || image.height <= 0 || image.pixels.size() != size_t(image.width) * image.height * 3)
    fuzz::finding(how + " returned a " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                  " image with " + std::to_string(image.pixels.size()) + " values");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  scratch = glaze::fuzz::initialize_target("image");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string& extension = glaze::fuzz::kImageExtensions[data[0] % glaze::fuzz::kImageExtensions.size()];
  const std::filesystem::path path = scratch / ("image" + extension);
  glaze::fuzz::write_bytes(path, data + 1, size - 1);
  try {
    std::vector<float> alpha;
    const Image image = read_image(path.string(), &alpha);
    check_size(image, "read_image");
    if (alpha.size() != size_t(image.width) * image.height) fuzz::finding("read_image's alpha has the wrong size");
  } catch (const glaze::Error& e) {
    glaze::fuzz::refused(e);
  }
  try {
    Image image = read_image_from_memory(data + 1, size - 1, path.filename().string());
    check_size(image, "read_image_from_memory");
    if (size_t(image.width) * image.height <= 65536) {
      const Environment environment(std::move(image), EnvironmentOptions{}, "fuzz");
      for (const RGBd& c : environment.sh(2).values)
        if (!c.allFinite()) fuzz::finding("an SH coefficient of the environment is not finite");
    }
  } catch (const glaze::Error& e) {
    glaze::fuzz::refused(e);
  }
  std::filesystem::remove(path);
  return 0;
}
