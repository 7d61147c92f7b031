#include "inverse/samples.h"

#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/image_error.h"
#include "renderer/image_lookup.h"
#include "renderer/memory_budget.h"
#include "renderer/rng.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace glaze {

DropCounts& DropCounts::operator+=(const DropCounts& other) {
  grazing += other.grazing;
  silhouette += other.silhouette;
  non_finite += other.non_finite;
  saturated += other.saturated;
  masked += other.masked;
  hidden += other.hidden;
  return *this;
}

DropCounts SampleSet::total_dropped() const {
  DropCounts total;
  for (const DropCounts& d : dropped) total += d;
  return total;
}

namespace {

// Points spread uniformly over the object's surface.
std::vector<Vec3> surface_points(const Scene& scene, int count, uint64_t seed) {
  std::vector<Vec3> points;
  points.reserve(count);
  if (scene.meshes.empty() && scene.spheres.size() == 1) {
    // Fibonacci lattice: equal-area bands in z, golden-angle steps in phi.
    const Sphere& s = scene.spheres.front();
    const double golden_angle = kPiD * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / count, r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden_angle * i;
      points.push_back(s.center + s.radius * Vec3d(r * std::cos(phi), r * std::sin(phi), z).cast<float>());
    }
    return points;
  }
  if (!scene.spheres.empty()) throw Error("--points supports one analytic sphere or triangle meshes, not a mix");
  // Area-weighted triangles, then a uniform point in the chosen triangle.
  std::vector<double> cumulative;
  std::vector<std::pair<int, int>> triangles;  // (mesh, triangle)
  double total = 0.0;
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    for (size_t t = 0; t < scene.meshes[m].triangles.size(); ++t) {
      const auto& tri = scene.meshes[m].triangles[t];
      const auto& p = scene.meshes[m].positions;
      total += 0.5 * (p[tri[1]] - p[tri[0]]).cross(p[tri[2]] - p[tri[0]]).norm();
      cumulative.push_back(total);
      triangles.emplace_back(int(m), int(t));
    }
  if (!(total > 0.0)) throw Error(scene.path + ": the object has no surface area to place points on");
  Pcg32 rng(seed, 0x5eed);
  for (int i = 0; i < count; ++i) {
    const double target = rng.next_float() * total;
    const size_t k =
        std::min(size_t(std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin()),
                 cumulative.size() - 1);
    const TriangleMesh& mesh = scene.meshes[triangles[k].first];
    const auto& tri = mesh.triangles[triangles[k].second];
    float a = rng.next_float(), b = rng.next_float();
    if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
    points.push_back(mesh.positions[tri[0]] + a * (mesh.positions[tri[1]] - mesh.positions[tri[0]]) +
                     b * (mesh.positions[tri[2]] - mesh.positions[tri[0]]));
  }
  return points;
}

// The pixels of an 8-bit image that are clipped (kJpegClipCode, samples.h); empty for
// other images.
std::vector<uint8_t> clipped_pixels(const Image& image) {
  if (image.source_bits != 8) return {};
  const int top = image.source_lossy ? kJpegClipCode : image.max_code();
  const int reach = image.source_lossy ? kJpegClipReach : 0;
  std::vector<uint8_t> clipped(size_t(image.width) * image.height, 0);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const RGB value = image.at(x, y);
      if (std::max({image.code(value[0]), image.code(value[1]), image.code(value[2])}) < top) continue;
      for (int j = std::max(0, y - reach); j <= std::min(image.height - 1, y + reach); ++j)
        for (int i = std::max(0, x - reach); i <= std::min(image.width - 1, x + reach); ++i)
          clipped[size_t(j) * image.width + i] = 1;
    }
  return clipped;
}

// Everything about one frame that deciding on a sample needs.
struct FrameView {
  const PinholeCamera& camera;
  const Image& image;
  const Image* mask;
  std::vector<float> alpha;
  std::vector<uint8_t> clipped;  // 8-bit images: clipped_pixels
  std::vector<uint8_t> interior;
  float saturation;
  float min_cos;

