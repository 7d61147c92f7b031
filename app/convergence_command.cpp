// convergence_command.cpp: `glaze convergence`: error against run time of the path
// tracer and of the analytic sh integrator, measured against one converged reference.
//
// The reference is the path tracer at --ref-spp, rendered as two independent halves:
// their mean is the reference and half their difference measures its own noise, so an
// error can be reported both as measured and beyond that noise (sqrt(e^2 - noise^2):
// the mean squared differences of independent errors add). Times are wall-clock seconds
// of the render alone (all threads); for the sh integrator they include the SH
// projection of the environment for that lmax, which a fresh process pays once.
#include "app/commands.h"
#include "app/plot.h"
#include "app/shared_options.h"
#include "app/timing.h"
#include "renderer/error.h"
#include "renderer/image_error.h"
#include "renderer/path_tracer.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"
#include "renderer/text_file.h"

#include <nlohmann/json.hpp>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <thread>

namespace glaze {
namespace {

struct ConvergenceCommandOptions {
  std::string scene, out;
  CameraChoice camera;
  std::optional<Resolution> resolution;
  std::optional<std::string> reference;  // --ref FILE.exr, instead of rendering it
  float reference_noise = 0.0f;
  long reference_spp = 16384;
  std::optional<long> max_spp;
  uint64_t seed = 0;
  int threads = 0;
  int max_depth = 8;
  EnvironmentOverride environment;
};

constexpr int kShLmax[] = {2, 4, 6, 8, 12};
// Sub-pixel sampling of the sh rows: K x K everywhere, and K x K refined to M x M where
// a pixel's samples disagree (ShIntegratorOptions::refined_supersampling).
struct ShSampling {
  int ss, refined;
  std::string label() const {
    return "ss " + std::to_string(ss) + (refined > 0 ? " refined " + std::to_string(refined) : "");
  }
};
constexpr ShSampling kShSampling[] = {{1, 0}, {2, 0}, {4, 0}, {1, 8}, {2, 8}};
// Baselines of the sh error split: the truncation error of lmax is its difference from
// lmax 32 at the same ss, the anti-aliasing error of ss its difference from ss 8 at the
// same lmax.
constexpr int kSplitLmax = 32, kSplitSupersampling = 8;
constexpr double kTargets[] = {0.01, 0.003};

struct Row {
  std::string integrator, setting;
  int lmax = 0, sampling = 0;       // sh rows: lmax, index in kShSampling
  double projection_seconds = 0.0;  // sh rows: the part of `seconds` that projects the map
  double seconds = 0.0;
  ImageError error;
  double beyond_noise = 0.0;
};

// Time at which the path tracer's error (beyond the reference noise) reaches `target`:
// interpolated on log-log axes between the rows around it, or extrapolated from the last
// row at the Monte-Carlo rate (error ~ time^-1/2) when no row reaches it.
std::pair<double, bool> path_time_to(const std::vector<Row>& rows, double target) {
  const Row* previous = nullptr;
  for (const Row& row : rows) {
    if (row.integrator != "path") continue;
    if (row.beyond_noise <= target) {
      if (!previous || previous->beyond_noise <= row.beyond_noise) return {row.seconds, false};
      const double slope =
          std::log(row.seconds / previous->seconds) / std::log(row.beyond_noise / previous->beyond_noise);
      return {previous->seconds * std::pow(target / previous->beyond_noise, slope), false};
    }
    previous = &row;
  }
  if (!previous) return {NAN, true};
  return {previous->seconds * std::pow(previous->beyond_noise / target, 2.0), true};
}

// The fastest sh setting whose error beyond the reference noise is within `target`.
const Row* fastest_sh_within(const std::vector<Row>& rows, double target) {
  const Row* best = nullptr;
  for (const Row& row : rows)
    if (row.integrator == "sh" && row.beyond_noise <= target && (!best || row.seconds < best->seconds)) best = &row;
  return best;
}

int convergence(const ConvergenceCommandOptions& args) {
  Scene scene = load_scene(args.scene);
  const EnvironmentSpec spec = environment_spec(scene, args.environment);
  const PinholeCamera camera =
      scene.make_camera(scene.camera(choose_camera(scene, args.camera, args.resolution)),
                        args.resolution ? std::optional(args.resolution->pair()) : std::nullopt);
  const Environment environment = make_environment(spec.source, spec.options, spec.width, spec.height);
  const RayTracer ray_tracer(scene);
  const std::vector<uint8_t> mask = interior_mask(ray_tracer, camera);
  const std::filesystem::path out(args.out);
  create_output_folder(out, "output");

  PathTracerOptions path_options;
  path_options.max_depth = args.max_depth;
  RenderOptions options;
  options.seed = args.seed;
  options.threads = args.threads;
  auto render_path = [&](const RenderOptions& passes) {
    return PathIntegrator(scene, ray_tracer, environment, path_options, passes).render(camera);
  };

  // The reference, and its own noise when glaze renders it.
  Image reference;
  double reference_noise = 0.0, reference_seconds = 0.0;
  const long reference_spp = args.reference ? 0 : args.reference_spp;
  const long max_spp = args.max_spp.value_or(reference_spp > 0 ? std::max(1L, reference_spp / 16) : 1024);
  if (reference_spp > 0 && max_spp > reference_spp / 4)
    throw Error("--max-spp " + std::to_string(max_spp) + " is too close to the reference's " +
                std::to_string(reference_spp) +
                " spp: errors against it would mostly measure the reference's own noise; use at most --ref-spp / 4 (" +
                std::to_string(reference_spp / 4) + ") or raise --ref-spp");
  if (args.reference) {
    reference = read_image(*args.reference);
    // Its own relative RMSE, as an earlier run measured it (0: taken as exact).
    reference_noise = args.reference_noise;
    if (!(reference_noise >= 0.0 && reference_noise < 1.0))
      throw Error("--ref-noise must be a relative RMSE in [0, 1)");
    if (reference.width != camera.width || reference.height != camera.height)
      throw Error(*args.reference + ": the reference is " + std::to_string(reference.width) + "x" +
                  std::to_string(reference.height) + " but camera " + camera.name + " renders " +
                  std::to_string(camera.width) + "x" + std::to_string(camera.height) + " (match it with --res)");
  } else {
    RenderOptions half = options;
    half.spp = static_cast<int>(reference_spp / 2);
    half.progress = isatty(STDERR_FILENO);
    std::cerr << "reference: " << reference_spp << " spp in two halves\n";
    half.seed = options.seed + 1000003;
    const IntegratorResult first = render_path(half);
    half.seed = options.seed + 2000003;
    const IntegratorResult second = render_path(half);
    reference = first.image;
    for (size_t i = 0; i < reference.pixels.size(); ++i)
      reference.pixels[i] = 0.5f * (first.image.pixels[i] + second.image.pixels[i]);
    reference_noise = 0.5 * image_error(first.image, second.image, mask).relative_rmse;
    reference_seconds = first.seconds + second.seconds;
    write_image((out / "reference.exr").string(), reference,
                {{"glaze:integrator", "path"},
                 {"glaze:spp", std::to_string(reference_spp)},
                 {"glaze:seconds", std::to_string(reference_seconds)},
                 {"glaze:camera", camera.name}});
  }
  auto beyond_noise = [&](double error) {
    return std::sqrt(std::max(0.0, error * error - reference_noise * reference_noise));
  };

  std::vector<Row> rows;
  for (long spp = 1; spp <= max_spp; spp *= 2) {
    options.spp = static_cast<int>(spp);
    const IntegratorResult result = render_path(options);
    Row row;
    row.integrator = "path";
    row.setting = std::to_string(spp) + " spp";
    row.seconds = result.seconds;
    row.error = image_error(result.image, reference, mask);
    row.beyond_noise = beyond_noise(row.error.relative_rmse);
    rows.push_back(row);
    std::cerr << "path " << spp << " spp: " << row.seconds << " s, relative RMSE " << row.error.relative_rmse << '\n';
  }

  ShIntegratorOptions sh_options;
  sh_options.threads = options.threads;
  auto render_sh_at = [&](int lmax, ShSampling sampling) {
    sh_options.lmax = lmax;
    sh_options.supersampling = sampling.ss;
    sh_options.refined_supersampling = sampling.refined;
    return ShIntegrator(scene, ray_tracer, environment, sh_options).render(camera);
  };
  // The split's baselines, by sampling and by lmax.
  std::map<int, Image> finest_lmax, finest_ss;
  for (size_t s = 0; s < std::size(kShSampling); ++s)
    finest_lmax[int(s)] = render_sh_at(kSplitLmax, kShSampling[s]).image;
  for (int lmax : kShLmax) finest_ss[lmax] = render_sh_at(lmax, {kSplitSupersampling, 0}).image;
  std::vector<std::string> split_lines;
  for (int lmax : kShLmax) {
    const auto projection_start = std::chrono::steady_clock::now();
    sh_project_latlong(environment.map(), environment.local_to_world(), lmax);  // what environment.sh() pays once
    const double projection_seconds = seconds_since(projection_start);
    for (size_t s = 0; s < std::size(kShSampling); ++s) {
      const IntegratorResult sh = render_sh_at(lmax, kShSampling[s]);
      const Image& image = sh.image;
      Row row;
      row.integrator = "sh";
      row.setting = "lmax " + std::to_string(lmax) + " " + kShSampling[s].label();
      row.lmax = lmax;
      row.sampling = int(s);
      row.seconds = projection_seconds + sh.seconds;
      row.projection_seconds = projection_seconds;
      row.error = image_error(image, reference, mask);
      row.beyond_noise = beyond_noise(row.error.relative_rmse);
      rows.push_back(row);
      const double truncation = image_error(image, finest_lmax[int(s)], mask).relative_rmse;
      const double antialiasing = image_error(image, finest_ss[lmax], mask).relative_rmse;
      char line[160];
      std::snprintf(line, sizeof line, "%d,%d,%d,%.6g,%.6g,%.8f", lmax, kShSampling[s].ss, kShSampling[s].refined,
                    truncation, antialiasing, sh_kernel_energy_fraction(lmax));
      split_lines.push_back(line);
    }
  }

  // convergence.csv, split.csv, summary.json, convergence.png.
  {
    std::ofstream csv(out / "convergence.csv");
    csv << "integrator,setting,seconds,relative_rmse,max_error,relative_rmse_beyond_reference_noise\n";
    for (const Row& row : rows)
      csv << row.integrator << ',' << row.setting << ',' << row.seconds << ',' << row.error.relative_rmse << ','
          << row.error.max_error << ',' << row.beyond_noise << '\n';
    std::ofstream split(out / "split.csv");
    split << "lmax,ss,refined_ss,truncation_rmse,antialiasing_rmse,kernel_energy_kept\n";
    for (const std::string& line : split_lines) split << line << '\n';
    if (!csv || !split) throw Error(out.string() + ": could not write the CSV files");
  }
  nlohmann::json summary = {
      {"scene", scene.path},
      {"camera", camera.name},
      {"resolution", {camera.width, camera.height}},
      {"interior_pixels", rows.front().error.pixels},
      {"reference", {{"spp", reference_spp}, {"seconds", reference_seconds}, {"relative_noise", reference_noise}}}};
  std::printf("%s, camera %s, %dx%d, %zu interior pixels; reference %ld spp (relative noise %.3g%%)\n",
              scene.path.c_str(), camera.name.c_str(), camera.width, camera.height, rows.front().error.pixels,
              reference_spp, 100 * reference_noise);
  for (double target : kTargets) {
    char key[16];
    std::snprintf(key, sizeof key, "%g", target);
    // A reference whose own noise is not well below the target cannot tell whether a
    // method reaches it: say so instead of reporting a time.
    if (reference_noise > 0.5 * target) {
      summary["time_to"][key] = {{"resolvable", false}, {"reference_noise", reference_noise}};
      std::printf("relative RMSE %.2g%%: not resolvable, the reference's own noise is %.3g%% (raise --ref-spp)\n",
                  100 * target, 100 * reference_noise);
      continue;
    }
    const auto [path_seconds, extrapolated] = path_time_to(rows, target);
    const Row* sh = fastest_sh_within(rows, target);
    nlohmann::json entry = {{"path_seconds", path_seconds}, {"path_extrapolated", extrapolated}};
    std::printf("relative RMSE %.2g%%: path tracer %.3g s%s", 100 * target, path_seconds,
                extrapolated ? " (extrapolated)" : "");
    if (sh) {
      entry["sh_seconds"] = sh->seconds;
      entry["sh_setting"] = sh->setting;
      entry["sh_projection_seconds"] = sh->projection_seconds;
      entry["speedup"] = path_seconds / sh->seconds;
      // A renderer keeps the projection (once per environment and lmax): the frame's own
      // time is what every further frame of the same lighting costs.
      entry["speedup_projection_cached"] = path_seconds / (sh->seconds - sh->projection_seconds);
      std::printf(", sh %.3g s (%s): %.0fx faster; %.0fx with the SH projection (%.3g s) cached\n", sh->seconds,
                  sh->setting.c_str(), path_seconds / sh->seconds,
                  path_seconds / (sh->seconds - sh->projection_seconds), sh->projection_seconds);
    } else {
      entry["sh_seconds"] = nullptr;
      std::printf(", sh: no setting reaches it\n");
    }
    summary["time_to"][key] = entry;
  }
  {
    std::ofstream file(out / "summary.json");
    file << summary.dump(2) << '\n';
    if (!file) throw Error((out / "summary.json").string() + ": could not be written");
  }

  LogLogPlot plot{"Relative RMSE against run time: " + std::filesystem::path(scene.path).filename().string() + ", " +
                      std::to_string(camera.width) + "x" + std::to_string(camera.height),
                  "seconds (" +
                      std::to_string(options.threads > 0 ? options.threads : int(std::thread::hardware_concurrency())) +
                      " threads)",
                  "relative RMSE over the object",
                  {},
                  {}};
  PlotSeries path_series{"path tracer", {}, {}, RGB(0.1f, 0.3f, 0.8f)};
  for (const Row& row : rows)
    if (row.integrator == "path")
      path_series.x.push_back(row.seconds), path_series.y.push_back(row.error.relative_rmse);
  plot.series.push_back(path_series);
  const RGB sh_colours[] = {RGB(0.9f, 0.5f, 0.1f), RGB(0.8f, 0.1f, 0.1f), RGB(0.2f, 0.6f, 0.2f), RGB(0.6f, 0.2f, 0.7f),
                            RGB(0.1f, 0.6f, 0.7f)};
  static_assert(std::size(sh_colours) == std::size(kShSampling));

  for (size_t k = 0; k < std::size(kShSampling); ++k) {
    PlotSeries series{"sh, " + kShSampling[k].label() + ", lmax 2..12", {}, {}, sh_colours[k]};
    for (const Row& row : rows)
      if (row.integrator == "sh" && row.sampling == int(k))
        series.x.push_back(row.seconds), series.y.push_back(row.error.relative_rmse);
    plot.series.push_back(series);
  }
  plot.lines = {{0.01, "1%"}, {0.003, "0.3%"}};
  if (reference_noise > 0.0) plot.lines.push_back({reference_noise, "reference noise"});
  write_loglog_plot((out / "convergence.png").string(), plot);
  std::cerr << "wrote " << (out / "convergence.csv").string() << ", split.csv, summary.json, convergence.png\n";
  return 0;
}

}  // namespace

CommandRun declare_convergence(CLI::App& app) {
  auto args = std::make_shared<ConvergenceCommandOptions>();
  app.description("error against run time of the path tracer and the sh integrator, against one reference");
  add_scene(app, args->scene);
  add_text(app, "--out DIR", args->out, "where the study goes")->required();
  add_camera_choice(app, args->camera, "which camera, by its node's or its glTF camera's name (default: the first)");
  add_film_resolution(app, args->resolution);
  CLI::Option* reference_spp =
      add_integer(app, "--ref-spp N", args->reference_spp, 2, 1 << 24,
                  "path-trace the reference at N spp, in two halves whose difference measures its noise");
  CLI::Option* reference = add_text(app, "--ref FILE.exr", args->reference, "use this reference instead");
  reference->excludes(reference_spp);
  add_real(app, "--ref-noise X", args->reference_noise,
           "the relative noise of --ref, as summary.json of the run that made it says (in [0, 1))")
      ->needs(reference);
  add_integer(app, "--max-spp N", args->max_spp, 1, 1 << 20,
              "path tracer at 1, 2, 4, ... N spp (default ref-spp / 16)");
  add_seed(app, args->seed, "random seed of the path tracer");
  add_threads(app, args->threads);
  add_max_depth(app, args->max_depth);
  add_environment_override(app, args->environment);
  app.footer(
      "Writes DIR/convergence.csv (seconds, relative RMSE, max error, RMSE beyond the reference noise),\n"
      "split.csv (sh error from SH truncation and from anti-aliasing, kernel energy kept per lmax),\n"
      "summary.json (time to 1% and 0.3%) and convergence.png (log-log plot). sh runs lmax 2, 4, 6, 8, 12\n"
      "x ss 1, 2, 4, and ss 1 and 2 refined to 8 (--ss-refine 8).");
  return [args] { return convergence(*args); };
}

}  // namespace glaze
