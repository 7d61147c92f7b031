// texture_fit.h: the diffuse texture fit under known lighting (docs/design.md §5, paper section
// 5): Rd(u, v) per texel on a width x height grid over the texture coordinates (lat-long
// of the normal for a sphere, the mesh's UVs otherwise), and R0 shared, by the same
// nested fit as the homogeneous material with one Rd group per texel.
//
// Sample weights follow the paper: views close to the normal (n.v) and a large diffuse
// part relative to the mirror part (judged at the homogeneous fit), so that texels are
// estimated from the observations that say most about the base colour. Texels that no
// weighted sample constrains are unknown (alpha 0): nothing is invented for them.
#pragma once

#include "inverse/material_fit.h"

namespace glaze {

struct RecoveredTexture {
  float R0 = 0.0f;
  Image Rd;                  // clamped to [0, 1]; 0 where unknown
  std::vector<float> known;  // per texel: 1 known, 0 unknown (written as alpha)
  double coverage = 0.0;     // fraction of texels known
  MaterialFit fit;           // the solver's account
};

// `homogeneous` is the homogeneous fit of the same samples (its R0 starts the search
// and its Rd judges the weights).
RecoveredTexture fit_texture(std::span<const Sample> samples, std::span<const ShadingTerms> terms, int width,
                             int height, const MaterialFit& homogeneous, const MaterialFitOptions& options);

// RMSE over the known texels against a reference texture (times its Rd factor), each
// recovered texel compared with the mean of the reference over its area.
double texture_rmse(const RecoveredTexture& texture, const Image& reference, const RGB& factor);

}  // namespace glaze
