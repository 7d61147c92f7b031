// image_error.h: how far an image is from a reference, over the pixels that show an
// object's surface and nothing else. One definition, used by `glaze convergence`, the
// acceptance tests and the inverse module's residuals.
//
// Relative RMSE = sqrt(sum over pixels and channels of (image - reference)^2 / sum of
// reference^2), the RMSE divided by the reference's RMS over the same pixels and
// channels: a uniform 1% error in every channel reads 1% whatever the colour (a red
// object's dark green and blue channels neither dilute nor inflate it), and dark pixels
// do not blow it up. Max error is the largest absolute difference divided by the same RMS.
#pragma once

#include "renderer/camera.h"
#include "renderer/image.h"
#include "renderer/ray_tracer.h"

#include <cstdint>
#include <span>
#include <vector>

namespace glaze {

// Pixels whose whole footprint lies on the objects: the rays through the four corners
// and the centre all hit a surface that faces the camera (n.v > 0). Silhouette pixels,
// which mix object and background, are excluded. 1 = interior, row-major.
std::vector<uint8_t> interior_mask(const RayTracer& tracer, const PinholeCamera& camera);

struct ImageError {
  double relative_rmse = 0.0;
  double max_error = 0.0;  // relative to the reference's RMS, like relative_rmse
  size_t pixels = 0;       // pixels compared
};

// Throws glaze::Error if the sizes differ, the mask is empty, the reference is black over
// it or the image is not finite there.
ImageError image_error(const Image& image, const Image& reference, std::span<const uint8_t> mask);

}  // namespace glaze
