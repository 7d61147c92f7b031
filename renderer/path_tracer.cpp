#include "renderer/path_tracer.h"

#include "renderer/error.h"

namespace glaze {
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
    const PolishedMaterial material = scene_.material_at(hit->material, hit->uv, hit->color);
    const Vec3 origin = hit->position + RayTracer::ray_offset(hit->position) * hit->geometric_normal;

    if (use_environment_samples) {
      const EnvironmentSample light = environment_.sample(rng);
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
