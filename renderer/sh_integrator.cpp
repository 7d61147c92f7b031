#include "renderer/sh_integrator.h"

#include "renderer/error.h"
#include "renderer/shading.h"
#include "renderer/sh.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>

namespace glaze {

Image render_sh(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                const PinholeCamera& camera, const ShIntegratorOptions& options) {
  if (options.supersampling < 1 || options.supersampling > 64) throw Error("supersampling must be in [1, 64]");
  if (!scene.is_single_convex_object()) {
    warn_once(scene.path + ": the sh integrator assumes a single convex object under distant light; "
         "it ignores the occlusion and interreflection of this scene (use --integrator path)");
  }
  const ShDiffuseSum diffuse_sum(environment.sh(options.lmax));  // projected once per environment and lmax
  const int k = options.supersampling;
  // Texture coordinates cost a sphere two arc tangents: only when a material needs them.
  const bool textured = std::any_of(scene.materials.begin(), scene.materials.end(), [](const SceneMaterial& m) { return m.texture >= 0; });
  // Without textures every material is a constant: made (and validated) once, not per ray.
  std::vector<PolishedMaterial> untextured;
  if (!textured)
    for (size_t m = 0; m < scene.materials.size(); ++m) untextured.push_back(scene.material_at(int(m), Vec2::Zero()));
  Image image(camera.width, camera.height);
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(0, camera.height, [&](int y) {
      // A row's sub-pixel rays, k per pixel along each of its k sub-rows, 16 at a time
      // in SIMD lanes (lanes.h): the hits, the cosines and mirror directions, and where
      // those fall in the map; then per lane the SH sum and the texels.
      std::vector<RGB> row(camera.width, RGB::Zero());
      std::array<Ray, kLanes> rays;
      std::array<int, kLanes> pixel;
      SurfaceHits hits;
      Directions mirror;
      alignas(64) float mu[kLanes];
      EnvironmentLookups mirror_at;
      const int rays_per_subrow = camera.width * k;
      for (int sy = 0; sy < k; ++sy) {
        for (int first = 0; first < rays_per_subrow; first += kLanes) {
          const int n = std::min(kLanes, rays_per_subrow - first);
          for (int lane = 0; lane < n; ++lane) {
            const int index = first + lane, sx = index % k;
            pixel[lane] = index / k;
            rays[lane] = camera.generate_ray(pixel[lane] + (sx + 0.5f) / k, y + (sy + 0.5f) / k);
          }
          tracer.intersect(rays.data(), n, hits, textured);
          for (int lane = 0; lane < kLanes; ++lane) {
            const Vec3 v = -rays[std::min(lane, n - 1)].direction;
            mu[lane] = hits.normal.x[lane] * v.x() + hits.normal.y[lane] * v.y() + hits.normal.z[lane] * v.z();
            mirror.set(lane, reflect(v, hits.normal[lane]));
          }
          mirror_at.locate(environment, mirror);
          for (int lane = 0; lane < n; ++lane) {
            RGB& sum = row[pixel[lane]];
            if (!hits.hit[lane]) {
              if (!options.black_background) sum += environment.eval(rays[lane].direction);
              continue;
            }
            if (!(mu[lane] > 0.0f)) continue;  // shading normal facing away: nothing reflected
            const PolishedMaterial material = textured ? scene.material_at(hits.material[lane], hits.uv[lane])
                                                       : untextured[size_t(hits.material[lane])];
            // Clamped at zero: a negative truncated sum is SH ringing (a point-like light
            // seen from its far side), not light. The inverse fits keep it unclamped, where
            // the model must stay linear in the lighting coefficients.
            const RGB E = options.clamp_diffuse ? diffuse_sum(hits.normal[lane]).max(0.0f) : diffuse_sum(hits.normal[lane]);
            sum += polished_radiance(material, mu[lane], environment.eval(mirror_at[lane]), E);
          }
        }
      }
      for (int x = 0; x < camera.width; ++x) image.set(x, y, row[x] / float(k * k));
    });
  });
  return image;
}

}  // namespace glaze
