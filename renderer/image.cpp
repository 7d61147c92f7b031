#include "renderer/image.h"

#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/input_file.h"
#include "renderer/memory_budget.h"
#include "renderer/text_file.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <filesystem>
#include <set>
#include <system_error>

namespace glaze {

float srgb_to_linear(float encoded) {
  return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

int Image::code(float value) const {
  const float encoded = source_srgb ? linear_to_srgb(value) : value;
  return int(std::lround(std::clamp(encoded, 0.0f, 1.0f) * float(max_code())));
}

float linear_to_srgb(float linear) {
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

namespace {

// Refuses an image with no pixels or more than glaze accepts, and checks that decoding
// it (`bytes_per_pixel`) fits the memory budget.
void require_sane_size(const OIIO::ImageSpec& spec, const std::string& name, uint64_t bytes_per_pixel) {
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw Error(name + ": image has no pixels (" + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                ", " + std::to_string(spec.nchannels) + " channels)");
  constexpr int64_t kMaxPixels = int64_t(1) << 28;  // 16k x 16k: far beyond any map glaze needs
  // Also a bound on each side: OpenImageIO's readers allocate per scanline (found by the
  // fuzzer: an HDR of 2147483 x 4 asked for gigabytes).
  constexpr int kMaxSide = 65536;
  if (int64_t(spec.width) * spec.height > kMaxPixels || spec.width > kMaxSide || spec.height > kMaxSide ||
      spec.nchannels > 64)
    throw Error(name + ": image is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " with " +
                std::to_string(spec.nchannels) +
                " channels, larger than glaze accepts (at most 2^28 pixels, 65536 a side); "
                "is the file corrupt?");
  const uint64_t pixels = uint64_t(spec.width) * uint64_t(spec.height);
  require_memory(saturating_mul(pixels, bytes_per_pixel), "decoding " + name);
}

// Reads an opened image as linear RGB; `name` is used in messages.
Image decode(OIIO::ImageInput& input, const std::string& name, std::vector<float>* alpha) {
  const OIIO::ImageSpec& spec = input.spec();
  const int channels = spec.nchannels;
  // Bytes per pixel: the decoded channels (4 each), the RGB image (12) and alpha (4);
  // `glaze sh` of a 4096x2048 RGB EXR against 512x256 peaks at 24 (/usr/bin/time -v).
  require_sane_size(spec, name, 4 * uint64_t(std::max(channels, 0)) + 16);
  std::vector<float> raw(size_t(spec.width) * spec.height * channels);
  if (!input.read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, raw.data())) {
    throw Error(name + ": pixel data could not be read, the file is probably truncated or corrupt (" +
                input.geterror() + ")");
  }

  // Integer images (PNG, JPEG, 8-bit TIFF, ...) store sRGB-encoded values unless the
  // file says it is linear; float images (EXR, HDR, PFM) are linear already.
  const std::string color_space = spec.get_string_attribute("oiio:ColorSpace");
  const bool integer_format =
      spec.format.basetype == OIIO::TypeDesc::UINT8 || spec.format.basetype == OIIO::TypeDesc::UINT16 ||
      spec.format.basetype == OIIO::TypeDesc::INT8 || spec.format.basetype == OIIO::TypeDesc::INT16;
  const bool srgb_encoded = integer_format && !OIIO::Strutil::iequals(color_space, "linear");

  Image image(spec.width, spec.height);
  if (integer_format) {
    image.source_bits = int(spec.format.size()) * 8;
    image.source_srgb = srgb_encoded;
    image.source_lossy = std::string(input.format_name()) == "jpeg";
  }
  const size_t count = size_t(spec.width) * spec.height;
  for (size_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c) {
      const float value = raw[i * channels + (channels >= 3 ? c : 0)];
      image.pixels[i * 3 + c] = srgb_encoded ? srgb_to_linear(value) : value;
    }
  }
  if (alpha) {  // alpha is never sRGB-encoded
    alpha->assign(count, 1.0f);
    if (spec.alpha_channel >= 0)
      for (size_t i = 0; i < count; ++i) (*alpha)[i] = raw[i * channels + spec.alpha_channel];
  }
  return image;
}

// Which of OpenImageIO's readers glaze lets see a file: those of the formats it documents,
// plus camera raw (LibRaw) for photographs only.
enum class Readers { kGlaze, kPhotographs };

// OIIO picks a reader by the file's extension, else by trying every plugin it has; glaze
// decodes only the formats it documents, so that no other plugin sees a hostile file.
void require_known_format(const OIIO::ImageInput& input, const std::string& name, Readers readers = Readers::kGlaze) {
  static const std::set<std::string> kFormats = {"openexr", "hdr", "pnm", "png", "jpeg", "tiff"};
  const std::string format = input.format_name();
  if (kFormats.count(format) || (readers == Readers::kPhotographs && format == "raw")) return;
  throw Error(name + ": is a " + format + " image; glaze reads EXR, HDR, PFM, PNG, JPEG and TIFF images" +
              (readers == Readers::kPhotographs ? " and camera raw" : "") + ": convert it to one of those");
}

// Opens the regular file `path` with the readers allowed; `expected` ends the message
// when it is no image. Camera raw is demosaicked to linear sRGB primaries, white
// balanced as the camera recorded, without OIIO's automatic brightening.
std::unique_ptr<OIIO::ImageInput> open_input(const std::string& path, Readers readers, const std::string& expected) {
  // A FIFO or a device would block OIIO's open or never end.
  require_regular_file(path, "image");
  OIIO::ImageSpec config;
  config.attribute("raw:ColorSpace", "sRGB-linear");
  config.attribute("raw:auto_bright", 0);
  config.attribute("raw:use_camera_wb", 1);
  auto input = OIIO::ImageInput::open(path, readers == Readers::kPhotographs ? &config : nullptr);
  if (!input) throw Error(path + ": cannot be read as an image (" + OIIO::geterror() + ")" + expected);
  require_known_format(*input, path, readers);
  return input;
}

}  // namespace

Image read_image(const std::string& path, std::vector<float>* alpha) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw Error(path + ": no such file (check the path; environment maps are lat-long EXR, HDR or PFM images)");
  auto input = open_input(path, Readers::kGlaze, "; expected a float image such as EXR, HDR or PFM");
  return decode(*input, path, alpha);
}

