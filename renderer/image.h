// image.h: float images and their files, through OpenImageIO.
//
// Reading accepts anything OpenImageIO reads (EXR, HDR, PFM, PNG, ...) and converts to
// linear float RGB; failures become glaze::Error naming the file. Writing goes to a
// temporary file in the same directory that is renamed over the target only when
// complete (text_file.h: TemporaryOutput), so a good file is never replaced by a
// half-written one.
#pragma once

#include "renderer/math.h"

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace glaze {

// An RGB float image, row-major, row 0 at the top.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;  // width * height * 3
  // What the file stored, for data that the decoded values cannot tell about: integer
  // codes clip at the top of their range and quantise (8 bits: steps of a few percent).
  int source_bits = 0;        // bits per channel of an integer file (8, 16); 0: float data
  bool source_srgb = false;   // integer codes were sRGB-encoded (decoded to linear above)
  bool source_lossy = false;  // JPEG: codes carry compression artefacts beside edges and clipping

  // The integer code that decoded to `value` (one of this image's pixel values), for an
  // integer source (source_bits > 0).
  int code(float value) const;
  // The largest code of an integer source: 2^source_bits - 1.
  int max_code() const { return (1 << source_bits) - 1; }

  Image() = default;
  Image(int w, int h) : width(w), height(h), pixels(size_t(w) * size_t(h) * 3, 0.0f) {}

  RGB at(int x, int y) const {
    const float* p = &pixels[(size_t(y) * width + x) * 3];
    return {p[0], p[1], p[2]};
  }
  void set(int x, int y, const RGB& c) {
    float* p = &pixels[(size_t(y) * width + x) * 3];
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
  }
};

// Reads `path` as linear RGB (grey is replicated, alpha and extra channels dropped).
// Integer formats (PNG, JPEG, ...) are decoded from sRGB unless tagged linear.
// Throws glaze::Error for a missing, unreadable, truncated, empty or absurdly large image.
// `alpha`, if given, receives the alpha channel (one value per pixel; 1 where there is none).
Image read_image(const std::string& path, std::vector<float>* alpha = nullptr);

// The same for an image held in memory (a glTF data URI or .glb chunk); `name` picks
// the format by its extension and appears in messages.
Image read_image_from_memory(const unsigned char* bytes, size_t size, const std::string& name);

// The sRGB transfer function's inverse (IEC 61966-2-1), for 8- and 16-bit images.
float srgb_to_linear(float encoded);
// The sRGB transfer function (linear to encoded, both in [0, 1]).
float linear_to_srgb(float linear);

// The string metadata attribute `key` of the image file `path` (its header only), or ""
// when it has none. Throws glaze::Error when the file cannot be opened as an image.
std::string image_attribute(const std::string& path, const std::string& key);

// A photograph's pixels as the camera stored them, for the HDR merge (inverse/photos/),
// which recovers the response of 8-bit images itself and so needs their codes, not
// read_image's sRGB decoding.
struct PhotoCodes {
  int width = 0;
  int height = 0;
  int bits = 8;                 // 8 or 16: codes run 0 .. 2^bits - 1
  bool linear = false;          // codes proportional to exposure (16-bit TIFF/PNG, camera raw)
  std::vector<uint16_t> codes;  // width * height * 3, row-major (grey replicated)
};

// Reads `path` as PhotoCodes: 8-bit JPEG/PNG/TIFF (response unknown), 16-bit PNG/TIFF
// and camera raw (through OpenImageIO's LibRaw reader, demosaicked to linear sRGB
// primaries), both linear. Unlike read_image it accepts camera raw, and refuses float
// images (already HDR). Throws glaze::Error naming the file.
PhotoCodes read_photo_codes(const std::string& path);

// Writes `photo` as its camera would store it: 8-bit codes as PNG or JPEG (quality 95) by
// the extension, 16-bit codes as PNG or TIFF; atomically, with string metadata. Throws
// glaze::Error naming the file.
void write_photo_codes(const std::string& path, const PhotoCodes& photo,
                       const std::map<std::string, std::string>& metadata = {});

// The numeric metadata attribute `key` of the photograph `path` (its header only: EXIF
// "ExposureTime", "FNumber", ...), or nothing when it has none. A text value ("1/60")
// is parsed. Camera raw is accepted as by read_photo_codes. Throws glaze::Error when
// the file cannot be opened as an image.
std::optional<double> photo_number_attribute(const std::string& path, const std::string& key);

// The width and height of the image file `path`, from its header (the pixels are not
// read). Throws glaze::Error when the file cannot be opened as an image.
struct ImageSize {
  int width = 0, height = 0;
};
ImageSize image_size(const std::string& path);

// Writes `image` (format from the extension; .exr is written as float) with string
// metadata attributes, atomically. Throws glaze::Error on failure.
// `alpha`, if given (one value per pixel), is written as a fourth channel.
void write_image(const std::string& path, const Image& image, const std::map<std::string, std::string>& metadata = {},
                 std::span<const float> alpha = {});

// Writes an 8-bit sRGB picture (row-major, 3 bytes a pixel; display.h makes them),
// tagged sRGB, atomically. Throws glaze::Error on failure.
void write_picture(const std::string& path, int width, int height, std::span<const uint8_t> srgb,
                   const std::map<std::string, std::string>& metadata = {});

}  // namespace glaze
