#include "renderer/image.h"

#include "renderer/error.h"

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <system_error>

namespace glaze {

Image read_image(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw Error(path + ": no such file (check the path; environment maps are lat-long EXR, HDR or PFM images)");
  if (std::filesystem::is_directory(path, ec)) throw Error(path + ": is a directory, not an image");

  auto input = OIIO::ImageInput::open(path);
  if (!input) {
    throw Error(path + ": cannot be read as an image (" + OIIO::geterror() +
                "); expected a float image such as EXR, HDR or PFM");
  }
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw Error(path + ": image has no pixels (" + std::to_string(spec.width) + "x" +
                std::to_string(spec.height) + ", " + std::to_string(spec.nchannels) + " channels)");

  const int channels = spec.nchannels;
  std::vector<float> raw(size_t(spec.width) * spec.height * channels);
  if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, raw.data())) {
    throw Error(path + ": pixel data could not be read, the file is probably truncated or corrupt (" +
                input->geterror() + ")");
  }
  input->close();

  Image image(spec.width, spec.height);
  const size_t count = size_t(spec.width) * spec.height;
  for (size_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c)
      image.pixels[i * 3 + c] = raw[i * channels + (channels >= 3 ? c : 0)];
  }
  return image;
}

void write_image(const std::string& path, const Image& image,
                 const std::map<std::string, std::string>& metadata) {
  if (image.width <= 0 || image.height <= 0) throw Error(path + ": refusing to write an empty image");
  const std::filesystem::path target(path);
  std::filesystem::path temporary = target;
  // Same directory (so rename is atomic), same extension (so the format is chosen right).
  // (Built with append: GCC 12 gives a false -Wrestrict on a chain of operator+.)
  std::string name = target.stem().string();
  name.insert(0, 1, '.');
  name.append(".tmp").append(std::to_string(std::random_device{}())).append(target.extension().string());
  temporary.replace_filename(name);

  auto output = OIIO::ImageOutput::create(temporary.string());
  if (!output) throw Error(path + ": no image writer for this file type (" + OIIO::geterror() + ")");
  OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::FLOAT);
  for (const auto& [key, value] : metadata) spec.attribute(key, value);
  const bool ok = output->open(temporary.string(), spec) &&
                  output->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()) && output->close();
  if (!ok) {
    const std::string reason = output->geterror();
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    throw Error(path + ": could not be written (" + reason + ")");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, target, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw Error(path + ": could not be written (rename failed: " + ec.message() + ")");
  }
}

}  // namespace glaze
