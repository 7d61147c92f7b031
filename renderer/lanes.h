// lanes.h: structure-of-arrays batches of 16, the layout in which glaze's per-sample
// loops (the path tracer's single-sphere estimator, the sh integrator) run as SIMD: a
// loop over the lanes of inline, branch-free code is vectorised by the compiler.
#pragma once

#include "renderer/math.h"

namespace glaze {

inline constexpr int kLanes = 16;

// 16 directions (or points), one array per coordinate.
struct Directions {
  alignas(64) float x[kLanes];
  alignas(64) float y[kLanes];
  alignas(64) float z[kLanes];
  Vec3 operator[](int k) const { return {x[k], y[k], z[k]}; }
  void set(int k, const Vec3& v) {
    x[k] = v.x();
    y[k] = v.y();
    z[k] = v.z();
  }
};

}  // namespace glaze
