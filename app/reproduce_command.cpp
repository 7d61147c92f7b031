// reproduce_command.cpp: `glaze reproduce`, the paper's experiments end to end on
// scenes/ (Nielsen and Brodersen 2004, Table 2, Figures 5-9, Table 3), with a report.
//
// Each experiment runs the commands a user would (render --captures, invert-fit) in
// OUT/captures and OUT/fits, so that every number in the report can be re-derived from
// files on disk. Per lighting (office and blue-room, and two real maps when
// ../shared/data/envmaps holds them):
//   - path-traced captures of the red, white and textured spheres (input and held-out
//     views);
//   - Table 2: invert-fit --mode material (homogeneous spheres), --mode texture
//     (textured sphere), known lighting; Figure 5: the textures; Figure 6: the held-out
//     views re-rendered with the recovered materials;
//   - Figure 8: --mode lighting (known material); Figure 9 and Table 3: --mode joint.
// Across lightings, Figure 7: each recovered material rendered in every other lighting
// against the true appearance there, for the path-traced RGB captures and for captures
// of a spectral camera (inverse/pseudo_brdf.h), which is where the paper's colour shift
// comes from. Then `glaze convergence` on the red sphere in the office for the
// error-against-run-time plot. OUT/results.json holds every number; OUT/report.md puts
// them beside the figures (OUT/figures/*.png).
#include "app/commands.h"
#include "app/figure.h"
#include "app/shared_options.h"
#include "app/timing.h"
#include "inverse/fit_diagnostics.h"
#include "inverse/pseudo_brdf.h"
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/image_error.h"
#include "renderer/json_input.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"
#include "renderer/text_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>

namespace glaze {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Lighting {
  std::string name;          // as the report names it
  std::string scene_suffix;  // which scenes/*_sphere_SUFFIX.gltf (the real maps use the office ones)
  std::string env;           // --env override, or empty for the scene's own
};

const char* const kHomogeneous[] = {"red", "white"};

using Size = std::pair<int, int>;  // width, height

// "WxH", as the commands take it.
std::string size_text(const Size& size) { return std::to_string(size.first) + "x" + std::to_string(size.second); }

struct Settings {
  fs::path out, scenes;
  Size resolution, texture_resolution, lighting_resolution;
  int spp = 256;
  std::string seed = "0";  // of the captures' path tracer
  int transfer_lmax = 16;
  std::vector<Lighting> lightings;
  std::string threads;  // empty: all cores
  Size convergence_resolution;
  int convergence_ref_spp = 65536;
  bool convergence = true;
};

std::string scene_file(const Settings& s, const std::string& object, const Lighting& l) {
  return (s.scenes / (object + "_sphere_" + l.scene_suffix + ".gltf")).string();
}

json read_json(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path.string() + ": missing (a step of reproduce did not write it)");
  return read_json_file(path.string(), "a step's result");
}

std::string fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}
std::string signed_fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%+.*f", digits, value);
  return text;
}
std::string percent(double value) { return fixed(100 * value, 2) + "%"; }
std::string rgb_text(const json& c, int digits) {
  return fixed(c[0].get<double>(), digits) + " " + fixed(c[1].get<double>(), digits) + " " +
         fixed(c[2].get<double>(), digits);
}
RGB rgb_of(const json& c) { return RGB(c[0].get<float>(), c[1].get<float>(), c[2].get<float>()); }

// Runs one glaze step, timed, logged as it goes.
template <typename Command>
double step(const std::string& what, Command command, const std::vector<std::string>& args) {
  std::printf("\n== %s\n", what.c_str());
  std::fflush(stdout);
  const auto start = Clock::now();
  if (const int status = command(args); status != 0)
    throw Error("reproduce: the step '" + what + "' failed (status " + std::to_string(status) + ")");
  return seconds_since(start);
}

std::vector<std::string> with_threads(std::vector<std::string> args, const Settings& s) {
  if (!s.threads.empty()) args.insert(args.end(), {"--threads", s.threads});
  return args;
}

// The scene of `object` in lighting `l` with its material replaced.
Scene with_material(Scene scene, float R0, const RGB& Rd) {
  for (SceneMaterial& m : scene.materials) m.R0 = R0, m.Rd = Rd;
  return scene;
}

// Captures of a spectral camera (pseudo_brdf.h): the capture set's images rewritten as
// render_sh_spectral of the true material, with the set's own integrator settings.
void make_spectral(const fs::path& folder, const Scene& scene, const Environment& environment, int lmax, int ss) {
  const CaptureSet set = read_transforms(folder.string());
  const SceneMaterial& m = scene.materials.at(0);
  const Mat3 M = spectral_diffuse_matrix(m.Rd);
  const RayTracer tracer(scene);
  for (const CaptureFrame& frame : set.frames)
    write_image(frame.file_path,
                render_sh_spectral(scene, tracer, environment, frame.camera, {lmax, ss, true, 0, true}, M),
                {{"glaze:integrator", "sh (spectral camera, inverse/pseudo_brdf.h)"}});
}

// What Figure 7 shows of one transfer.
struct TransferImages {
  AppearanceError numbers;
  Image truth, rendered;
  std::vector<uint8_t> mask;
};

