#include "renderer/sh_integrator.h"

#include "renderer/error.h"
#include "renderer/shading.h"
#include "renderer/sh.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <tuple>
#include <vector>

namespace glaze {

Image render_sh(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                const PinholeCamera& camera, const ShIntegratorOptions& options) {
  if (options.supersampling < 1 || options.supersampling > 64) throw Error("supersampling must be in [1, 64]");
  if (!scene.is_single_convex_object()) {
    warn_once(scene.path + ": the sh integrator assumes a single convex object under distant light; "
         "it ignores the occlusion and interreflection of this scene (use --integrator path)");
  }
  const ShDiffuseSum diffuse_sum(environment.sh(options.lmax));  // projected once per environment and lmax
  if (options.refined_supersampling != 0 && (options.refined_supersampling < 1 || options.refined_supersampling > 64))
    throw Error("refined supersampling must be 0 (off) or in [1, 64]");
  const int k = options.supersampling, fine = options.refined_supersampling;
  // Texture coordinates cost a sphere two arc tangents: only when a material needs them.
  const bool textured = std::any_of(scene.materials.begin(), scene.materials.end(), [](const SceneMaterial& m) { return m.texture >= 0; });
  // Without textures every material is a constant: made (and validated) once, not per ray.
  std::vector<PolishedMaterial> untextured;
  if (!textured)
    for (size_t m = 0; m < scene.materials.size(); ++m) untextured.push_back(scene.material_at(int(m), Vec2::Zero()));
  Image image(camera.width, camera.height);
  // The luminance of every coarse sub-pixel sample, on the image's k-times finer lattice,
  // when refinement will look for edges in it.
  const int lattice_width = camera.width * k;
  const bool refining = fine > k;
  std::vector<float> lattice(refining ? size_t(lattice_width) * camera.height * k : 0);

  // Shades `count` sub-pixel rays, ray i through film point place(i) = (x, y) of the
  // image, handing each radiance to record(i, radiance): 16 at a time in SIMD lanes
  // (lanes.h), the hits, the cosines and mirror directions and where those fall in the
  // map, then per lane the SH sum and the texels.
  auto shade = [&](int count, auto&& place, auto&& record) {
    std::array<Ray, kLanes> rays;
    SurfaceHits hits;
    Directions mirror;
    alignas(64) float mu[kLanes];
    EnvironmentLookups mirror_at;
    for (int first = 0; first < count; first += kLanes) {
      const int n = std::min(kLanes, count - first);
      for (int lane = 0; lane < n; ++lane) {
        const auto [film_x, film_y] = place(first + lane);
        rays[lane] = camera.generate_ray(film_x, film_y);
      }
      tracer.intersect(rays.data(), n, hits, textured);
      for (int lane = 0; lane < kLanes; ++lane) {
        const Vec3 v = -rays[std::min(lane, n - 1)].direction;
        mu[lane] = hits.normal.x[lane] * v.x() + hits.normal.y[lane] * v.y() + hits.normal.z[lane] * v.z();
        mirror.set(lane, reflect(v, hits.normal[lane]));
      }
      mirror_at.locate(environment, mirror);
      for (int lane = 0; lane < n; ++lane) {
        RGB radiance = RGB::Zero();
        if (!hits.hit[lane]) {
          if (!options.black_background) radiance = environment.eval(rays[lane].direction);
        } else if (mu[lane] > 0.0f) {  // else the shading normal faces away: nothing reflected
          const PolishedMaterial material = textured ? scene.material_at(hits.material[lane], hits.uv[lane])
                                                     : untextured[size_t(hits.material[lane])];
          // Clamped at zero: a negative truncated sum is SH ringing (a point-like light
          // seen from its far side), not light. The inverse fits keep it unclamped, where
          // the model must stay linear in the lighting coefficients.
          const RGB E = options.clamp_diffuse ? diffuse_sum(hits.normal[lane]).max(0.0f) : diffuse_sum(hits.normal[lane]);
          radiance = polished_radiance(material, mu[lane], environment.eval(mirror_at[lane]), E);
        }
        record(first + lane, radiance);
      }
    }
  };

  // threads 0: the caller's arena (all cores, or what an enclosing arena allows, such as
  // invert-fit --threads for its re-renders).
  auto render_rows = [&] {
    // The K x K grid, a sub-row at a time (k rays per pixel along it, so that the lanes
    // see neighbouring rays).
    tbb::parallel_for(0, camera.height, [&](int y) {
      std::vector<RGB> row(camera.width, RGB::Zero());
      for (int sy = 0; sy < k; ++sy) {
        float* lattice_row = refining ? &lattice[(size_t(y) * k + sy) * lattice_width] : nullptr;
        shade(
            lattice_width,
            [&](int i) { return std::pair(float(i / k) + (float(i % k) + 0.5f) / k, float(y) + (float(sy) + 0.5f) / k); },
            [&](int i, const RGB& radiance) {
              row[size_t(i / k)] += radiance;
              if (lattice_row) lattice_row[i] = luminance(radiance);
            });
      }
      for (int x = 0; x < camera.width; ++x) image.set(x, y, row[x] / float(k * k));
    });
    if (!refining) return;
    // Finer grids where the K x K one misses detail. The K x K mean errs little where
    // light varies smoothly across the pixel (exact for linear variation, and a fraction
    // 1/24 of the second difference for curved), and a lot at an edge (a silhouette, a
    // reflected light's border): there, on an M x M grid, the edge cuts about M cells,
    // each off by a uniform fraction of its step D / M^2, so the pixel's mean is off by
    // about D / (sqrt(12) M^1.5). Edges show on the lattice of samples as third
    // differences (zero for any quadratic): a step D as one of 2D. A pixel where one is
    // `bend` times 2 refine_contrast of its luminance L is rendered again on the grid that
    // brings the error under refine_contrast L / 2, M = (bend / sqrt(3))^(2/3), at least
    // K + 1 and at most the finest allowed: a high-contrast edge (a window in HDR) gets
    // many samples and a faint one a few.
    const int lattice_height = camera.height * k;
    auto at = [&](int i, int j) {
      return lattice[size_t(std::clamp(j, 0, lattice_height - 1)) * lattice_width + std::clamp(i, 0, lattice_width - 1)];
    };
    // The largest third difference along x and y of the 4-sample windows holding (i, j).
    auto edge_step = [&](int i, int j) {
      float step = 0.0f;
      for (int first = -2; first <= 0; ++first) {
        const int a = first, b = first + 1, c = first + 2, d = first + 3;
        step = std::max({step, std::abs(at(i + d, j) - 3.0f * at(i + c, j) + 3.0f * at(i + b, j) - at(i + a, j)),
                         std::abs(at(i, j + d) - 3.0f * at(i, j + c) + 3.0f * at(i, j + b) - at(i, j + a))});
      }
      return 0.5f * step;
    };
    tbb::parallel_for(0, camera.height, [&](int y) {
      struct Refined {
        int x, grid, first_ray;
      };
      std::vector<Refined> refine;
      int rays = 0;
      for (int x = 0; x < camera.width; ++x) {
        float step = 0.0f;
        for (int j = y * k; j < (y + 1) * k; ++j)
          for (int i = x * k; i < (x + 1) * k; ++i) step = std::max(step, edge_step(i, j));
        const float bend = step / (options.refine_contrast * std::max(luminance(image.at(x, y)), 1e-20f));
        if (!(bend > 1.0f)) continue;
        const int grid = int(std::clamp(std::ceil(std::pow(bend / std::sqrt(3.0f), 2.0f / 3.0f)), float(k + 1), float(fine)));
        refine.push_back({x, grid, rays});
        rays += grid * grid;
      }
      std::vector<RGB> sums(refine.size(), RGB::Zero());
      auto owner = [&](int ray) {  // the refined pixel that ray `ray` of the row belongs to
        return size_t(std::upper_bound(refine.begin(), refine.end(), ray,
                                       [](int r, const Refined& p) { return r < p.first_ray; }) -
                      refine.begin() - 1);
      };
      shade(
          rays,
          [&](int ray) {
            const Refined& p = refine[owner(ray)];
            const int sub = ray - p.first_ray;
            return std::pair(float(p.x) + (float(sub % p.grid) + 0.5f) / p.grid, float(y) + (float(sub / p.grid) + 0.5f) / p.grid);
          },
          [&](int ray, const RGB& radiance) { sums[owner(ray)] += radiance; });
      for (size_t p = 0; p < refine.size(); ++p) image.set(refine[p].x, y, sums[p] / float(refine[p].grid * refine[p].grid));
    });
  };
  if (options.threads > 0) tbb::task_arena(options.threads).execute(render_rows);
  else render_rows();
  return image;
}

}  // namespace glaze