  bool interior_pixel(int x, int y) const {
    return x >= 0 && y >= 0 && x < camera.width && y < camera.height && interior[size_t(y) * camera.width + x];
  }
  bool masked_pixel(int x, int y) const {
    return (mask && mask->at(x, y)[0] < 0.5f) || alpha[size_t(y) * camera.width + x] < 0.5f;
  }
  bool clipped_pixel(int x, int y) const { return !clipped.empty() && clipped[size_t(y) * camera.width + x]; }
  // Applies the drop rules to a hit seen through film point (fx, fy) with value `observed`.
  bool keep(const SurfaceHit& hit, const Vec3& view, const RGB& observed, bool clipped, bool masked,
            DropCounts& dropped) const {
    const float mu = hit.normal.dot(view);
    if (!(mu >= min_cos)) return ++dropped.grazing, false;
    if (!observed.allFinite()) return ++dropped.non_finite, false;
    if (clipped || (observed >= saturation).any()) return ++dropped.saturated, false;
    if (masked) return ++dropped.masked, false;
    return true;
  }
};

Sample make_sample(const SurfaceHit& hit, const Vec3& view, const RGB& observed, int frame, const Vec2& film,
                   const Image& image) {
  return {hit.position,
          hit.normal,
          view,
          hit.normal.dot(view),
          observed,
          hit.uv,
          frame,
          film,
          quantisation_weight(image, observed)};
}

}  // namespace

float quantisation_weight(const Image& image, const RGB& value) {
  if (image.source_bits != 8) return 1.0f;
  const auto decoded = [&](float code) {
    const float encoded = std::clamp(code / float(image.max_code()), 0.0f, 1.0f);
    return image.source_srgb ? srgb_to_linear(encoded) : encoded;
  };
  constexpr double kRelative = 0.02;  // the relative rounding error at which the weight halves
  double sum = 0.0;
  for (int c = 0; c < 3; ++c) {
    const float code = float(image.code(value[c]));
    const double step = decoded(code + 0.5f) - decoded(code - 0.5f);
    const double relative = step / std::sqrt(12.0) / kRelative;
    sum += value[c] > 0.0f ? 1.0 / (1.0 + relative * relative / (double(value[c]) * value[c])) : 0.0;
  }
  return float(sum / 3.0);
}