// A texture for people: unknown texels (alpha 0) as a magenta and grey checkerboard.
Image texture_with_unknown(const std::string& path) {
  std::vector<float> alpha;
  Image texture = read_image(path, &alpha);
  for (int y = 0; y < texture.height; ++y)
    for (int x = 0; x < texture.width; ++x)
      if (alpha[size_t(y) * texture.width + x] <= 0.0f)
        texture.set(x, y, ((x / 4 + y / 4) % 2) ? RGB(0.6f, 0.0f, 0.6f) : RGB(0.25f, 0.25f, 0.25f));
  return texture;
}

// Pixels where the capture sees the object (the background is black): for the error images.
std::vector<uint8_t> object_pixels(const Image& capture) {
  std::vector<uint8_t> mask(size_t(capture.width) * capture.height);
  for (size_t p = 0; p < mask.size(); ++p)
    mask[p] = capture.pixels[3 * p] + capture.pixels[3 * p + 1] + capture.pixels[3 * p + 2] > 0.0f;
  return mask;
}

class Reproduction {
 public:
  explicit Reproduction(Settings settings) : s_(std::move(settings)) {}

  void run() {
    create_output_folder(s_.out / "figures", "reproduction");
    results_["settings"] = {{"resolution", size_text(s_.resolution)},
                            {"spp", s_.spp},
                            {"texture_resolution", size_text(s_.texture_resolution)},
                            {"lighting_resolution", size_text(s_.lighting_resolution)},
                            {"transfer_lmax", s_.transfer_lmax},
                            {"scenes", s_.scenes.string()}};
    for (const Lighting& l : s_.lightings) {
      results_["lightings"].push_back({{"name", l.name}, {"env", l.env.empty() ? "the scene's" : l.env}});
      captures_and_fits(l);
    }
    transfers();
    figures();
    if (s_.convergence) convergence();
    write_text_atomically((s_.out / "results.json").string(), results_.dump(2) + "\n");
    report();
    std::printf("\nwrote %s and %s\n", (s_.out / "report.md").string().c_str(),
                (s_.out / "results.json").string().c_str());
  }

 private:
  fs::path captures_dir(const Lighting& l, const std::string& object) const {
    return s_.out / "captures" / l.name / object;
  }
  fs::path fit_dir(const Lighting& l, const std::string& object, const std::string& mode) const {
    return s_.out / "fits" / l.name / object / mode;
  }
  void time(const std::string& stage, double seconds) { results_["stage_seconds"][stage] = seconds; }

  void captures_and_fits(const Lighting& l) {
    for (const std::string object : {"red", "white", "textured"}) {
      const fs::path captures = captures_dir(l, object);
      std::vector<std::string> render = {
          scene_file(s_, object, l), "--captures", captures.string(), "--holdout", "novel_0,novel_1",       "--spp",
          std::to_string(s_.spp),    "--seed",     s_.seed,           "--res",     size_text(s_.resolution)};
      if (!l.env.empty()) render.insert(render.end(), {"--env", l.env});
      time("captures/" + l.name + "/" + object,
           step("captures: " + object + " sphere, " + l.name, command_render, with_threads(render, s_)));
      const std::string transforms = (captures / "transforms.json").string();
      if (object == "textured") {
        fit(l, object, "texture", {transforms, "--mode", "texture", "--texture-res", size_text(s_.texture_resolution)});
        continue;
      }
      fit(l, object, "material", {transforms, "--mode", "material"});
      fit(l, object, "lighting", {transforms, "--mode", "lighting", "--env-res", size_text(s_.lighting_resolution)});
      fit(l, object, "joint", {transforms, "--mode", "joint", "--env-res", size_text(s_.lighting_resolution)});
      // The same object seen by a spectral camera (noise-free sh captures, footprint 1).
      const fs::path spectral = captures_dir(l, object + "_spectral");
      std::vector<std::string> sh = {scene_file(s_, object, l),
                                     "--captures",
                                     spectral.string(),
                                     "--integrator",
                                     "sh",
                                     "--ss",
                                     "1",
                                     "--lmax",
                                     "16",
                                     "--res",
                                     size_text(s_.resolution)};
      if (!l.env.empty()) sh.insert(sh.end(), {"--env", l.env});
      time("captures/" + l.name + "/" + object + "_spectral",
           step("spectral captures: " + object + " sphere, " + l.name, command_render, with_threads(sh, s_)));
      const Scene scene = load_scene(scene_file(s_, object, l));
      make_spectral(spectral, scene, environment(l), 16, 1);
      fit(l, object + "_spectral", "material", {(spectral / "transforms.json").string(), "--mode", "material"});
    }
  }

  void fit(const Lighting& l, const std::string& object, const std::string& mode, std::vector<std::string> args) {
    const fs::path out = fit_dir(l, object, mode);
    args.insert(args.end(), {"--out", out.string()});
    time("fits/" + l.name + "/" + object + "/" + mode,
         step(mode + " fit: " + object + " sphere, " + l.name, command_invert_fit, with_threads(args, s_)));
    fits_[l.name][object][mode] = read_json(out / "fit.json");
  }

  // The lighting's true environment, as its scenes (or the --env override) define it:
  // built once (and its SH projections with it), the same for every sphere.
  const Environment& environment(const Lighting& l) {
    std::unique_ptr<Environment>& cached = environments_[l.name];
    if (!cached) {
      EnvironmentOverride lighting;
      if (!l.env.empty()) lighting.source = l.env;
      const EnvironmentSpec spec = environment_spec(load_scene(scene_file(s_, "red", l)), lighting);
      // (Environment does not move: built in place from make_environment's result.)
      cached.reset(new Environment(make_environment(spec.source, spec.options, spec.width, spec.height)));
    }
    return *cached;
  }