PhotoCodes read_photo_codes(const std::string& path) {
  auto input = open_input(path, Readers::kPhotographs, "; expected a photograph: JPEG, PNG, TIFF or camera raw");
  const OIIO::ImageSpec& spec = input->spec();
  const OIIO::TypeDesc::BASETYPE type = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
  const bool raw = std::string(input->format_name()) == "raw";
  if (type != OIIO::TypeDesc::UINT8 && type != OIIO::TypeDesc::UINT16)
    throw Error(path + ": is a " + std::string(spec.format.c_str()) +
                " image; a bracket holds 8-bit JPEG/PNG/TIFF, 16-bit PNG/TIFF or camera raw photographs (an "
                "image that is HDR already needs no merge)");
  const int channels = spec.nchannels;
  // The decoded channels (2 bytes each) and the RGB codes (6).
  require_sane_size(spec, path, 2 * uint64_t(std::max(channels, 0)) + 6);
  PhotoCodes photo;
  photo.bits = type == OIIO::TypeDesc::UINT8 ? 8 : 16;
  photo.linear = photo.bits == 16 || raw;
  photo.width = spec.width, photo.height = spec.height;
  const size_t count = size_t(spec.width) * spec.height;
  photo.codes.resize(count * 3);
  // Read in the stored type (no conversion by OIIO), then the RGB channels copied out.
  auto read_as = [&]<typename Code>(OIIO::TypeDesc type_desc) {
    std::vector<Code> stored(count * channels);
    if (!input->read_image(0, 0, 0, channels, type_desc, stored.data()))
      throw Error(path + ": pixel data could not be read, the file is probably truncated or corrupt (" +
                  input->geterror() + ")");
    for (size_t i = 0; i < count; ++i)
      for (int c = 0; c < 3; ++c) photo.codes[i * 3 + c] = stored[i * channels + (channels >= 3 ? c : 0)];
  };
  if (photo.bits == 8)
    read_as.template operator()<uint8_t>(OIIO::TypeDesc::UINT8);
  else
    read_as.template operator()<uint16_t>(OIIO::TypeDesc::UINT16);
  return photo;
}

std::optional<double> photo_number_attribute(const std::string& path, const std::string& key) {
  auto input = open_input(path, Readers::kPhotographs, "; expected a photograph: JPEG, PNG, TIFF or camera raw");
  const OIIO::ParamValue* value = input->spec().find_attribute(key);
  if (!value) return std::nullopt;
  if (value->type() == OIIO::TypeString) {  // "1/60", "0.5"
    const std::string text = value->get_string();
    char* end = nullptr;
    double number = std::strtod(text.c_str(), &end);
    if (end != text.c_str() && *end == '/') {
      const char* denominator = end + 1;
      number /= std::strtod(denominator, &end);
    }
    if (end == text.c_str() || *end != '\0' || !std::isfinite(number)) return std::nullopt;
    return number;
  }
  if (value->type() == OIIO::TypeRational) {
    const int* parts = static_cast<const int*>(value->data());
    return parts[1] != 0 ? std::optional<double>(double(parts[0]) / parts[1]) : std::nullopt;
  }
  const double number = value->get_float(NAN);
  return std::isfinite(number) ? std::optional<double>(number) : std::nullopt;
}

