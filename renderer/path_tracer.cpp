#include "renderer/path_tracer.h"

#include "renderer/error.h"

#include <array>
#include <optional>
#include <span>

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
    for (int first = 0; first < count; first += kLanes)
      trace_paths(rays + first, std::min(kLanes, count - first), rng, out + first);
  }
}

void PathTracer::trace_paths(const Ray* rays, int count, Pcg32& rng, RGB* out) const {
  // Each lane's path state; `active` lists the lanes whose paths go on, in lane order, so
  // that the random numbers are drawn in an order fixed by the pixel alone.
  struct Path {
    Ray ray;
    RGB throughput = RGB::Ones();
    bool after_delta = true;     // the last bounce was the mirror (or there was none)
    float last_bsdf_pdf = 0.0f;  // solid-angle density of the last diffuse-lobe sample
  };
  std::array<Path, kLanes> paths;
  std::array<int, kLanes> active;
  std::array<Ray, kLanes> path_rays;  // the live paths' rays, packed for one packet
  std::array<SurfaceHit, kLanes> hits;
  std::array<bool, kLanes> hit;
  std::array<Ray, kLanes> shadow_rays;
  std::array<int, kLanes> shadowed;  // the lane (index into active) of each shadow ray
  std::array<bool, kLanes> blocked;
  std::array<RGB, kLanes> unblocked;  // what each shadow ray's light adds if nothing blocks it
  std::array<EnvironmentLookup, kLanes> at;
  std::array<EnvironmentSample, kLanes> lights;
  for (int k = 0; k < count; ++k) {
    paths[k].ray = rays[k];
    out[k] = RGB::Zero();
    active[k] = k;
  }
  int live = count;
  const bool use_environment_samples = options_.estimator != DirectLightEstimator::bsdf;

  for (int bounce = 0; live > 0; ++bounce) {
    for (int i = 0; i < live; ++i) path_rays[i] = paths[active[i]].ray;
    tracer_.intersect(path_rays.data(), live, hits.data(), hit.data(),
                      bounce == 0 ? RayCoherence::coherent : RayCoherence::incoherent);

    // Paths that escaped: every lane's texels (and sampling density) are requested
    // before the first is read.
    const bool need_pdf = bounce > 0 && options_.estimator == DirectLightEstimator::mis;
    for (int i = 0; i < live; ++i) {
      if (hit[i] || (bounce == 0 && options_.black_background)) continue;
      at[i] = environment_.locate(paths[active[i]].ray.direction);
      environment_.prefetch(at[i], need_pdf && !paths[active[i]].after_delta);
    }
    int next = 0;
    for (int i = 0; i < live; ++i) {
      const int k = active[i];
      const Path& path = paths[k];
      if (hit[i]) {
        if (bounce < max_depth_) hits[next] = hits[i], active[next++] = k;
        continue;
      }
      if (bounce == 0) {
        if (!options_.black_background) out[k] += environment_.eval(at[i]);
      } else {
        const bool pdf_needed = need_pdf && !path.after_delta;
        const float weight =
            escape_weight(path.after_delta, path.last_bsdf_pdf, pdf_needed ? environment_.pdf(at[i]) : 0.0f);
        if (weight > 0.0f) out[k] += path.throughput * environment_.eval(at[i]) * weight;
      }
    }
    live = next;

    // Next-event estimation: all lanes' light samples at once (their table reads
    // overlap), and the texels of their radiance requested before the shadow rays.
    if (use_environment_samples) {
      environment_.sample(rng, std::span(lights.data(), size_t(live)));
      for (int i = 0; i < live; ++i) {
        if (!(lights[i].pdf > 0.0f)) continue;
        at[i] = environment_.locate(lights[i].direction);
        environment_.prefetch(at[i], false);
      }
    }

    // The shading at each hit, and the shadow rays of the light samples that would add
    // something, traced together as one packet.
    std::array<Frame, kLanes> frames;
    std::array<Vec3, kLanes> wos, origins;
    std::array<std::optional<PolishedMaterial>, kLanes> materials;  // (no default constructor)
    int shadow_count = 0;
    for (int i = 0; i < live; ++i) {
      const int k = active[i];
      const SurfaceHit& h = hits[i];
      frames[i] = Frame::from_normal(h.normal);
      wos[i] = frames[i].to_local(-paths[k].ray.direction);
      materials[i].emplace(scene_.material_at(h.material, h.uv, h.color));
      origins[i] = h.position + RayTracer::ray_offset(h.position) * h.geometric_normal;

      const EnvironmentSample& light = lights[i];
      if (!use_environment_samples || !(light.pdf > 0.0f) || light.direction.dot(h.geometric_normal) <= 0.0f) continue;
      const Vec3 wi = frames[i].to_local(light.direction);
      const RGB f = materials[i]->eval_diffuse(wos[i], wi);
      if (!(f > 0.0f).any()) continue;
      const float weight = light_sample_weight(light.pdf, materials[i]->pdf_diffuse(wos[i], wi));
      unblocked[shadow_count] = paths[k].throughput * f * (wi.z() * weight / light.pdf) * environment_.eval(at[i]);
      shadow_rays[shadow_count] = {origins[i], light.direction};
      shadowed[shadow_count++] = i;
    }
    if (shadow_count > 0) tracer_.occluded(shadow_rays.data(), shadow_count, blocked.data());
    for (int j = 0; j < shadow_count; ++j)
      if (!blocked[j]) out[active[shadowed[j]]] += unblocked[j];

    next = 0;
    for (int i = 0; i < live; ++i) {
      const int k = active[i];
      Path& path = paths[k];
      const SurfaceHit& h = hits[i];
      const Frame& frame = frames[i];
      const Vec3& wo = wos[i];
      const PolishedMaterial& material = *materials[i];
      const Vec3& origin = origins[i];

      const float u_lobe = rng.next_float();
      const Vec2 u(rng.next_float(), rng.next_float());
      const std::optional<MaterialSample> sample = material.sample(wo, u_lobe, u);
      if (!sample) continue;
      const Vec3 direction = frame.to_world(sample->wi);
      if (direction.dot(h.geometric_normal) <= 0.0f) continue;  // shading normal sent it inside
      path.throughput *= sample->weight;
      path.after_delta = sample->is_specular;
      path.last_bsdf_pdf = sample->pdf;
      path.ray = {origin, direction.normalized()};

      if (bounce + 1 >= options_.russian_roulette_depth) {
        const float survive = std::min(0.95f, path.throughput.maxCoeff());
        if (!(rng.next_float() < survive)) continue;
        path.throughput /= survive;
      }
      active[next++] = k;
    }
    live = next;
  }
}

}  // namespace glaze