  const json& fit_of(const Lighting& l, const std::string& object, const std::string& mode) const {
    return fits_.at(l.name).at(object).at(mode);
  }

  // Figure 7 shows the paper's pair, the first two lightings; results.json has all.
  bool in_figure_pair(const Lighting& l) const {
    return l.name == s_.lightings[0].name || (s_.lightings.size() > 1 && l.name == s_.lightings[1].name);
  }

  // Figure 7's numbers: every material recovered in lighting a, rendered (view_0, sh
  // integrator) in lighting b against its true appearance there, rendered once per b.
  void transfers() {
    const ShIntegratorOptions options{s_.transfer_lmax, 2, true, 0, true};
    for (const std::string kind : {"rgb", "spectral"})
      for (const char* object : kHomogeneous)
        for (const Lighting& b : s_.lightings) {
          const Scene scene = load_scene(scene_file(s_, object, b));
          const RayTracer tracer(scene);
          const PinholeCamera camera = scene.make_camera(scene.camera("view_0"), s_.resolution);
          const Image truth = kind == "spectral" ? render_sh_spectral(scene, tracer, environment(b), camera, options,
                                                                      spectral_diffuse_matrix(scene.materials[0].Rd))
                                                 : render_sh(scene, tracer, environment(b), camera, options);
          const std::vector<uint8_t> mask = interior_mask(tracer, camera);
          for (const Lighting& a : s_.lightings) {
            // A fit shown in its own lighting: the RGB model's best (kept for the spectral camera only).
            if (a.name == b.name && kind == "rgb") continue;
            const json& recovered = fit_of(a, kind == "rgb" ? object : std::string(object) + "_spectral", "material");
            Image rendered = render_sh(with_material(scene, recovered["R0"].get<float>(), rgb_of(recovered["Rd"])),
                                       tracer, environment(b), camera, options);
            const AppearanceError t = appearance_error(rendered, truth, mask);
            results_["transfer"].push_back({{"kind", kind},
                                            {"object", object},
                                            {"fitted_in", a.name},
                                            {"shown_in", b.name},
                                            {"relative_rmse", t.relative_rmse},
                                            {"colour_ratio", {t.colour_ratio[0], t.colour_ratio[1], t.colour_ratio[2]}},
                                            {"Rd", recovered["Rd"]}});
            if (a.name != b.name && in_figure_pair(a) && in_figure_pair(b))
              transfer_images_[kind + "/" + object + "/" + a.name + "/" + b.name] = {t, truth, std::move(rendered),
                                                                                     mask};
          }
        }
    for (const char* object : kHomogeneous) {
      const Scene scene = load_scene(scene_file(s_, object, s_.lightings.front()));
      const Mat3 M = spectral_diffuse_matrix(scene.materials.at(0).Rd);
      for (int r = 0; r < 3; ++r) results_["spectral_matrix"][object].push_back({M(r, 0), M(r, 1), M(r, 2)});
    }
    // How neutral each lighting is: the spread of its L00 over the channels (1 = white).
    std::map<std::string, double> spread;
    for (const Lighting& l : s_.lightings) {
      const RGBd L00 = environment(l).sh(0).values[0];
      spread[l.name] = L00.maxCoeff() / std::max(L00.minCoeff(), 1e-30);
      results_["lighting_colour_spread"][l.name] = spread[l.name];
    }
    // The paper's claim, per lighting shown in: among the materials fitted in the other
    // lightings, the one fitted in the most neutral lighting renders best. It needs at
    // least two other lightings to compare.
    std::ostringstream summary;
    summary << "Colour of each lighting (max/min channel of its L00):";
    for (const Lighting& l : s_.lightings) summary << " " << l.name << " " << fixed(spread[l.name], 2);
    summary << ".";
    for (const std::string kind : {"rgb", "spectral"})
      for (const char* object : kHomogeneous)
        for (const Lighting& b : s_.lightings) {
          if (s_.lightings.size() < 3) continue;
          std::string best, most_neutral;
          double best_error = INFINITY, lowest_spread = INFINITY;
          for (const json& row : results_["transfer"]) {
            if (row["kind"] != kind || row["object"] != object || row["shown_in"] != b.name ||
                row["fitted_in"] == b.name)
              continue;
            const std::string a = row["fitted_in"];
            if (row["relative_rmse"].get<double>() < best_error)
              best_error = row["relative_rmse"].get<double>(), best = a;
            if (spread[a] < lowest_spread) lowest_spread = spread[a], most_neutral = a;
          }
          results_["transfer_ranking"].push_back({{"kind", kind},
                                                  {"object", object},
                                                  {"shown_in", b.name},
                                                  {"best_fitted_in", best},
                                                  {"most_neutral_source", most_neutral},
                                                  {"agrees", best == most_neutral}});
        }
    // Mean error of each lighting's fits shown in the other lightings, beside its colour.
    for (const std::string kind : {"rgb", "spectral"}) {
      summary << " Mean error of the fits from each lighting shown in the others, "
              << (kind == "rgb" ? "RGB captures:" : "spectral camera:");
      for (const Lighting& a : s_.lightings) {
        double sum = 0.0;
        int count = 0;
        for (const json& row : results_["transfer"])
          if (row["kind"] == kind && row["fitted_in"] == a.name && row["shown_in"] != a.name)
            sum += row["relative_rmse"].get<double>(), ++count;
        if (count == 0) continue;
        results_["transfer_mean"][kind][a.name] = sum / count;
        summary << " " << a.name << " " << percent(sum / count);
      }
      summary << ".";
    }
    // Spearman's rank correlation between a lighting's colour spread and the mean error
    // of its fits elsewhere: +1 when the more coloured the light, the worse its fits travel.
    if (s_.lightings.size() >= 3)
      for (const std::string kind : {"rgb", "spectral"}) {
        std::vector<std::pair<double, double>> pairs;
        for (const Lighting& l : s_.lightings)
          pairs.push_back({spread[l.name], results_["transfer_mean"][kind][l.name].get<double>()});
        const double rho = rank_correlation(pairs);
        results_["transfer_rank_correlation"][kind] = rho;
        summary << " Rank correlation of colour spread with that error, "
                << (kind == "rgb" ? "RGB captures: " : "spectral camera: ") << fixed(rho, 2) << ".";
      }
    if (results_.contains("transfer_ranking")) {
      for (const std::string kind : {"rgb", "spectral"}) {
        int agree = 0, total = 0;
        for (const json& row : results_["transfer_ranking"])
          if (row["kind"] == kind) agree += row["agrees"].get<bool>(), ++total;
        summary << " " << (kind == "rgb" ? "RGB captures" : "Spectral camera") << ": in " << agree << " of " << total
                << " (sphere, lighting shown in) pairs the material fitted in the most neutral of the other lightings "
                   "renders best.";
      }
    } else {
      summary << " (Whether fits from white-ish light transfer best needs three or more lightings to rank; run with "
                 "the real maps.)";
    }
    results_["transfer_summary"] = summary.str();
  }

