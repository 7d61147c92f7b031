// Benchmarks of the shared core (Google Benchmark). Run: build/tests/glaze_bench
// Reported in docs/performance.md: SH projection of a 1024x512 map at lmax 4, 10M environment
// samples on all cores, a 512x512 frame of the sh integrator, the invert-fit pipeline, the
// path tracer on meshes (the still life, a 25k-triangle sphere), the HDR merge of a
// seven-exposure 24-megapixel bracket (decoding, alignment check and merge apart), a
// sphere located from its outline in three 1536x1024 views.
#include "gltf_builder.h"
#include "inverse/photos/bracket_alignment.h"
#include "inverse/photos/hdr_merge.h"
#include "inverse/photos/mirror_ball_probe.h"
#include "inverse/photos/sphere_outline.h"
#include "photo_bracket.h"
#include "inverse/capture_scene.h"
#include "inverse/joint_fit.h"
#include "inverse/material_fit.h"
#include "inverse/noise_model.h"
#include "inverse/samples.h"
#include "inverse/texture_fit.h"
#include "renderer/environment.h"
#include "renderer/material.h"
#include "renderer/path_tracer.h"
#include "renderer/procedural_environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"
#include "renderer/sh.h"

#include <benchmark/benchmark.h>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <tbb/parallel_for.h>
#include <unistd.h>

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
  Pcg32 warm_up;
  env.sample(warm_up);  // build the alias table outside the timing
  constexpr int kSamples = 10'000'000, kChunk = 1 << 16;
  for (auto _ : state) {
    tbb::parallel_for(0, (kSamples + kChunk - 1) / kChunk, [&](int chunk) {
      Pcg32 rng(1, chunk);
      float sum = 0.0f;
      const int end = std::min(kSamples, (chunk + 1) * kChunk);
      for (int k = chunk * kChunk; k < end; ++k) sum += env.sample(rng).pdf;
      benchmark::DoNotOptimize(sum);
    });
  }
  state.SetItemsProcessed(state.iterations() * int64_t(kSamples));
}
BENCHMARK(BM_EnvironmentSample10M)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same through the batched interface the path tracer uses (16 at a time).
void BM_EnvironmentSampleBatched10M(benchmark::State& state) {
  const Environment env(office_map(), {});
  Pcg32 warm_up;
  env.sample(warm_up);
  constexpr int kSamples = 10'000'000, kChunk = 1 << 16, kBatch = 16;
  for (auto _ : state) {
    tbb::parallel_for(0, (kSamples + kChunk - 1) / kChunk, [&](int chunk) {
      Pcg32 rng(1, chunk);
      std::array<EnvironmentSample, kBatch> out;
      float sum = 0.0f;
      const int end = std::min(kSamples, (chunk + 1) * kChunk);
      for (int k = chunk * kChunk; k < end; k += kBatch) {
        env.sample(rng, out);
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
BENCHMARK(BM_ShDiffuseSum)->Arg(4)->Arg(8)->Arg(16);

// The same sums for a batch of 1024 normals at once (SIMD lanes of normals above lmax 4).
void BM_ShDiffuseSumLanes(benchmark::State& state) {
  const Environment env(office_map(), {});
  const ShDiffuseSum sum(env.sh(static_cast<int>(state.range(0))));
  Pcg32 rng(4);
  std::vector<Vec3> normals(1024);
  for (Vec3& n : normals)
    n = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f).normalized();
  std::vector<RGB> out(normals.size());
  for (auto _ : state) {
    sum(normals, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(normals.size()));
}
BENCHMARK(BM_ShDiffuseSumLanes)->Arg(4)->Arg(8)->Arg(16);

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

// The same frame at ss 2 refined to 8 x 8 where a pixel's 2 x 2 samples disagree
// (`glaze convergence` measures what that buys in error).
void BM_ShIntegratorFrame512Refined(benchmark::State& state) {
  const Scene scene = load_scene(std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf");
  const Environment env(office_map(), {});
  const RayTracer tracer(scene);
  const PinholeCamera camera = scene.make_camera(scene.cameras.front(), std::pair(512, 512));
  ShIntegratorOptions options{4, 2, true, 0};
  options.refined_supersampling = 8;
  render_sh(scene, tracer, env, camera, options);
  for (auto _ : state) benchmark::DoNotOptimize(render_sh(scene, tracer, env, camera, options));
}
BENCHMARK(BM_ShIntegratorFrame512Refined)->Unit(benchmark::kMillisecond)->UseRealTime();

// The issue-41 figures: the path tracer (default options, depth 8) on meshes under the
// procedural office, on all cores, as samples per second: the still life (a ground,
// a cube, a mesh sphere and an analytic sphere that shadow each other), and a UV sphere
// of 25,344 triangles alone. The sphere's glTF is written to the temporary directory,
// where the Mitsuba comparison (docs/performance.md) takes it from.
std::string mesh_sphere_scene() {
  using namespace testing;
  constexpr int kStacks = 100, kSlices = 128;  // 2 * kSlices * (kStacks - 1) triangles
  std::vector<float> positions, uvs;
  std::vector<uint16_t> indices;
  for (int i = 0; i <= kStacks; ++i) {
    const double theta = M_PI * i / kStacks;
    for (int j = 0; j <= kSlices; ++j) {
      const double phi = 2.0 * M_PI * j / kSlices;
      for (const double c : {std::sin(theta) * std::sin(phi), std::cos(theta), std::sin(theta) * std::cos(phi)})
        positions.push_back(float(c));
      uvs.insert(uvs.end(), {float(j) / kSlices, float(i) / kStacks});
    }
  }
  for (int i = 0; i < kStacks; ++i) {
    for (int j = 0; j < kSlices; ++j) {
      const int a = i * (kSlices + 1) + j, b = a + kSlices + 1;  // b below a
      if (i > 0) indices.insert(indices.end(), {uint16_t(a), uint16_t(b), uint16_t(a + 1)});
      if (i < kStacks - 1) indices.insert(indices.end(), {uint16_t(a + 1), uint16_t(b), uint16_t(b + 1)});
    }
  }
  GltfBuffer buffer;
  const int position = buffer.floats(positions, 3), normal = buffer.floats(positions, 3), uv = buffer.floats(uvs, 2);
  const int index = buffer.indices(indices);
  json camera_node = {{"camera", 0}, {"translation", {0.0, 0.0, 4.0}}};
  json gltf = gltf_document({{{"mesh", 0}}, camera_node}, {0, 1});
  gltf["meshes"] = json::array(
      {{{"primitives", json::array({{{"attributes", {{"POSITION", position}, {"NORMAL", normal}, {"TEXCOORD_0", uv}}},
                                     {"indices", index},
                                     {"material", 0}}})}}});
  gltf["materials"] =
      json::array({quiet_material({{"extras", {{"glaze", {{"R0", 0.0452}, {"Rd", {0.9765, 0.0186, 0.0}}}}}}})});
  gltf["cameras"] =
      json::array({{{"type", "perspective"},
                    {"perspective", {{"yfov", 30.0 * M_PI / 180.0}, {"aspectRatio", 1.0}, {"znear", 0.1}}}}});
  gltf["scenes"][0]["extras"] = {
      {"glaze", {{"environment", {{"procedural", "office"}}}, {"film", {{"width", 256}, {"height", 256}}}}}};
  buffer.into(gltf);
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "glaze_bench_mesh_sphere";
  std::filesystem::create_directories(folder);
  const std::string path = (folder / "mesh_sphere.gltf").string();
  std::ofstream(path) << gltf.dump();
  return path;
}

void path_trace_benchmark(benchmark::State& state, const std::string& path) {
  const Scene scene = load_scene(path);
  const EnvironmentSpec& spec = *scene.environment;
  const Environment environment = make_environment(spec.source, spec.options, spec.width, spec.height);
  const RayTracer tracer(scene);
  const PathTracer path_tracer(scene, tracer, environment, {});
  const PinholeCamera camera = scene.make_camera(scene.cameras.front(), std::nullopt);
  RenderOptions options;
  options.spp = 4;
  Pcg32 warm_up;
  environment.sample(warm_up);  // build the alias table outside the timing
  for (auto _ : state) benchmark::DoNotOptimize(render(path_tracer, camera, options).image.pixels.data());
  state.SetItemsProcessed(state.iterations() * int64_t(camera.width) * camera.height * options.spp);
}

void BM_PathTraceStillLife(benchmark::State& state) {
  path_trace_benchmark(state, std::string(GLAZE_SOURCE_DIR) + "/scenes/still_life_office.gltf");
}
BENCHMARK(BM_PathTraceStillLife)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PathTraceMeshSphere25k(benchmark::State& state) { path_trace_benchmark(state, mesh_sphere_scene()); }
BENCHMARK(BM_PathTraceMeshSphere25k)->Unit(benchmark::kMillisecond)->UseRealTime();

// The issue-5 figures: the fit pipeline of `invert-fit` (samples, shading terms, the
// nested fit; not the re-renders) on sh-rendered 512x512 captures made once by the glaze
// command: three views of the red sphere (homogeneous), four of the textured sphere at
// 256x128 texels (texture). The per-stage times are in fit.json's stage_seconds.
std::string benchmark_captures(const std::string& scene, const std::string& holdout) {
  const std::string folder = (std::filesystem::temp_directory_path() / ("glaze_bench_" + scene)).string();
  if (!std::filesystem::exists(folder + "/transforms.json")) {
    const std::string command = std::string(GLAZE_EXECUTABLE) + " render " + GLAZE_SOURCE_DIR + "/scenes/" + scene +
                                ".gltf --integrator sh --res 512x512 --holdout " + holdout + " --captures " + folder +
                                " 2>/dev/null";
    if (std::system(command.c_str()) != 0) throw std::runtime_error("could not render the benchmark captures");
  }
  return folder;
}

void fit_benchmark(benchmark::State& state, const std::string& folder, int texels_wide) {
  const CaptureSet captures = read_transforms(folder);
  const Environment environment = make_environment(capture_environment(captures)->source);
  environment.sh(16);  // the projection is a per-environment cost, measured on its own above
  const Scene scene = capture_object_scene(captures, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  const RayTracer tracer(scene);
  size_t samples = 0;
  for (auto _ : state) {
    const SampleSet set = collect_samples(captures, tracer, scene, {});
    const std::vector<ShadingTerms> terms = shading_terms(set, captures, tracer, environment, 16, 4);
    const MaterialFit homogeneous = fit_material(set.samples, terms, {}, 1, {}, {});
    if (texels_wide > 0)
      benchmark::DoNotOptimize(fit_texture(set.samples, terms, texels_wide, texels_wide / 2, homogeneous, {}));
    samples = set.samples.size();
  }
  state.counters["samples"] = double(samples);
}

void BM_HomogeneousFit3x512(benchmark::State& state) {
  fit_benchmark(state, benchmark_captures("red_sphere_office", "novel_0,novel_1"), 0);
}
BENCHMARK(BM_HomogeneousFit3x512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_TextureFit4x512(benchmark::State& state) {
  fit_benchmark(state, benchmark_captures("textured_sphere_office", "novel_0,novel_1"), 256);
}
BENCHMARK(BM_TextureFit4x512)->Unit(benchmark::kMillisecond)->UseRealTime();

// The issue-6 figure for lighting recovery: samples, shading rows and the lighting (L_lm
// and the 256x128 map) of the white sphere at its known material, on three sh-rendered
// 512x512 views: one fit for these band-limited captures, each pixel modelled by the
// 2 x 2 rays the sh integrator took; as for photographs and path-traced captures, two
// fits (diffuse bands to 16 predicted from the first, lighting_fit.h), the data-driven
// noise model and pixels of invert-fit's default 4 x 4 rays.
void lighting_fit_benchmark(benchmark::State& state, int diffuse_lmax) {
  const CaptureSet captures = read_transforms(benchmark_captures("white_sphere_office", "novel_0,novel_1"));
  const Scene scene = capture_object_scene(captures, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  const RayTracer tracer(scene);
  const PolishedMaterial& material = captures.material->material;
  const bool photographs = diffuse_lmax > 4;
  const int footprint = photographs ? 4 : captures.renderer->supersampling;
  for (auto _ : state) {
    const SampleSet set = collect_samples(captures, tracer, scene, {});
    LightingData data = gather_lighting_data(set, captures, tracer, 4, footprint, /*noise_free=*/!photographs);
    benchmark::DoNotOptimize(fit_lighting_full_band(data, set, diffuse_lmax, material.R0(), material.Rd(), {}));
  }
}
// The captures' noise model alone (inverse/noise_model.h), on the same three views read as
// photographs: each sample's window median, the lighting fit's (and the joint fit's)
// largest single cost on full-band captures.
void BM_NoiseModel3x512(benchmark::State& state) {
  const CaptureSet captures = read_transforms(benchmark_captures("white_sphere_office", "novel_0,novel_1"));
  const Scene scene = capture_object_scene(captures, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  const RayTracer tracer(scene);
  const SampleSet set = collect_samples(captures, tracer, scene, {});
  std::vector<RGB> observed;
  for (const Sample& s : set.samples) observed.push_back(s.observed);
  for (auto _ : state) benchmark::DoNotOptimize(estimate_noise(observed, set, /*noise_free=*/false));
  state.counters["samples"] = double(set.samples.size());
}
BENCHMARK(BM_NoiseModel3x512)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_LightingFit3x512(benchmark::State& state) { lighting_fit_benchmark(state, 4); }
BENCHMARK(BM_LightingFit3x512)->Unit(benchmark::kMillisecond)->UseRealTime();
void BM_LightingFitPhotographs3x512(benchmark::State& state) { lighting_fit_benchmark(state, 16); }
BENCHMARK(BM_LightingFitPhotographs3x512)->Unit(benchmark::kMillisecond)->UseRealTime();

// The issue-6 figure: the joint fit (samples, shading rows, the views' pairing, R0, Rd and
// the lighting at them; not the re-renders) on three sh-rendered 512x512 views of the
// white sphere, as `invert-fit --mode joint` runs it on them: one pass for these
// band-limited captures; passes until R0 and Rd settle (diffuse bands to 16 predicted
// from the pass before, joint_fit.h) as for photographs and path-traced captures, whose
// cost depends little on what the bands hold.
void joint_fit_benchmark(benchmark::State& state, bool band_limited) {
  const CaptureSet captures = read_transforms(benchmark_captures("white_sphere_office", "novel_0,novel_1"));
  const Scene scene = capture_object_scene(captures, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  const RayTracer tracer(scene);
  LightingFitOptions options;
  JointFitOptions joint;
  joint.band_limited_diffuse = band_limited;
  const int footprint = captures.renderer->supersampling;
  for (auto _ : state) {
    const SampleSet set = collect_samples(captures, tracer, scene, {});
    // Band-limited: as noise-free captures; the other with the data-driven noise model, as
    // for photographs.
    LightingData data = gather_lighting_data(set, captures, tracer, 4, footprint, /*noise_free=*/band_limited);
    benchmark::DoNotOptimize(fit_joint_full_band(data, set, 16, options, joint));
  }
}
void BM_JointFit3x512(benchmark::State& state) { joint_fit_benchmark(state, true); }
BENCHMARK(BM_JointFit3x512)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
void BM_JointFitPasses3x512(benchmark::State& state) { joint_fit_benchmark(state, false); }
BENCHMARK(BM_JointFitPasses3x512)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// A seven-exposure bracket of 6000x4000 JPEGs (the synthetic scene of the HDR tests,
// 1/4096 s to 1 s), written once to a temporary folder that is removed at exit.
struct BracketFiles {
  std::filesystem::path folder;
  Bracket bracket;
  BracketFiles() {
    folder = std::filesystem::temp_directory_path() / ("glaze_bench_bracket_" + std::to_string(getpid()));
    std::filesystem::create_directories(folder);
    const testing::SyntheticScene scene = testing::synthetic_scene(6000, 4000);
    for (int j = 0; j < 7; ++j) {
      const double seconds = std::pow(4.0, j - 6);
      const auto file = folder / ("exposure_" + std::to_string(j) + ".jpg");
      // EXIF times 4.096 times the true ones (OpenImageIO 2.4 writes 1/4096 s as inf).
      testing::write_photo(file.string(), testing::photograph(scene, seconds, 1, /*noise=*/false),
                           {{"ExposureTime", float(0.001 * std::pow(4.0, j))}});
    }
    bracket = find_bracket(folder);
  }
  ~BracketFiles() {
    std::error_code ec;
    std::filesystem::remove_all(folder, ec);
  }
};
const BracketFiles& bracket_files() {
  static const BracketFiles files;
  return files;
}
const BracketPhotos& decoded_bracket() {
  static const BracketPhotos photos = read_bracket(bracket_files().bracket);
  return photos;
}

void BM_DecodeBracket24MP(benchmark::State& state) {
  const Bracket& bracket = bracket_files().bracket;
  for (auto _ : state) benchmark::DoNotOptimize(read_bracket(bracket));
  state.SetItemsProcessed(state.iterations() * 7 * 24'000'000);
}
BENCHMARK(BM_DecodeBracket24MP)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ResponseFromBracket24MP(benchmark::State& state) {
  const BracketPhotos& photos = decoded_bracket();
  for (auto _ : state) {
    const ResponseSamples samples = sample_bracket(photos);
    benchmark::DoNotOptimize(recover_response({&samples, 1}));
  }
}
BENCHMARK(BM_ResponseFromBracket24MP)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_AlignBracket24MP(benchmark::State& state) {
  const BracketPhotos& photos = decoded_bracket();
  const ResponseSamples samples = sample_bracket(photos);
  const CameraResponse response = recover_response({&samples, 1});
  for (auto _ : state) benchmark::DoNotOptimize(bracket_shifts(photos, response));
}
BENCHMARK(BM_AlignBracket24MP)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MergeBracket24MP(benchmark::State& state) {
  const BracketPhotos& photos = decoded_bracket();
  const ResponseSamples samples = sample_bracket(photos);
  const CameraResponse response = recover_response({&samples, 1});
  for (auto _ : state) benchmark::DoNotOptimize(merge_bracket(photos, response));
  state.SetItemsProcessed(state.iterations() * 7 * 24'000'000);
}
BENCHMARK(BM_MergeBracket24MP)->Unit(benchmark::kMillisecond)->UseRealTime();

// The light probe at its default 256x128 from three views of a 5 cm ball 0.5 m away. Its
// cost is the map's directions times the views (inverse sampling): the photos' size does
// not enter, so they are plain grey.
void BM_MirrorBallProbe256x128(benchmark::State& state) {
  const MirrorBall ball{Vec3d(0.1, 0.08, 0.07), 0.05};
  std::vector<ProbeView> views;
  for (double azimuth : {-60.0, 60.0, 180.0}) {
    const double a = azimuth * kPiD / 180.0, e = kPiD / 6.0;
    const Vec3d origin = ball.center + 0.5 * Vec3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
    const Vec3d forward = (ball.center - origin).normalized(), right = forward.cross(Vec3d::UnitZ()).normalized();
    Eigen::Affine3f pose = Eigen::Affine3f::Identity();
    pose.linear() << right.cast<float>(), right.cross(forward).cast<float>(), -forward.cast<float>();
    pose.translation() = origin.cast<float>();
    ProbeView view;
    view.name = "probe_" + std::to_string(views.size());
    view.camera = PinholeCamera::from_vertical_fov(view.name, pose, 0.3f, 1920, 1080);
    view.radiance = Image(1920, 1080);
    std::fill(view.radiance.pixels.begin(), view.radiance.pixels.end(), 0.5f);
    views.push_back(std::move(view));
  }
  for (auto _ : state) benchmark::DoNotOptimize(build_mirror_ball_probe(views, ball));
  state.SetItemsProcessed(state.iterations() * 256 * 128 * 3);
}
BENCHMARK(BM_MirrorBallProbe256x128)->Unit(benchmark::kMillisecond)->UseRealTime();

// A 5 cm sphere seen from 0.5 m at 30 degrees elevation by three 1536 x 1024 cameras
// (fl 1500 px, k1 -0.1) 120 degrees apart, rendered once by the sh integrator under the
// office turned +Y to +Z (the board's frame), then located from its outline; the
// counters say how far from the truth.
void BM_LocateSphere3x1536(benchmark::State& state) {
  static const std::vector<SphereView> views = [] {
    const Vec3 center(0.03f, -0.02f, 0.05f);
    Scene scene;
    scene.path = "sphere-outline-benchmark";
    scene.materials.push_back({"coated", 0.04f, RGB(0.8f, 0.1f, 0.1f), -1});
    scene.spheres.push_back({"ball", center, 0.05f, 0, Mat3::Identity()});
    const RayTracer tracer(scene);
    EnvironmentOptions options;
    options.to_world = Eigen::AngleAxisf(kPi / 2, Vec3::UnitX()).toRotationMatrix();
    const Environment environment(office_map(), options);
    std::vector<SphereView> result;
    for (int v = 0; v < 3; ++v) {
      const float a = (20.0f + 120.0f * v) * kPi / 180, e = 30.0f * kPi / 180;
      const Vec3 eye = center + 0.5f * Vec3(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      const Vec3 forward = (center - eye).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
      SphereView view;
      view.name = "view_00" + std::to_string(v);
      view.camera.camera_to_world.linear() << right, right.cross(forward), -forward;
      view.camera.camera_to_world.translation() = eye;
      view.camera.width = 1536, view.camera.height = 1024;
      view.camera.fl_x = view.camera.fl_y = 1500.0f;
      view.camera.cx = 768.0f, view.camera.cy = 512.0f;
      view.camera.distortion = {LensDistortion::Model::opencv, -0.1, 0.01, 0.0, 0.0, 0.0, 0.0};
      view.image = render_sh(scene, tracer, environment, view.camera, {4, 2, false, 0});
      result.push_back(std::move(view));
    }
    return result;
  }();
  SphereFit fit;
  for (auto _ : state) fit = locate_sphere(views);
  state.counters["centre_error_mm"] = 1e3 * (fit.center - Vec3d(0.03, -0.02, 0.05)).norm();
  state.counters["radius_error_pct"] = 100.0 * (fit.radius / 0.05 - 1.0);
}
BENCHMARK(BM_LocateSphere3x1536)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace glaze

BENCHMARK_MAIN();