Image read_image_from_memory(const unsigned char* bytes, size_t size, const std::string& name) {
  OIIO::Filesystem::IOMemReader reader(const_cast<unsigned char*>(bytes), size);
  auto input = OIIO::ImageInput::open(name, nullptr, &reader);
  if (!input) throw Error(name + ": cannot be decoded as an image (" + OIIO::geterror() + ")");
  require_known_format(*input, name);
  return decode(*input, name, nullptr);
}

namespace {

// Writes `pixels` (interleaved, `spec`'s size and channels, of type `format`) to a
// temporary file beside `path` (text_file.h) and renames it over `path` only when it is
// complete.
void write_atomically(const std::string& path, OIIO::ImageSpec spec, OIIO::TypeDesc format, const void* pixels,
                      const std::map<std::string, std::string>& metadata) {
  const std::filesystem::path target(path);
  TemporaryOutput temporary(target);
  // The writer is chosen by the target's name (the temporary file keeps its extension).
  auto output = OIIO::ImageOutput::create(target.string());
  if (!output)
    throw Error(path + ": no image writer for the extension '" + target.extension().string() +
                "' (radiance: .exr, .hdr or .pfm; a picture: .png or .jpg)");
  for (const auto& [key, value] : metadata) spec.attribute(key, value);
  const bool ok =
      output->open(temporary.path().string(), spec) && output->write_image(format, pixels) && output->close();
  if (!ok) temporary.fail(output->geterror());
  temporary.commit();
}

}  // namespace

void write_image(const std::string& path, const Image& image, const std::map<std::string, std::string>& metadata,
                 std::span<const float> alpha) {
  if (image.width <= 0 || image.height <= 0) throw Error(path + ": refusing to write an empty image");
  const size_t pixels = size_t(image.width) * image.height;
  if (!alpha.empty() && alpha.size() != pixels) throw Error(path + ": the alpha channel does not match the image size");
  const int channels = alpha.empty() ? 3 : 4;
  std::vector<float> interleaved;
  if (!alpha.empty()) {
    interleaved.resize(pixels * 4);
    for (size_t p = 0; p < pixels; ++p) {
      for (int c = 0; c < 3; ++c) interleaved[4 * p + c] = image.pixels[3 * p + c];
      interleaved[4 * p + 3] = alpha[p];
    }
  }
  OIIO::ImageSpec spec(image.width, image.height, channels, OIIO::TypeDesc::FLOAT);
  if (channels == 4) spec.alpha_channel = 3;
  write_atomically(path, spec, OIIO::TypeDesc::FLOAT, alpha.empty() ? image.pixels.data() : interleaved.data(),
                   metadata);
}

void write_picture(const std::string& path, int width, int height, std::span<const uint8_t> srgb,
                   const std::map<std::string, std::string>& metadata) {
  if (width <= 0 || height <= 0) throw Error(path + ": refusing to write an empty image");
  if (srgb.size() != size_t(width) * height * 3) throw Error(path + ": the pixels do not match the image size");
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "sRGB");
  write_atomically(path, spec, OIIO::TypeDesc::UINT8, srgb.data(), metadata);
}

void write_photo_codes(const std::string& path, const PhotoCodes& photo,
                       const std::map<std::string, std::string>& metadata) {
  if (photo.width <= 0 || photo.height <= 0) throw Error(path + ": refusing to write an empty image");
  if (photo.codes.size() != size_t(photo.width) * photo.height * 3)
    throw Error(path + ": the codes do not match the image size");
  if (photo.bits != 8 && photo.bits != 16) throw Error(path + ": a photo has 8 or 16 bits a code");
  const OIIO::TypeDesc type = photo.bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
  OIIO::ImageSpec spec(photo.width, photo.height, 3, type);
  spec.attribute("Compression", "jpeg:95");
  if (photo.bits == 16) {
    write_atomically(path, spec, type, photo.codes.data(), metadata);
    return;
  }
  const std::vector<uint8_t> bytes(photo.codes.begin(), photo.codes.end());
  write_atomically(path, spec, type, bytes.data(), metadata);
}

std::string image_attribute(const std::string& path, const std::string& key) {
  return open_input(path, Readers::kGlaze, "")->spec().get_string_attribute(key);
}

ImageSize image_size(const std::string& path) {
  const OIIO::ImageSpec spec = open_input(path, Readers::kGlaze, "")->spec();
  return {spec.width, spec.height};
}

}  // namespace glaze
