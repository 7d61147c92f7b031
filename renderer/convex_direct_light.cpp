// convex_direct_light.cpp: the path tracer's estimator for its most common scene, one
// analytic sphere under distant light (PathTracer::convex_direct_light).
//
// Nothing can occlude the sky of a lone convex object, so a camera sample needs one
// ray-sphere root and three environment lookups: the mirror direction, whose term
// F(n.v) L(r) is taken exactly, and two estimates of the diffuse lobe's light combined
// by MIS, one from a direction drawn from the environment's density, one from a
// direction drawn from the lobe.
//
// The work runs 16 camera samples at a time, stage by stage, in structure-of-arrays
// lanes. The arithmetic stages are loops over the lanes of the same inline, branch-free
// code the rest of glaze calls one direction at a time (the ray-sphere root, the
// environment's lat-long lookup, the frame, the Fresnel and diffuse factors), which the
// compiler turns into SIMD. The stages that read tables (the environment's density and
// texels, a texture) prefetch them a stage ahead, so that their cache misses overlap.
#include "renderer/path_tracer.h"

#include <array>

namespace glaze {

void PathTracer::convex_direct_light(const Ray* rays, int count, Pcg32& rng, RGB* out) const {
  const Sphere& sphere = scene_.spheres.front();
  const SceneMaterial& material = scene_.materials[sphere.material];
  const bool textured = material.texture >= 0;
  const float R0 = material.R0;
  const bool use_environment_samples = options_.estimator != DirectLightEstimator::bsdf;
  const bool need_light_pdf = options_.estimator == DirectLightEstimator::mis;
  // The estimators in use as factors, so that the lane loops below have no branches
  // on them: with the light's density at 0 (no MIS) the power heuristic gives 1.
  const float lobe_used = options_.estimator == DirectLightEstimator::environment ? 0.0f : 1.0f;
  const float mis = need_light_pdf ? 1.0f : 0.0f;

  SurfaceHits hits;
  const Directions& normal = hits.normal;
  const int* hit = hits.hit;
  Directions view, mirror, lobe, light;
  alignas(64) float mu_o[kLanes], mirror_weight[kLanes], light_weight[kLanes], lobe_weight[kLanes];
  alignas(64) float light_pdf[kLanes], lobe_density[kLanes], lobe_light_pdf[kLanes];
  alignas(64) float lobe_u_theta[kLanes], lobe_u_phi[kLanes], lobe_cos_theta[kLanes];
  std::array<EnvironmentSample, kLanes> light_samples;
  std::array<RGB, kLanes> Rd;
  EnvironmentLookups light_at, mirror_at, lobe_at;

  for (int first = 0; first < count; first += kLanes) {
    const int n = std::min(kLanes, count - first);
    // 1. The camera rays' hits (SIMD for a lone sphere: RayTracer), the environment's
    // samples (their table reads interleaved) and two numbers per hit for the lobe.
    tracer_.intersect(rays + first, n, hits, textured);
    if (use_environment_samples) environment_.sample(rng, std::span(light_samples.data(), n));
    for (int k = 0; k < kLanes; ++k) {
      const Vec2 u = k < n && hit[k] ? Vec2(rng.next_float(), rng.next_float()) : Vec2(0.5f, 0.5f);
      lobe_u_theta[k] = u.x();
      lobe_u_phi[k] = u.y();
    }
    for (int k = 0; k < kLanes; ++k) {
      const bool drawn = use_environment_samples && k < n;
      light.set(k, drawn ? light_samples[k].direction : Vec3::UnitZ());
      light_pdf[k] = drawn ? light_samples[k].pdf : 0.0f;
    }

    // 3. SIMD: the cosine to the viewer and the mirror direction.
    for (int k = 0; k < kLanes; ++k) {
      const Ray& ray = rays[first + std::min(k, n - 1)];
      view.set(k, ray.direction);
    }
    for (int k = 0; k < kLanes; ++k) {
      mu_o[k] = -(normal.x[k] * view.x[k] + normal.y[k] * view.y[k] + normal.z[k] * view.z[k]);
      mirror.x[k] = view.x[k] + 2.0f * mu_o[k] * normal.x[k];
      mirror.y[k] = view.y[k] + 2.0f * mu_o[k] * normal.y[k];
      mirror.z[k] = view.z[k] + 2.0f * mu_o[k] * normal.z[k];
    }
    // 4. The diffuse reflectance (a texture read per lane, or the material's constant)
    // and the lobe's direction: cos(theta) from its inverse CDF, then into the world.
    for (int k = 0; k < kLanes; ++k) {
      Rd[k] = textured && hit[k] ? scene_.material_at(sphere.material, hits.uv[k]).Rd() : material.Rd;
    }
    diffuse_lobe_cos_theta(lobe_u_theta, lobe_cos_theta);
    for (int k = 0; k < kLanes; ++k) {
      lobe_density[k] = diffuse_lobe_pdf(lobe_cos_theta[k]);
      lobe.set(k, Frame::from_normal(normal[k]).to_world(diffuse_lobe_direction(lobe_cos_theta[k], lobe_u_phi[k])));
    }
    // 5. SIMD: where the three directions fall in the map; then their texels (and the
    // density at the lobe's direction, for its MIS weight) start loading.
    mirror_at.locate(environment_, mirror);
    lobe_at.locate(environment_, lobe);
    if (use_environment_samples) light_at.locate(environment_, light);
    for (int k = 0; k < n; ++k) {
      if (!hit[k]) continue;
      environment_.prefetch(mirror_at[k], false);
      environment_.prefetch(lobe_at[k], need_light_pdf);
      if (use_environment_samples) environment_.prefetch(light_at[k], false);
    }
    for (int k = 0; k < kLanes; ++k)
      lobe_light_pdf[k] = need_light_pdf && hit[k] && k < n ? environment_.pdf(lobe_at[k]) : 0.0f;

    // 6. SIMD: the weight of each lookup, the material's (material.h) per unit of Rd. The
    // mirror: F(mu_o). The environment's direction: f_d cos / pdf, times its MIS weight.
    // The lobe's: diffuse_lobe_weight, times its MIS weight. Zero where a direction is
    // below the horizon (for a sphere the geometric normal is the shading normal) or the
    // camera ray missed.
    for (int k = 0; k < kLanes; ++k) {
      const bool seen = hit[k] != 0 && mu_o[k] > 0.0f;
      mirror_weight[k] = seen ? schlick_fresnel(R0, mu_o[k]) : 0.0f;
    }
    for (int k = 0; k < kLanes; ++k) {
      const bool seen = hit[k] != 0 && mu_o[k] > 0.0f;
      const float mu_lobe = normal.x[k] * lobe.x[k] + normal.y[k] * lobe.y[k] + normal.z[k] * lobe.z[k];
      lobe_weight[k] = seen && mu_lobe > 0.0f ? lobe_used * diffuse_lobe_weight(R0, mu_o[k]) *
                                                    power_heuristic(lobe_density[k], lobe_light_pdf[k])
                                              : 0.0f;
    }
    for (int k = 0; k < kLanes; ++k) {
      const bool seen = hit[k] != 0 && mu_o[k] > 0.0f;
      const float mu_light = normal.x[k] * light.x[k] + normal.y[k] * light.y[k] + normal.z[k] * light.z[k];
      light_weight[k] = seen && mu_light > 0.0f && light_pdf[k] > 0.0f
                            ? diffuse_factor(R0, mu_light, mu_o[k]) * mu_light *
                                  power_heuristic(light_pdf[k], mis * diffuse_lobe_pdf(mu_light)) / light_pdf[k]
                            : 0.0f;
    }
    // 7. The texels, weighted.
    for (int k = 0; k < n; ++k) {
      RGB& result = out[first + k];
      if (!hit[k]) {
        result = options_.black_background ? RGB::Zero() : environment_.eval(view[k]);
        continue;
      }
      RGB diffuse = RGB::Zero();
      if (lobe_weight[k] > 0.0f) diffuse += lobe_weight[k] * environment_.eval(lobe_at[k]);
      if (light_weight[k] > 0.0f) diffuse += light_weight[k] * environment_.eval(light_at[k]);
      result = Rd[k] * diffuse;
      if (mirror_weight[k] > 0.0f) result += mirror_weight[k] * environment_.eval(mirror_at[k]);
    }
  }
}

}  // namespace glaze
