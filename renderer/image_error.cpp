#include "renderer/image_error.h"

#include "renderer/error.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace glaze {

std::vector<uint8_t> interior_mask(const RayTracer& tracer, const PinholeCamera& camera) {
  // Whether the ray through film point (x, y) sees a front-facing surface, for the
  // (width + 1) x (height + 1) pixel corners and each pixel centre.
  auto sees_surface = [&](float x, float y) {
    const Ray ray = camera.generate_ray(x, y);
    const std::optional<SurfaceHit> hit = tracer.intersect(ray);
    return hit && hit->normal.dot(-ray.direction) > 0.0f;
  };
  const int width = camera.width, height = camera.height;
  std::vector<uint8_t> corner(size_t(width + 1) * (height + 1)), mask(size_t(width) * height);
  tbb::parallel_for(0, height + 1, [&](int y) {
    for (int x = 0; x <= width; ++x) corner[size_t(y) * (width + 1) + x] = sees_surface(float(x), float(y));
  });
  tbb::parallel_for(0, height, [&](int y) {
    for (int x = 0; x < width; ++x) {
      auto at = [&](int dx, int dy) { return corner[size_t(y + dy) * (width + 1) + x + dx]; };
      mask[size_t(y) * width + x] = at(0, 0) && at(1, 0) && at(0, 1) && at(1, 1) && sees_surface(x + 0.5f, y + 0.5f);
    }
  });
  return mask;
}

ImageError image_error(const Image& image, const Image& reference, std::span<const uint8_t> mask) {
  if (image.width != reference.width || image.height != reference.height)
    throw Error("image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                " but the reference is " + std::to_string(reference.width) + "x" + std::to_string(reference.height));
  if (mask.size() != size_t(image.width) * image.height) throw Error("mask does not match the image size");
  double squared = 0.0, reference_sum = 0.0, largest = 0.0;  // reference_sum: of squares
  size_t pixels = 0;
  for (size_t p = 0; p < mask.size(); ++p) {
    if (!mask[p]) continue;
    ++pixels;
    for (int c = 0; c < 3; ++c) {
      const double difference = double(image.pixels[3 * p + c]) - double(reference.pixels[3 * p + c]);
      squared += difference * difference;
      largest = std::max(largest, std::abs(difference));
      reference_sum += double(reference.pixels[3 * p + c]) * reference.pixels[3 * p + c];
    }
  }
  if (pixels == 0) throw Error("no pixel to compare: the object covers no pixel completely");
  if (!(reference_sum > 0.0) || !std::isfinite(reference_sum))
    throw Error("the reference is black or not finite over the object's pixels; a relative error is undefined");
  if (!std::isfinite(squared)) throw Error("the image has non-finite pixels over the object");
  const double reference_rms = std::sqrt(reference_sum / (3.0 * pixels));
  return {std::sqrt(squared / reference_sum), largest / reference_rms, pixels};
}

}  // namespace glaze