  void figures() {
    table_2();
    figure_5();
    figure_6();
    figure_7();
    figure_8_and_9();
  }

  void table_2() {
    for (const Lighting& l : s_.lightings) {
      for (const char* object : kHomogeneous) {
        const json& r = fit_of(l, object, "material");
        const json& truth = r["reference_material"];
        json row = {{"lighting", l.name},
                    {"object", object},
                    {"true_R0", truth["R0"]},
                    {"true_Rd", truth["Rd"]},
                    {"R0", r["R0"]},
                    {"Rd", r["Rd"]},
                    {"R0_error", r["R0"].get<double>() - truth["R0"].get<double>()},
                    {"seconds", r["seconds"]},
                    {"samples", r["samples"]}};
        for (int c = 0; c < 3; ++c) row["Rd_error"].push_back(r["Rd"][c].get<double>() - truth["Rd"][c].get<double>());
        results_["table2"].push_back(row);
      }
      const json& t = fit_of(l, "textured", "texture");
      results_["table2"].push_back({{"lighting", l.name},
                                    {"object", "textured"},
                                    {"true_R0", t["reference_material"]["R0"]},
                                    {"R0", t["R0"]},
                                    {"R0_error", t["R0"].get<double>() - t["reference_material"]["R0"].get<double>()},
                                    {"texture_rmse", t.value("texture_rmse", json())},
                                    {"coverage", t["coverage"]},
                                    {"seconds", t["seconds"]},
                                    {"samples", t["samples"]}});
    }
  }

  void figure_5() {
    Figure figure{
        "Figure 5: diffuse textures recovered under known lighting (magenta/grey checks: unknown texels)", {}, {}};
    const Scene scene = load_scene(scene_file(s_, "textured", s_.lightings.front()));
    const Image truth = scene.textures.at(0).image;
    const DisplaySettings display{0.0f, ToneMapping::clamp};  // albedo in [0, 1]: shown as it is
    for (const Lighting& l : s_.lightings) {
      const json& t = fit_of(l, "textured", "texture");
      figure.row_labels.push_back(l.name);
      figure.rows.push_back(
          {picture_panel(truth, display, "true albedo", 384),
           picture_panel(texture_with_unknown(t["texture"].get<std::string>()), display,
                         "recovered: texel RMSE " +
                             (t["texture_rmse"].is_number() ? fixed(t["texture_rmse"].get<double>(), 4) : "n/a") +
                             "\nknown " + percent(t["coverage"].get<double>()) + ", R0 " +
                             fixed(t["R0"].get<double>(), 4),
                         384)});
    }
    write_figure((s_.out / "figures" / "figure5_textures.png").string(), figure);
  }

  void figure_6() {
    Figure figure{"Figure 6: held-out views, captured (path tracer) and rendered with the recovered material", {}, {}};
    for (const Lighting& l : s_.lightings)
      for (const std::string object : {"red", "white", "textured"}) {
        const json& r = fit_of(l, object, object == "textured" ? "texture" : "material");
        for (const json& view : r["holdout"]) {
          const Image captured = read_image(view["file"].get<std::string>());
          const Image rendered = read_image(view["render"].get<std::string>());
          const DisplaySettings display{exposure_for(captured), ToneMapping::filmic};
          const double error = view["relative_rmse"].is_number() ? view["relative_rmse"].get<double>() : NAN;
          results_["holdout"].push_back({{"lighting", l.name},
                                         {"object", object},
                                         {"camera", view["camera"]},
                                         {"relative_rmse", view["relative_rmse"]}});
          figure.row_labels.push_back(l.name + "\n" + object + " sphere\n" + view["camera"].get<std::string>());
          figure.rows.push_back({picture_panel(captured, display, "held-out capture"),
                                 picture_panel(rendered, display, "recovered material"),
                                 error_panel(rendered, captured, object_pixels(captured), 0.2f,
                                             "|difference| (0 to 20% of mean)\nrelative RMSE " + percent(error))});
        }
      }
    write_figure((s_.out / "figures" / "figure6_novel_views.png").string(), figure);
  }

