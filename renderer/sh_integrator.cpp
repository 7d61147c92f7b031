#include "renderer/sh_integrator.h"

#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/memory_budget.h"
#include "renderer/pixel_grid.h"
#include "renderer/shading.h"
#include "renderer/sh.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace glaze {
namespace {

// Peak bytes per pixel of an sh render besides the refinement lattice: the image (12)
// and the image as it is written. Measured with /usr/bin/time -v (maximum resident
// size) for `glaze render --integrator sh` at 2048x2048 against 256x256: 13 bytes.
constexpr uint64_t kShBytesPerPixel = 16;

void check_options(const ShIntegratorOptions& options) {
  if (options.supersampling < 1 || options.supersampling > 64) throw Error("supersampling must be in [1, 64]");
  if (options.refined_supersampling != 0 && (options.refined_supersampling < 1 || options.refined_supersampling > 64))
    throw Error("refined supersampling must be 0 (off) or in [1, 64]");
}

// Shades sub-pixel samples: what that needs beyond the ray (the lighting's SH, the
// materials) is made once per frame, not per ray.
class SampleShader {
 public:
  SampleShader(const Scene& scene, const RayTracer& tracer, const Environment& environment, const PinholeCamera& camera,
               const ShIntegratorOptions& options)
      : scene_(scene),
        tracer_(tracer),
        environment_(environment),
        camera_(camera),
        options_(options),
        diffuse_sum_(environment.sh(options.lmax)),  // projected once per environment and lmax
        textured_(std::any_of(scene.materials.begin(), scene.materials.end(),
                              [](const SceneMaterial& m) { return m.texture >= 0; }) ||
                  std::any_of(scene.meshes.begin(), scene.meshes.end(),
                              [](const TriangleMesh& m) { return !m.colors.empty(); })) {
    // Without textures and vertex colours every material is a constant: made (and
    // validated) once, not per ray.
    if (textured_) return;
    for (size_t m = 0; m < scene.materials.size(); ++m) untextured_.push_back(scene.material_at(int(m), Vec2::Zero()));
  }

  // Shades `count` samples, sample i through film point place(i) (a Vec2, pixels), handing
  // each radiance to record(i, radiance). kLanes at a time (lanes.h): the primary hits,
  // each one's n.v and mirror direction, and where those fall in the map are found for all
  // lanes at once, then each lane is shaded. The lanes are this function's own locals, so
  // that the compiler can see that they and the map do not overlap, and vectorises
  // (EnvironmentLookups::locate); handed to helper functions by reference, they are not.
  template <typename Place, typename Record>
  void shade(int count, Place&& place, Record&& record) const {
    std::array<Ray, kLanes> rays;
    SurfaceHits hits;
    Directions mirror;
    alignas(64) float mu[kLanes];  // n.v
    EnvironmentLookups mirror_at;
    for (int first = 0; first < count; first += kLanes) {
      const int n = std::min(kLanes, count - first);
      for (int lane = 0; lane < n; ++lane) {
        const Vec2 film = place(first + lane);
        rays[lane] = camera_.generate_ray(film.x(), film.y());
      }
      // Texture coordinates cost a sphere two arc tangents: only when a material needs them.
      tracer_.intersect(rays.data(), n, hits, textured_);
      // Every lane, the ones past n repeating the last ray's view, so that the loops run whole.
      for (int lane = 0; lane < kLanes; ++lane) {
        const Vec3 v = -rays[std::min(lane, n - 1)].direction;
        mu[lane] = hits.normal.x[lane] * v.x() + hits.normal.y[lane] * v.y() + hits.normal.z[lane] * v.z();
        mirror.set(lane, reflect(v, hits.normal[lane]));
      }
      mirror_at.locate(environment_, mirror);
      for (int lane = 0; lane < n; ++lane)
        record(first + lane, radiance(rays[lane], hits, lane, mu[lane], mirror_at[lane]));
    }
  }

 private:
  // The radiance along `ray`, lane `lane` of `hits`: the background where it misses, else
  // the shading model of docs/design.md §2 with n.v `mu` and the mirror direction's place
  // in the map `mirror`.
  RGB radiance(const Ray& ray, const SurfaceHits& hits, int lane, float mu, const EnvironmentLookup& mirror) const {
    if (!hits.hit[lane]) return options_.black_background ? RGB::Zero() : environment_.eval(ray.direction);
    if (!(mu > 0.0f)) return RGB::Zero();  // the shading normal faces away: nothing reflected
    const PolishedMaterial material = textured_
                                          ? scene_.material_at(hits.material[lane], hits.uv[lane], hits.color[lane])
                                          : untextured_[size_t(hits.material[lane])];
    // Clamped at zero: a negative truncated sum is SH ringing (a point-like light seen
    // from its far side), not light. The inverse fits keep it unclamped, where the model
    // must stay linear in the lighting coefficients.
    const RGB E = options_.clamp_diffuse ? diffuse_sum_(hits.normal[lane]).max(0.0f) : diffuse_sum_(hits.normal[lane]);
    return polished_radiance(material, mu, environment_.eval(mirror), E);
  }

