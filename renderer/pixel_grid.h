// pixel_grid.h: where the K x K sub-pixel samples of a pixel lie: at the centres of the
// cells of a K x K grid over the pixel's area (a box filter's deterministic samples).
// The sh integrator renders a pixel from them (--ss K, and M x M where it refines), and
// the inverse fits model a pixel by rays through the same points (footprint.h), so that
// a fit sees a pixel exactly as the sh integrator rendered it: both take the points
// from here.
#pragma once

#include "renderer/math.h"

namespace glaze {

// The film coordinate (pixels) of cell `cell` of a `k`-cell grid along one axis of the
// pixel at integer coordinate `pixel`.
inline float pixel_grid_coordinate(int pixel, int cell, int k) {
  return float(pixel) + (float(cell) + 0.5f) / float(k);
}

// The film point of cell (i, j), column i and row j, of the k x k grid over pixel (x, y).
inline Vec2 pixel_grid_point(int x, int y, int i, int j, int k) {
  return {pixel_grid_coordinate(x, i, k), pixel_grid_coordinate(y, j, k)};
}

}  // namespace glaze