  void figure_7() {
    Figure figure{"Figure 7: materials recovered in one lighting, shown in another (view_0, sh integrator)", {}, {}};
    for (const std::string kind : {"rgb", "spectral"})
      for (const char* object : kHomogeneous)
        for (const Lighting& a : s_.lightings)
          for (const Lighting& b : s_.lightings) {
            if (a.name == b.name || !in_figure_pair(a) || !in_figure_pair(b)) continue;
            const TransferImages& t = transfer_images_.at(kind + "/" + object + "/" + a.name + "/" + b.name);
            const DisplaySettings display{exposure_for(t.truth), ToneMapping::filmic};
            char ratio[96];
            std::snprintf(ratio, sizeof ratio, "colour ratio %.3f %.3f %.3f", t.numbers.colour_ratio[0],
                          t.numbers.colour_ratio[1], t.numbers.colour_ratio[2]);
            figure.row_labels.push_back(std::string(kind == "rgb" ? "RGB captures" : "spectral camera") + "\n" +
                                        object + " sphere\nfitted in " + a.name + "\nshown in " + b.name);
            figure.rows.push_back(
                {picture_panel(t.truth, display, "true appearance in " + b.name),
                 picture_panel(t.rendered, display, "recovered in " + a.name + "\n" + ratio),
                 error_panel(t.rendered, t.truth, t.mask, 0.2f,
                             "|difference| (0 to 20% of mean)\nrelative RMSE " + percent(t.numbers.relative_rmse))});
          }
    write_figure((s_.out / "figures" / "figure7_transfer.png").string(), figure);
  }

  void figure_8_and_9() {
    for (const std::string mode : {"lighting", "joint"}) {
      Figure figure{mode == "lighting" ? "Figure 8: lighting recovered from spheres of known material (" +
                                             size_text(s_.lighting_resolution) + "; coverage: white = seen)"
                                       : "Figure 9: lighting and material recovered together (joint)",
                    {},
                    {}};
      for (const Lighting& l : s_.lightings) {
        const Environment& truth = environment(l);
        // map() is before the scale, the recovered maps after it: one exposure for both.
        const float ev = exposure_for(truth.map());
        const DisplaySettings display{ev - std::log2(truth.scale()), ToneMapping::filmic};
        std::vector<FigurePanel> row = {picture_panel(truth.map(), {ev, ToneMapping::filmic}, "true map")};
        for (const char* object : kHomogeneous) {
          const json& r = fit_of(l, object, mode);
          const json& map_error = r["reference_map_error"]["64x32"]["relative_rmse"];
          std::string caption = std::string(object) + ": L_lm (l<=2) error " +
                                percent(r["reference_L_lm_error_l2"].get<double>()) + "\nmap error (64x32) " +
                                (map_error.is_number() ? percent(map_error.get<double>()) : "n/a") + ", covered " +
                                percent(r["covered_fraction"].get<double>());
          if (mode == "joint")
            caption += "\nR0 " + fixed(r["R0"].get<double>(), 4) + ", Rd " + rgb_text(r["Rd"], 3) + "\nscale " +
                       rgb_text(r["reference_scale"], 3);
          row.push_back(picture_panel(read_image(r["map"].get<std::string>()), display, caption));
          if (mode == "lighting")
            row.push_back(picture_panel(read_image(r["coverage_mask"].get<std::string>()), {0.0f, ToneMapping::clamp},
                                        std::string(object) + ": coverage"));
          results_[mode == "lighting" ? "lighting" : "table3"].push_back(table_row(l, object, mode));
        }
        figure.row_labels.push_back(l.name);
        figure.rows.push_back(std::move(row));
      }
      write_figure((s_.out / "figures" / (mode == "lighting" ? "figure8_lighting.png" : "figure9_joint.png")).string(),
                   figure);
    }
  }

  json table_row(const Lighting& l, const std::string& object, const std::string& mode) const {
    const json& r = fit_of(l, object, mode);
    json row = {{"lighting", l.name},
                {"object", object},
                {"L_lm_error_l2", r["reference_L_lm_error_l2"]},
                {"map_error", r["reference_map_error"]},
                {"covered_fraction", r["covered_fraction"]},
                {"seconds", r["seconds"]},
                {"scale", r["reference_scale"]}};
    if (mode == "joint") {
      const json& known = fit_of(l, object, "material");
      const json& truth = known["reference_material"];
      row["true"] = {{"R0", truth["R0"]}, {"Rd", truth["Rd"]}};
      row["known_lighting"] = {{"R0", known["R0"]}, {"Rd", known["Rd"]}};
      row["joint"] = {{"R0", r["R0"]}, {"Rd", r["Rd"]}, {"converged", r["converged"]}, {"iterations", r["iterations"]}};
      row["joint_R0_error"] = r["R0"].get<double>() - truth["R0"].get<double>();
      for (int c = 0; c < 3; ++c) {
        row["joint_Rd_error"].push_back(r["Rd"][c].get<double>() - truth["Rd"][c].get<double>());
        row["joint_minus_known_Rd"].push_back(r["Rd"][c].get<double>() - known["Rd"][c].get<double>());
      }
      row["joint_minus_known_R0"] = r["R0"].get<double>() - known["R0"].get<double>();
    }
    return row;
  }

