#include "renderer/sh_integrator.h"

#include "renderer/error.h"
#include "renderer/shading.h"
#include "renderer/sh.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <limits>

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
      for (int x = 0; x < camera.width; ++x) {
        RGB sum = RGB::Zero();
        for (int sy = 0; sy < k; ++sy) {
          for (int sx = 0; sx < k; ++sx) {
            const Ray ray = camera.generate_ray(x + (sx + 0.5f) / k, y + (sy + 0.5f) / k);
            const std::optional<SurfaceHit> hit = tracer.intersect(ray, std::numeric_limits<float>::infinity(), textured);
            if (!hit) {
              if (!options.black_background) sum += environment.eval(ray.direction);
              continue;
            }
            const Vec3 v = -ray.direction;
            const float mu = hit->normal.dot(v);
            if (!(mu > 0.0f)) continue;  // shading normal facing away: nothing reflected
            const PolishedMaterial material =
                textured ? scene.material_at(hit->material, hit->uv) : untextured[size_t(hit->material)];
            // Clamped at zero: a negative truncated sum is SH ringing (a point-like light
            // seen from its far side), not light. The inverse fits keep it unclamped, where
            // the model must stay linear in the lighting coefficients.
            const RGB E = options.clamp_diffuse ? diffuse_sum(hit->normal).max(0.0f) : diffuse_sum(hit->normal);
            sum += polished_radiance(material, mu, environment.eval(reflect(v, hit->normal)), E);
          }
        }
        image.set(x, y, sum / float(k * k));
      }
    });
  });
  return image;
}

}  // namespace glaze