  const Scene& scene_;
  const RayTracer& tracer_;
  const Environment& environment_;
  const PinholeCamera& camera_;
  const ShIntegratorOptions& options_;
  const ShDiffuseSum diffuse_sum_;
  const bool textured_;
  std::vector<PolishedMaterial> untextured_;
};

// The luminance of every K x K sample, on the image's K-times finer lattice: where the
// refinement looks for edges.
class SampleLattice {
 public:
  SampleLattice(int width, int height) : width_(width), height_(height), values_(size_t(width) * height) {}

  float* row(int j) { return &values_[size_t(j) * width_]; }

  // Edges show on the lattice as third differences (zero for any quadratic, so a smooth
  // gradient has none): a step D as one of 2D. Half the largest along x and y of the
  // 4-sample windows holding (i, j), so a step's own size.
  float edge_step(int i, int j) const {
    float step = 0.0f;
    for (int first = -2; first <= 0; ++first) {
      const int a = first, b = first + 1, c = first + 2, d = first + 3;
      step = std::max({step, std::abs(at(i + d, j) - 3.0f * at(i + c, j) + 3.0f * at(i + b, j) - at(i + a, j)),
                       std::abs(at(i, j + d) - 3.0f * at(i, j + c) + 3.0f * at(i, j + b) - at(i, j + a))});
    }
    return 0.5f * step;
  }

 private:
  float at(int i, int j) const {  // clamped at the image's border
    return values_[size_t(std::clamp(j, 0, height_ - 1)) * width_ + std::clamp(i, 0, width_ - 1)];
  }

  int width_, height_;
  std::vector<float> values_;
};

// Row y's pixels on their K x K grids, a sub-row of the grids at a time (k samples per
// pixel along it, so that the lanes see neighbouring rays), into the image as each
// pixel's mean (the box filter), and each sample's luminance into `lattice` if given.
void render_row(const SampleShader& shader, int k, int y, Image& image, SampleLattice* lattice) {
  std::vector<RGB> row(image.width, RGB::Zero());
  for (int sy = 0; sy < k; ++sy) {
    float* lattice_row = lattice ? lattice->row(y * k + sy) : nullptr;
    shader.shade(
        image.width * k,
        [&](int i) { return Vec2(pixel_grid_coordinate(i / k, i % k, k), pixel_grid_coordinate(y, sy, k)); },
        [&](int i, const RGB& radiance) {
          row[size_t(i / k)] += radiance;
          if (lattice_row) lattice_row[i] = luminance(radiance);
        });
  }
  for (int x = 0; x < image.width; ++x) image.set(x, y, row[x] / float(k * k));
}

// A pixel to render again, on an M x M grid: its samples are those from first_sample on
// among all of its row's refined pixels.
struct RefinedPixel {
  int x, grid, first_sample;
};

// The pixels of row y whose K x K mean misses detail, with the grid each needs. The
// K x K mean errs little where light varies smoothly across the pixel (exact for linear
// variation, and a fraction 1/24 of the second difference for curved), and a lot at an
// edge (a silhouette, a reflected light's border): there, on an M x M grid, the edge cuts
// about M cells, each off by a uniform fraction of its step D / M^2, so the pixel's mean
// is off by about D / (sqrt(12) M^1.5). A pixel whose largest step D among its samples
// (SampleLattice::edge_step) is `bend` times refine_contrast of its luminance L is
// rendered again on the grid that brings the error under refine_contrast L / 2,
// M = (bend / sqrt(3))^(2/3), at least K + 1 and at most the finest allowed: a
// high-contrast edge (a window in HDR) gets many samples and a faint one a few.
std::vector<RefinedPixel> pixels_to_refine(const SampleLattice& lattice, const Image& image, int y,
                                           const ShIntegratorOptions& options) {
  const int k = options.supersampling;
  std::vector<RefinedPixel> refine;
  int samples = 0;
  for (int x = 0; x < image.width; ++x) {
    float step = 0.0f;
    for (int j = y * k; j < (y + 1) * k; ++j)
      for (int i = x * k; i < (x + 1) * k; ++i) step = std::max(step, lattice.edge_step(i, j));
    const float bend = step / (options.refine_contrast * std::max(luminance(image.at(x, y)), 1e-20f));
    if (!(bend > 1.0f)) continue;
    const int grid = int(std::clamp(std::ceil(std::pow(bend / std::sqrt(3.0f), 2.0f / 3.0f)), float(k + 1),
                                    float(options.refined_supersampling)));
    refine.push_back({x, grid, samples});
    samples += grid * grid;
  }
  return refine;
}

// Renders row y's pixels `refine` on their M x M grids, all of them in one run of samples
// (so that the lanes stay full), and their means replace their K x K ones.
void refine_row(const SampleShader& shader, const std::vector<RefinedPixel>& refine, int y, Image& image) {
  if (refine.empty()) return;
  const int samples = refine.back().first_sample + refine.back().grid * refine.back().grid;
  auto owner = [&](int sample) {  // the refined pixel that `sample` belongs to
    return size_t(std::upper_bound(refine.begin(), refine.end(), sample,
                                   [](int s, const RefinedPixel& p) { return s < p.first_sample; }) -
                  refine.begin() - 1);
  };
  std::vector<RGB> sums(refine.size(), RGB::Zero());
  shader.shade(
      samples,
      [&](int sample) {
        const RefinedPixel& p = refine[owner(sample)];
        const int cell = sample - p.first_sample;
        return pixel_grid_point(p.x, y, cell % p.grid, cell / p.grid, p.grid);
      },
      [&](int sample, const RGB& radiance) { sums[owner(sample)] += radiance; });
  for (size_t p = 0; p < refine.size(); ++p)
    image.set(refine[p].x, y, sums[p] / float(refine[p].grid * refine[p].grid));
}

}  // namespace