  void convergence() {
    const Lighting office{"office", "office", ""};
    time("convergence",
         step("error against run time: red sphere, office", command_convergence,
              with_threads(
                  {scene_file(s_, "red", office), "--camera", "view_0", "--res", size_text(s_.convergence_resolution),
                   "--ref-spp", std::to_string(s_.convergence_ref_spp), "--out", (s_.out / "convergence").string()},
                  s_)));
    results_["convergence"] = read_json(s_.out / "convergence" / "summary.json");
  }

  void report() const;

  Settings s_;
  json results_;
  std::map<std::string, std::map<std::string, std::map<std::string, json>>> fits_;
  std::map<std::string, TransferImages> transfer_images_;
  std::map<std::string, std::unique_ptr<Environment>> environments_;
};

void Reproduction::report() const {
  std::ostringstream md;
  const json& r = results_;
  md << "# glaze reproduce: Nielsen and Brodersen 2004, end to end\n\n"
     << "Captures: glaze's path tracer, " << size_text(s_.resolution) << " pixels, " << s_.spp
     << " spp, three input views and two held-out views per sphere (scenes/). Lightings:";
  for (const Lighting& l : s_.lightings)
    md << " " << l.name << (l.env.empty() ? "" : " (" + fs::path(l.env).filename().string() + ")") << ",";
  md.seekp(-1, std::ios_base::end);
  md << ". Every number below is in `results.json`; every fit's own output (fit.json, solver report, re-renders, "
        "residual images) is under `fits/`.\n\n";

  md << "## Table 2: material under known lighting\n\n| lighting | sphere | true R0 | R0 | error | true Rd | Rd | "
        "error | fit time |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const json& row : r["table2"]) {
    md << "| " << row["lighting"].get<std::string>() << " | " << row["object"].get<std::string>() << " | "
       << fixed(row["true_R0"].get<double>(), 4) << " | " << fixed(row["R0"].get<double>(), 4) << " | "
       << signed_fixed(row["R0_error"].get<double>(), 4) << " | ";
    if (row.contains("Rd"))
      md << rgb_text(row["true_Rd"], 4) << " | " << rgb_text(row["Rd"], 4) << " | "
         << signed_fixed(row["Rd_error"][0].get<double>(), 4) << " "
         << signed_fixed(row["Rd_error"][1].get<double>(), 4) << " "
         << signed_fixed(row["Rd_error"][2].get<double>(), 4);
    else
      md << "texture | texture | texel RMSE "
         << (row["texture_rmse"].is_number() ? fixed(row["texture_rmse"].get<double>(), 4) : "n/a") << ", "
         << percent(row["coverage"].get<double>()) << " known";
    md << " | " << fixed(row["seconds"].get<double>(), 2) << " s |\n";
  }
  md << "\n## Figure 5: recovered diffuse textures\n\n![Figure 5](figures/figure5_textures.png)\n\n";
  md << "## Figure 6: held-out views\n\n| lighting | sphere | view | relative RMSE |\n|---|---|---|---|\n";
  for (const json& row : r["holdout"])
    md << "| " << row["lighting"].get<std::string>() << " | " << row["object"].get<std::string>() << " | "
       << row["camera"].get<std::string>() << " | "
       << (row["relative_rmse"].is_number() ? percent(row["relative_rmse"].get<double>()) : "n/a") << " |\n";
  md << "\nThe held-out captures carry the path tracer's noise at " << s_.spp
     << " spp; the re-renders (sh integrator) have none, so for the homogeneous spheres these errors are mostly that "
        "noise. "
        "The textured sphere's held-out views look at its poles, which no input view saw well: those texels are "
        "unknown "
        "(Figure 5) and render black, which is most of its error.\n\n![Figure 6](figures/figure6_novel_views.png)\n\n";

  md << "## Figure 7: recovered materials in other lighting\n\n"
        "Each material recovered in one lighting is rendered (view_0, sh integrator) in another and compared with its "
        "true "
        "appearance there. *RGB captures*: the path-traced captures above, which, like glaze, render per RGB channel, "
        "so a "
        "material transfers up to its fitting error. *Spectral camera*: noise-free captures of a camera that "
        "integrates "
        "31 wavelengths (inverse/pseudo_brdf.h); an RGB fit then finds a pseudo-BRDF that depends on the light it was "
        "fitted under, which is the colour shift the paper reports. Colour ratio: mean rendered over mean true, "
        "per channel.\n\n"
        "| captures | sphere | fitted in | shown in | relative RMSE | colour ratio (r g b) "
        "|\n|---|---|---|---|---|---|\n";
  for (const json& row : r["transfer"])
    md << "| " << row["kind"].get<std::string>() << " | " << row["object"].get<std::string>() << " | "
       << row["fitted_in"].get<std::string>() << " | " << row["shown_in"].get<std::string>() << " | "
       << percent(row["relative_rmse"].get<double>()) << " | " << rgb_text(row["colour_ratio"], 3) << " |\n";
  md << "\n"
     << r["transfer_summary"].get<std::string>()
     << "\n\nThe spectral camera's diffuse response M (camera RGB = M x RGB irradiance; "
        "an RGB fit can only find its diagonal):";
  for (const auto& [object, M] : r["spectral_matrix"].items())
    md << " " << object << " [" << rgb_text(M[0], 3) << "; " << rgb_text(M[1], 3) << "; " << rgb_text(M[2], 3) << "]";
  md << ".\n\n![Figure 7](figures/figure7_transfer.png)\n\n";

  md << "## Figure 8: lighting from spheres of known material\n\n| lighting | sphere | L_lm error (l<=2, of L00) | map "
        "error 64x32 | 128x64 | 256x128 | covered | time |\n|---|---|---|---|---|---|---|---|\n";
  auto map_error = [](const json& row, const char* key) {
    if (!row["map_error"].contains(key)) return std::string("-");  // finer than the recovered map
    const json& error = row["map_error"][key]["relative_rmse"];
    return error.is_number() ? percent(error.get<double>()) : std::string("n/a (no cell wholly covered)");
  };
  for (const json& row : r["lighting"])
    md << "| " << row["lighting"].get<std::string>() << " | " << row["object"].get<std::string>() << " | "
       << percent(row["L_lm_error_l2"].get<double>()) << " | " << map_error(row, "64x32") << " | "
       << map_error(row, "128x64") << " | " << map_error(row, "256x128") << " | "
       << percent(row["covered_fraction"].get<double>()) << " | " << fixed(row["seconds"].get<double>(), 2) << " s |\n";
  md << "\n![Figure 8](figures/figure8_lighting.png)\n\n";

  md << "## Figure 9 and Table 3: joint estimation against known lighting\n\n"
        "| lighting | sphere | true R0 | known-lighting R0 | joint R0 | true Rd | known-lighting Rd | joint Rd | joint "
        "- known Rd | scale (recovered/true L00) | time |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const json& row : r["table3"])
    md << "| " << row["lighting"].get<std::string>() << " | " << row["object"].get<std::string>() << " | "
       << fixed(row["true"]["R0"].get<double>(), 4) << " | " << fixed(row["known_lighting"]["R0"].get<double>(), 4)
       << " | " << fixed(row["joint"]["R0"].get<double>(), 4) << " | " << rgb_text(row["true"]["Rd"], 4) << " | "
       << rgb_text(row["known_lighting"]["Rd"], 4) << " | " << rgb_text(row["joint"]["Rd"], 4) << " | "
       << signed_fixed(row["joint_minus_known_Rd"][0].get<double>(), 4) << " "
       << signed_fixed(row["joint_minus_known_Rd"][1].get<double>(), 4) << " "
       << signed_fixed(row["joint_minus_known_Rd"][2].get<double>(), 4) << " | " << rgb_text(row["scale"], 3) << " | "
       << fixed(row["seconds"].get<double>(), 1) << " s |\n";
  md << "\nThe paper's Table 3 shows shifts of about 0.02 between known-lighting and joint estimates.\n\n![Figure "
        "9](figures/figure9_joint.png)\n\n";

  if (r.contains("convergence")) {
    md << "## Error against run time (sh integrator against the path tracer)\n\nRed sphere, office, view_0 at "
       << size_text(s_.convergence_resolution) << ", reference " << s_.convergence_ref_spp
       << " spp (`glaze convergence`).\n\n";
    for (const auto& [target, entry] : r["convergence"]["time_to"].items()) {
      md << "- relative RMSE " << percent(std::stod(target)) << ": ";
      if (entry.contains("resolvable") && !entry["resolvable"].get<bool>())
        md << "not resolvable at this reference's noise\n";
      else if (entry["sh_seconds"].is_number())
        md << "path tracer " << fixed(entry["path_seconds"].get<double>(), 3) << " s, sh "
           << fixed(entry["sh_seconds"].get<double>(), 4) << " s (" << entry["sh_setting"].get<std::string>()
           << "): " << fixed(entry["speedup"].get<double>(), 0) << "x, "
           << fixed(entry["speedup_projection_cached"].get<double>(), 0) << "x with the SH projection cached\n";
      else
        md << "path tracer " << fixed(entry["path_seconds"].get<double>(), 3) << " s, no sh setting reaches it\n";
    }
    md << "\n![error against run time](convergence/convergence.png)\n\n";
  }
  md << "## Run time of each stage\n\n| stage | seconds |\n|---|---|\n";
  double total = 0.0;
  for (const auto& [stage, seconds] : r["stage_seconds"].items()) {
    md << "| " << stage << " | " << fixed(seconds.get<double>(), 2) << " |\n";
    total += seconds.get<double>();
  }
  md << "| total | " << fixed(total, 1) << " |\n";
  write_text_atomically((s_.out / "report.md").string(), md.str());
}

