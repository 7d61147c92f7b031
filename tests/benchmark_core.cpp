// Benchmarks of the shared core (Google Benchmark). Run: build/tests/glaze_bench
// Reported in issue notes: SH projection of a 1024x512 map at lmax 4, 10M environment
// samples on all cores, a 512x512 frame of the sh integrator.
#include "renderer/environment.h"
#include "renderer/material.h"
#include "renderer/procedural_environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"
#include "renderer/sh.h"

#include <benchmark/benchmark.h>
#include <array>
#include <tbb/parallel_for.h>

namespace glaze {
namespace {

const Image& office_map() {
  static const Image map = make_procedural_environment("office", 1024, 512);
  return map;
}

void BM_ShProjection1024x512(benchmark::State& state) {
  const int lmax = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(sh_project_latlong(office_map(), Mat3::Identity(), lmax));
  state.SetItemsProcessed(state.iterations() * 1024 * 512);
}
BENCHMARK(BM_ShProjection1024x512)->Arg(4)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond)->UseRealTime();

// 10M samples per iteration, split over TBB tasks with one generator per chunk.
void BM_EnvironmentSample10M(benchmark::State& state) {
  const Environment env(office_map(), {});
  env.sample(Vec2(0.5f, 0.5f));  // build the distribution outside the timing
  constexpr int kSamples = 10'000'000, kChunk = 1 << 16;
  for (auto _ : state) {
    tbb::parallel_for(0, (kSamples + kChunk - 1) / kChunk, [&](int chunk) {
      Pcg32 rng(1, chunk);
      float sum = 0.0f;
      const int end = std::min(kSamples, (chunk + 1) * kChunk);
      for (int k = chunk * kChunk; k < end; ++k) sum += env.sample(Vec2(rng.next_float(), rng.next_float())).pdf;
      benchmark::DoNotOptimize(sum);
    });
  }
  state.SetItemsProcessed(state.iterations() * int64_t(kSamples));
}
BENCHMARK(BM_EnvironmentSample10M)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same through the batched interface the path tracer uses (16 at a time).
void BM_EnvironmentSampleBatched10M(benchmark::State& state) {
  const Environment env(office_map(), {});
  env.sample(Vec2(0.5f, 0.5f));
  constexpr int kSamples = 10'000'000, kChunk = 1 << 16, kBatch = 16;
  for (auto _ : state) {
    tbb::parallel_for(0, (kSamples + kChunk - 1) / kChunk, [&](int chunk) {
      Pcg32 rng(1, chunk);
      std::array<Vec2, kBatch> u;
      std::array<EnvironmentSample, kBatch> out;
      float sum = 0.0f;
      const int end = std::min(kSamples, (chunk + 1) * kChunk);
      for (int k = chunk * kChunk; k < end; k += kBatch) {
        for (Vec2& v : u) v = Vec2(rng.next_float(), rng.next_float());
        env.sample(u, out);
        for (const EnvironmentSample& s : out) sum += s.pdf;
      }
      benchmark::DoNotOptimize(sum);
    });
  }
  state.SetItemsProcessed(state.iterations() * int64_t(kSamples));
}
BENCHMARK(BM_EnvironmentSampleBatched10M)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_EnvironmentEval(benchmark::State& state) {
  const Environment env(office_map(), {});
  Pcg32 rng(3);
  for (auto _ : state) {
    const Vec3 w = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    benchmark::DoNotOptimize(env.eval(w.normalized()));
  }
}
BENCHMARK(BM_EnvironmentEval);

void BM_ShDiffuseSum(benchmark::State& state) {
  const Environment env(office_map(), {});
  const ShDiffuseSum sum(env.sh(static_cast<int>(state.range(0))));
  Pcg32 rng(4);
  for (auto _ : state) {
    const Vec3 n = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f).normalized();
    benchmark::DoNotOptimize(sum(n));
  }
}
BENCHMARK(BM_ShDiffuseSum)->Arg(4)->Arg(8);

void BM_MaterialSample(benchmark::State& state) {
  const PolishedMaterial material(0.0452f, RGB(0.9765f, 0.0186f, 0.0f));
  const Vec3 wo = Vec3(0.3f, 0.2f, 0.9f).normalized();
  Pcg32 rng(5);
  for (auto _ : state)
    benchmark::DoNotOptimize(material.sample(wo, rng.next_float(), Vec2(rng.next_float(), rng.next_float())));
}
BENCHMARK(BM_MaterialSample);

// The issue-4 figure: a 512x512 frame of the red sphere (the scene's first camera) by
// the sh integrator at lmax 4, ss 2, on all cores; the SH projection is cached, as it is
// for every frame after the first.
void BM_ShIntegratorFrame512(benchmark::State& state) {
  const Scene scene = load_scene(std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf");
  const Environment env(office_map(), {});
  const RayTracer tracer(scene);
  const PinholeCamera camera = scene.make_camera(scene.cameras.front(), std::pair(512, 512));
  const ShIntegratorOptions options{4, 2, true, 0};
  render_sh(scene, tracer, env, camera, options);
  for (auto _ : state) benchmark::DoNotOptimize(render_sh(scene, tracer, env, camera, options));
  state.SetItemsProcessed(state.iterations() * 512 * 512 * 4);
}
BENCHMARK(BM_ShIntegratorFrame512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace glaze

BENCHMARK_MAIN();