Image render_sh(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                const PinholeCamera& camera, const ShIntegratorOptions& options) {
  check_options(options);
  if (options.warn_when_inexact && !scene.is_single_convex_object()) {
    warn_once(scene.path +
              ": the sh integrator assumes a single convex object under distant light; "
              "it ignores the occlusion and interreflection of this scene (" +
              options.approximation_advice + ")");
  }
  const int k = options.supersampling;
  const uint64_t pixels = uint64_t(camera.width) * uint64_t(camera.height);
  const uint64_t lattice_bytes =
      options.refined_supersampling > k ? saturating_mul(pixels, uint64_t(k) * k * sizeof(float)) : 0;
  require_memory(checked_add(saturating_mul(pixels, kShBytesPerPixel), lattice_bytes).value_or(UINT64_MAX),
                 "the sh film of camera '" + camera.name + "' (" + std::to_string(camera.width) + "x" +
                     std::to_string(camera.height) + ")");
  const SampleShader shader(scene, tracer, environment, camera, options);
  Image image(camera.width, camera.height);
  // Refinement looks for edges among the K x K samples.
  std::optional<SampleLattice> lattice;
  if (options.refined_supersampling > k) lattice.emplace(camera.width * k, camera.height * k);
  auto render_rows = [&] {
    tbb::parallel_for(0, camera.height, [&](int y) { render_row(shader, k, y, image, lattice ? &*lattice : nullptr); });
    if (!lattice) return;
    // After every row's K x K pass: a pixel's edges are found in its neighbours' samples too.
    tbb::parallel_for(0, camera.height,
                      [&](int y) { refine_row(shader, pixels_to_refine(*lattice, image, y, options), y, image); });
  };
  // threads 0: the caller's arena (all cores, or what an enclosing arena allows, such as
  // invert-fit --threads for its re-renders).
  if (options.threads > 0)
    tbb::task_arena(options.threads).execute(render_rows);
  else
    render_rows();
  return image;
}

IntegratorResult ShIntegrator::render_camera(const PinholeCamera& camera, uint64_t) const {
  const auto start = std::chrono::steady_clock::now();
  IntegratorResult result;
  result.image = render_sh(scene_, tracer_, environment_, camera, options_);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.metadata = {{"glaze:integrator", std::string(kName)},
                     {"glaze:lmax", std::to_string(options_.lmax)},
                     {"glaze:ss", std::to_string(options_.supersampling)}};
  result.summary = "sh, lmax " + std::to_string(options_.lmax) + ", ss " + std::to_string(options_.supersampling);
  if (options_.refined_supersampling > 0) {
    result.metadata["glaze:ss_refined"] = std::to_string(options_.refined_supersampling);
    result.summary += " refined " + std::to_string(options_.refined_supersampling);
  }
  return result;
}

}  // namespace glaze