// ../shared/data next to the source tree by default; GLAZE_DATA_DIR overrides.
fs::path default_data_dir() {
  if (const char* env = std::getenv("GLAZE_DATA_DIR")) return env;
  return fs::path(GLAZE_SOURCE_DIR) / ".." / "shared" / "data";
}

struct ReproduceCommandOptions {
  std::string out;
  bool quick = false;
  std::optional<Resolution> resolution, texture_resolution, lighting_resolution;
  int spp = 256;
  uint64_t seed = 0;
  std::optional<std::vector<std::string>> lighting;
  std::vector<std::string> real_maps = {"st_fagans_interior_1k.hdr", "lebombo_1k.hdr"};
  std::optional<std::string> scenes;
  bool no_convergence = false;
  int threads = 0;
};

int reproduce(const ReproduceCommandOptions& args) {
  const bool quick = args.quick;
  Settings s;
  s.out = args.out;
  const bool here = fs::exists("scenes/red_sphere_office.gltf");
  s.scenes = args.scenes.value_or(here ? "scenes" : std::string(GLAZE_SOURCE_DIR) + "/scenes");
  if (!fs::exists(s.scenes / "red_sphere_office.gltf"))
    throw Error(s.scenes.string() +
                ": no scenes/red_sphere_office.gltf there; give glaze's scenes folder with --scenes DIR");
  auto size = [](const std::optional<Resolution>& given, Size otherwise) { return given ? given->pair() : otherwise; };
  s.resolution = size(args.resolution, quick ? Size(160, 160) : Size(512, 512));
  s.spp = args.spp;
  s.seed = std::to_string(args.seed);
  s.texture_resolution = size(args.texture_resolution, quick ? Size(64, 32) : Size(256, 128));
  s.lighting_resolution = size(args.lighting_resolution, quick ? Size(128, 64) : Size(256, 128));
  if (args.threads > 0) s.threads = std::to_string(args.threads);
  s.convergence = !args.no_convergence;
  // The reference's own noise must stay under half the 1% target: at 65536 spp it is
  // about 0.36% per pixel (2.9% at 1024), whatever the image size; 0.3% needs about
  // 16 times more (`glaze convergence --ref-spp`).
  s.convergence_resolution = quick ? Size(32, 32) : Size(128, 128);

  // Lightings: the paper's two, and real maps when present.
  const std::map<std::string, Lighting> procedural = {{"office", {"office", "office", ""}},
                                                      {"blue-room", {"blue-room", "blue_room", ""}}};
  const fs::path envmaps = default_data_dir() / "envmaps";
  std::vector<std::string> names;
  if (args.lighting) {
    names = *args.lighting;
  } else {
    names = {"office", "blue-room"};
    for (const std::string& name : args.real_maps) {
      if (fs::exists(envmaps / name))
        names.push_back(name);
      else
        std::printf("reproduce: %s not found under %s (set GLAZE_DATA_DIR): its experiments are skipped\n",
                    name.c_str(), envmaps.string().c_str());
    }
  }
  for (const std::string& name : names) {
    if (procedural.count(name))
      s.lightings.push_back(procedural.at(name));
    else if (fs::exists(name))
      s.lightings.push_back({fs::path(name).stem().string(), "office", fs::absolute(name).string()});
    else if (fs::exists(envmaps / name))
      s.lightings.push_back({fs::path(name).stem().string(), "office", (envmaps / name).string()});
    else
      throw Error("--lighting: '" + name + "' is neither office, blue-room, an image file nor a map under " +
                  envmaps.string());
  }
  if (s.lightings.empty()) throw Error("--lighting: no lighting given");
  const std::string out = s.out.string();
  // The report reads the fits' JSON by key; a key missing or of another type means a
  // fit.json from another glaze version, or edited, under OUT.
  try {
    Reproduction(std::move(s)).run();
  } catch (const json::exception& e) {
    throw Error(out + ": a fit.json or summary.json there lacks a value the report needs (" + e.what() +
                "); remove the folder and run reproduce again");
  }
  return 0;
}

}  // namespace