SampleSet collect_samples(const CaptureSet& captures, const RayTracer& tracer, const Scene& object_scene,
                          const SampleOptions& options) {
  if (captures.frames.empty()) throw Error(captures.directory + ": the capture set has no frames");
  if (!(options.min_cos >= 0.0f && options.min_cos < 1.0f)) throw Error("the grazing threshold must be in [0, 1)");
  SampleSet set;
  set.pixels = options.points == 0;
  if (options.points > 0)
    require_memory(saturating_mul(uint64_t(options.points), sizeof(Vec3)),
                   "--points " + std::to_string(options.points));
  const std::vector<Vec3> points =
      options.points > 0 ? surface_points(object_scene, options.points, options.seed) : std::vector<Vec3>();
  for (size_t f = 0; f < captures.frames.size(); ++f) {
    const CaptureFrame& frame = captures.frames[f];
    const PinholeCamera& camera = frame.camera;
    // At most one sample per pixel or point, held twice while the frame's are gathered
    // (per row, then kept), then added to the set's (which may double as it grows).
    const uint64_t frame_samples = points.empty() ? uint64_t(camera.width) * uint64_t(camera.height) : points.size();
    require_memory(saturating_mul(2 * frame_samples + 2 * set.samples.size(), sizeof(Sample)),
                   "the samples of " + frame.file_path);
    std::vector<float> alpha;
    const Image image = read_image(frame.file_path, &alpha);
    if (image.width != camera.width || image.height != camera.height)
      throw Error(frame.file_path + ": the image is " + std::to_string(image.width) + "x" +
                  std::to_string(image.height) + " but transforms.json gives its camera " +
                  std::to_string(camera.width) + "x" + std::to_string(camera.height));
    std::optional<Image> mask;
    if (!frame.mask_path.empty()) {
      mask = read_image(frame.mask_path);
      if (mask->width != image.width || mask->height != image.height)
        throw Error(frame.mask_path + ": the mask's size differs from its image " + frame.file_path);
    }
    const FrameView view{camera,
                         image,
                         mask ? &*mask : nullptr,
                         std::move(alpha),
                         clipped_pixels(image),
                         interior_mask(tracer, camera),
                         captures.saturation.value_or(std::numeric_limits<float>::infinity()),
                         options.min_cos};
    DropCounts dropped;
    std::vector<Sample> kept;

    if (points.empty()) {
      // One sample per interior pixel, rows in parallel, concatenated in row order.
      std::vector<std::vector<Sample>> rows(camera.height);
      std::vector<DropCounts> row_dropped(camera.height);
      tbb::parallel_for(0, camera.height, [&](int y) {
        for (int x = 0; x < camera.width; ++x) {
          const Ray ray = camera.generate_ray(x + 0.5f, y + 0.5f);
          const std::optional<SurfaceHit> hit = tracer.intersect(ray);
          if (!hit) continue;
          if (!view.interior_pixel(x, y)) {
            ++row_dropped[y].silhouette;
            continue;
          }
          if (view.keep(*hit, -ray.direction, image.at(x, y), view.clipped_pixel(x, y), view.masked_pixel(x, y),
                        row_dropped[y]))
            rows[y].push_back(
                make_sample(*hit, -ray.direction, image.at(x, y), int(f), Vec2(x + 0.5f, y + 0.5f), image));
        }
      });
      for (int y = 0; y < camera.height; ++y) {
        kept.insert(kept.end(), rows[y].begin(), rows[y].end());
        dropped += row_dropped[y];
      }
    } else {
      const Eigen::Affine3f world_to_camera = camera.camera_to_world.inverse();
      for (const Vec3& point : points) {
        const std::optional<Vec2> film = camera.project(world_to_camera * point);
        if (!film) continue;  // behind the camera
        const float fx = film->x(), fy = film->y();
        if (!(fx >= 0.0f && fy >= 0.0f && fx < camera.width && fy < camera.height)) continue;
        const Ray ray = camera.generate_ray(fx, fy);
        const std::optional<SurfaceHit> hit = tracer.intersect(ray);
        const float distance = (point - ray.origin).norm();
        if (!hit || std::abs(hit->distance - distance) > 1e-3f * distance) {
          ++dropped.hidden;  // another part of the object is in front, or the point faces away
          continue;
        }
        // The bilinear footprint: the four pixels around (fx, fy) must all be interior.
        const int x0 = int(std::floor(fx - 0.5f)), y0 = int(std::floor(fy - 0.5f));
        if (!(view.interior_pixel(x0, y0) && view.interior_pixel(x0 + 1, y0) && view.interior_pixel(x0, y0 + 1) &&
              view.interior_pixel(x0 + 1, y0 + 1))) {
          ++dropped.silhouette;
          continue;
        }
        const RGB observed =
            bilinear(image, bilinear_footprint(fx, fy, image.width, image.height, Wrap::clamp, Wrap::clamp));
        const auto any_of_four = [&](auto&& test) {
          return test(x0, y0) || test(x0 + 1, y0) || test(x0, y0 + 1) || test(x0 + 1, y0 + 1);
        };
        const bool clipped = any_of_four([&](int x, int y) { return view.clipped_pixel(x, y); });
        const bool masked = any_of_four([&](int x, int y) { return view.masked_pixel(x, y); });
        if (view.keep(*hit, -ray.direction, observed, clipped, masked, dropped))
          kept.push_back(make_sample(*hit, -ray.direction, observed, int(f), Vec2(fx, fy), image));
      }
    }
    set.per_frame.push_back(kept.size());
    set.source_bits.push_back(image.source_bits);
    set.source_lossy.push_back(image.source_lossy);
    set.dropped.push_back(dropped);
    set.samples.insert(set.samples.end(), kept.begin(), kept.end());
  }
  if (set.samples.empty()) {
    const DropCounts d = set.total_dropped();
    throw Error(captures.directory +
                ": no usable sample: the object is not visible in any view, or every pixel on it was dropped (" +
                std::to_string(d.grazing) + " grazing, " + std::to_string(d.silhouette) + " on the silhouette, " +
                std::to_string(d.non_finite) + " not finite, " + std::to_string(d.saturated) + " saturated, " +
                std::to_string(d.masked) + " masked); check the object and camera poses in transforms.json");
  }
  return set;
}

}  // namespace glaze
