#include "renderer/path_tracer.h"

#include "renderer/error.h"

#include <array>

namespace glaze {
namespace {

float power_heuristic(float pdf_a, float pdf_b) {
  const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

}  // namespace

DirectLightEstimator parse_direct_light_estimator(const std::string& name) {
  if (name == "mis") return DirectLightEstimator::mis;
  if (name == "bsdf") return DirectLightEstimator::bsdf;
  if (name == "environment") return DirectLightEstimator::environment;
  throw Error("unknown direct-light estimator '" + name + "' (known: mis, bsdf, environment)");
}

PathTracer::PathTracer(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                       const PathTracerOptions& options)
    : scene_(scene),
      tracer_(tracer),
      environment_(environment),
      options_(options),
      convex_(options.convex_shortcut && scene.is_single_convex_object()),
      max_depth_(convex_ ? std::min(options.max_depth, 1) : options.max_depth) {
  if (options.max_depth < 1) throw Error("max depth must be at least 1");
}

float PathTracer::light_sample_weight(float light_pdf, float bsdf_pdf) const {
  return options_.estimator == DirectLightEstimator::mis ? power_heuristic(light_pdf, bsdf_pdf) : 1.0f;
}

float PathTracer::escape_weight(bool after_delta, float bsdf_pdf, float light_pdf) const {
  if (after_delta || options_.estimator == DirectLightEstimator::bsdf) return 1.0f;
  if (options_.estimator == DirectLightEstimator::environment) return 0.0f;
  return power_heuristic(bsdf_pdf, light_pdf);
}

RGB PathTracer::radiance(const Ray& ray, Pcg32& rng) const {
  RGB result;
  radiance(&ray, 1, rng, &result);
  return result;
}

void PathTracer::radiance(const Ray* rays, int count, Pcg32& rng, RGB* out) const {
  if (convex_) {
    convex_direct_light(rays, count, rng, out);
  } else {
    for (int k = 0; k < count; ++k) out[k] = trace_path(rays[k], rng);
  }
}

void PathTracer::convex_direct_light(const Ray* rays, int count, Pcg32& rng, RGB* out) const {
  constexpr int kBatch = 16;
  const bool use_environment_samples = options_.estimator != DirectLightEstimator::bsdf;
  const bool need_light_pdf = options_.estimator == DirectLightEstimator::mis;
  struct Lane {
    bool active;
    Frame frame;
    Vec3 wo, geometric_normal;
    float fresnel;
    std::optional<PolishedMaterial> material;
    EnvironmentSample light;
    EnvironmentLookup light_at, mirror_at, diffuse_at;
    bool mirror_escapes;
    std::optional<MaterialSample> diffuse;
  };
  std::array<Lane, kBatch> lanes;
  std::array<Vec2, kBatch> light_u;
  std::array<EnvironmentSample, kBatch> light_samples;
  for (int first = 0; first < count; first += kBatch) {
    const int n = std::min(kBatch, count - first);
    // 1. Camera rays; next-event directions, whose texels start loading.
    if (use_environment_samples) {
      for (int k = 0; k < n; ++k) light_u[k] = Vec2(rng.next_float(), rng.next_float());
      environment_.sample(std::span(light_u.data(), n), std::span(light_samples.data(), n));
    }
    for (int k = 0; k < n; ++k) {
      Lane& lane = lanes[k];
      const Ray& ray = rays[first + k];
      const std::optional<SurfaceHit> hit = tracer_.intersect(ray);
      out[first + k] = RGB::Zero();
      lane.active = hit.has_value();
      if (!hit) {
        if (!options_.black_background) out[first + k] = environment_.eval(ray.direction);
        continue;
      }
      lane.frame = Frame::from_normal(hit->normal);
      lane.wo = lane.frame.to_local(-ray.direction);
      lane.geometric_normal = hit->geometric_normal;
      lane.material.emplace(scene_.material_at(hit->material, hit->uv));
      lane.light.pdf = 0.0f;
      if (use_environment_samples) {
        lane.light = light_samples[k];
        if (lane.light.pdf > 0.0f && lane.light.direction.dot(lane.geometric_normal) > 0.0f) {
          lane.light_at = environment_.locate(lane.light.direction);
          environment_.prefetch(lane.light_at, false);
        } else {
          lane.light.pdf = 0.0f;
        }
      }
    }
    // 2. The mirror direction and a diffuse-lobe sample; their texels start loading.
    for (int k = 0; k < n; ++k) {
      Lane& lane = lanes[k];
      if (!lane.active) continue;
      const Vec2 u(rng.next_float(), rng.next_float());
      lane.fresnel = lane.material->fresnel(lane.wo.z());
      const Vec3 mirror = lane.frame.to_world(Vec3(-lane.wo.x(), -lane.wo.y(), lane.wo.z()));
      lane.mirror_escapes = lane.wo.z() > 0.0f && mirror.dot(lane.geometric_normal) > 0.0f;
      if (lane.mirror_escapes) {
        lane.mirror_at = environment_.locate(mirror);
        environment_.prefetch(lane.mirror_at, false);
      }
      lane.diffuse = lane.material->sample_diffuse(lane.wo, u);
      if (!lane.diffuse) continue;
      const Vec3 direction = lane.frame.to_world(lane.diffuse->wi);
      if (direction.dot(lane.geometric_normal) <= 0.0f) {
        lane.diffuse.reset();
        continue;
      }
      lane.diffuse_at = environment_.locate(direction);
      environment_.prefetch(lane.diffuse_at, need_light_pdf);
    }
    // 3. Next-event estimates (no shadow rays: nothing occludes a convex object's sky).
    for (int k = 0; k < n; ++k) {
      const Lane& lane = lanes[k];
      if (!lane.active || !(lane.light.pdf > 0.0f)) continue;
      const Vec3 wi = lane.frame.to_local(lane.light.direction);
      const RGB f = lane.material->eval_diffuse(lane.wo, wi);
      if (!(f > 0.0f).any()) continue;
      const float weight = light_sample_weight(lane.light.pdf, diffuse_lobe_pdf(wi.z()));
      out[first + k] += f * (wi.z() * weight / lane.light.pdf) * environment_.eval(lane.light_at);
    }
    // 4. The mirror term, exactly, and the diffuse sample escaping to the environment.
    for (int k = 0; k < n; ++k) {
      const Lane& lane = lanes[k];
      if (!lane.active) continue;
      if (lane.mirror_escapes) out[first + k] += lane.fresnel * environment_.eval(lane.mirror_at);
      if (!lane.diffuse) continue;
      const float light_pdf = need_light_pdf ? environment_.pdf(lane.diffuse_at) : 0.0f;
      const float weight = escape_weight(false, lane.diffuse->pdf, light_pdf);
      if (weight > 0.0f) out[first + k] += lane.diffuse->weight * weight * environment_.eval(lane.diffuse_at);
    }
  }
}

RGB PathTracer::trace_path(const Ray& camera_ray, Pcg32& rng) const {
  RGB result = RGB::Zero(), throughput = RGB::Ones();
  Ray ray = camera_ray;
  bool after_delta = true;     // the last bounce was the mirror (or there was none)
  float last_bsdf_pdf = 0.0f;  // solid-angle density of the last diffuse-lobe sample
  const bool use_environment_samples = options_.estimator != DirectLightEstimator::bsdf;

  for (int bounce = 0;; ++bounce) {
    const std::optional<SurfaceHit> hit = tracer_.intersect(ray);
    if (!hit) {
      if (bounce == 0) {
        if (!options_.black_background) result += environment_.eval(ray.direction);
      } else {
        const EnvironmentLookup at = environment_.locate(ray.direction);
        const bool need_pdf = !after_delta && options_.estimator == DirectLightEstimator::mis;
        const float weight = escape_weight(after_delta, last_bsdf_pdf, need_pdf ? environment_.pdf(at) : 0.0f);
        if (weight > 0.0f) result += throughput * environment_.eval(at) * weight;
      }
      break;
    }
    if (bounce >= max_depth_) break;

    const Frame frame = Frame::from_normal(hit->normal);
    const Vec3 wo = frame.to_local(-ray.direction);
    const PolishedMaterial material = scene_.material_at(hit->material, hit->uv);
    const Vec3 origin = hit->position + RayTracer::ray_offset(hit->position) * hit->geometric_normal;

    if (use_environment_samples) {
      const EnvironmentSample light = environment_.sample(Vec2(rng.next_float(), rng.next_float()));
      if (light.pdf > 0.0f && light.direction.dot(hit->geometric_normal) > 0.0f) {
        const Vec3 wi = frame.to_local(light.direction);
        const RGB f = material.eval_diffuse(wo, wi);
        if ((f > 0.0f).any() && !tracer_.occluded({origin, light.direction})) {
          const float weight = light_sample_weight(light.pdf, material.pdf_diffuse(wo, wi));
          result += throughput * f * (wi.z() * weight / light.pdf) * environment_.eval(light.direction);
        }
      }
    }

    const float u_lobe = rng.next_float();
    const Vec2 u(rng.next_float(), rng.next_float());
    const std::optional<MaterialSample> sample = material.sample(wo, u_lobe, u);
    if (!sample) break;
    const Vec3 direction = frame.to_world(sample->wi);
    if (direction.dot(hit->geometric_normal) <= 0.0f) break;  // shading normal sent it inside
    throughput *= sample->weight;
    after_delta = sample->is_specular;
    last_bsdf_pdf = sample->pdf;
    ray = {origin, direction.normalized()};

    if (bounce + 1 >= options_.russian_roulette_depth) {
      const float survive = std::min(0.95f, throughput.maxCoeff());
      if (!(rng.next_float() < survive)) break;
      throughput /= survive;
    }
  }
  return result;
}

}  // namespace glaze