CommandRun declare_reproduce(CLI::App& app) {
  auto args = std::make_shared<ReproduceCommandOptions>();
  app.description("the paper's experiments end to end (Table 2, Figures 5-9, Table 3) with a report: DIR/report.md");
  add_text(app, "--out DIR", args->out, "where the captures, fits, figures and report go")->required();
  app.add_flag("--quick", args->quick,
               "the reduced run (160x160 captures, 64x32 textures, 128x64 maps, a small convergence study):\n"
               "minutes, not the full hour");
  add_resolution(app, "--res WxH", args->resolution, "size of the captures (default 512x512)");
  add_spp(app, args->spp, "samples per pixel of the captures");
  add_seed(app, args->seed, "random seed of the captures' path tracer");
  add_resolution(app, "--texture-res WxH", args->texture_resolution,
                 "textures of the textured sphere (default 256x128)");
  add_resolution(app, "--env-res WxH", args->lighting_resolution,
                 "maps recovered by the lighting and joint fits (default 256x128)");
  add_names(app, "--lighting L,...", args->lighting,
            "office, blue-room, map files or names under $GLAZE_DATA_DIR/envmaps (default: office,\n"
            "blue-room and --real-maps where present: absent ones are skipped, saying so)");
  add_names(app, "--real-maps NAME,...", args->real_maps, "maps under $GLAZE_DATA_DIR/envmaps");
  add_text(app, "--scenes DIR", args->scenes, "glaze's scenes folder (default ./scenes, else the source tree's)");
  app.add_flag("--no-convergence", args->no_convergence, "leave out the error-against-run-time study");
  add_threads(app, args->threads);
  app.footer(
      "Writes DIR/report.md (tables and figures side by side), DIR/results.json (every number),\n"
      "DIR/figures/*.png, and the captures and fits behind them.");
  return [args] { return reproduce(*args); };
}

}  // namespace glaze
