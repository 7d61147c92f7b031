#include "app/invert_fit.h"

#if GLAZE_HAVE_PREVIEW
#include "app/fit_preview.h"
#endif
#include "inverse/capture_scene.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/image_error.h"
#include "renderer/sh.h"
#include "renderer/sh_integrator.h"

#include <algorithm>
#include <cstdio>

namespace glaze::invert_fit {
namespace {

// Re-renders `frames` with the recovered material and writes them with residual images
// (observed - predicted); returns per-view figures.
nlohmann::json rerender(const std::vector<CaptureFrame>& frames, const Scene& scene, const RayTracer& tracer,
                        const Environment& environment, int lmax, int footprint, OutputFolder& out,
                        const std::string& prefix) {
  // The fit's own model of a pixel (its footprint), so residuals show what the fit saw.
  ShIntegratorOptions options{lmax, footprint, true, 0};
  options.approximation_advice = kFitModelAdvice;
  const ShIntegrator integrator(scene, tracer, environment, options);
  nlohmann::json views = nlohmann::json::array();
  for (size_t f = 0; f < frames.size(); ++f) {
    const PinholeCamera& camera = frames[f].camera;
    const Image observed = read_image(frames[f].file_path);
    if (observed.width != camera.width || observed.height != camera.height)
      throw Error(frames[f].file_path + ": the image's size differs from its camera in transforms.json");
    const IntegratorResult rendered = integrator.render(camera);
    const Image& predicted = rendered.image;
    Image residual(camera.width, camera.height);
    for (size_t i = 0; i < residual.pixels.size(); ++i) residual.pixels[i] = observed.pixels[i] - predicted.pixels[i];
    char name[64];
    std::snprintf(name, sizeof name, "%s_%03zu.exr", prefix.c_str(), f);
    const std::string render_file = out.write_image("render_" + std::string(name), predicted, rendered.metadata);
    const std::string residual_file = out.write_image("residual_" + std::string(name), residual);
    nlohmann::json view = {
        {"file", frames[f].file_path}, {"camera", camera.name}, {"render", render_file}, {"residual", residual_file}};
    const std::vector<uint8_t> mask = interior_mask(tracer, camera);
    try {
      view["relative_rmse"] = image_error(predicted, observed, mask).relative_rmse;
    } catch (const Error&) {
      view["relative_rmse"] = nullptr;  // the object covers no whole pixel in this view
    }
    views.push_back(view);
  }
  return views;
}

// 8-bit captures: a warning; JPEGs whose highlights clip over much of the object are
// refused. Their blocks and halved colour resolution spread the clipping into pixels and
// channels that hold no clipped code, beyond what dropping the neighbours of clipped
// codes removes: on the red sphere clipped over 90% of its pixels, R0 came out 0.034
// for 0.045 (tests/ldr_captures_test.cpp), where the same set as PNG fits to 0.0002.
void check_8bit(const SampleSet& samples, const std::string& directory) {
  size_t eight_bit = 0, clipped = 0, seen = 0;
  for (size_t f = 0; f < samples.source_bits.size(); ++f) {
    if (samples.source_bits[f] != 8) continue;
    ++eight_bit;
    if (!samples.source_lossy[f]) continue;
    clipped += samples.dropped[f].saturated;
    seen += samples.dropped[f].saturated + samples.per_frame[f];
  }
  if (eight_bit == 0) return;
  const std::string remedy = "merge brackets into HDR (glaze hdr-merge) for linear images";
  constexpr double kMostClippedJpeg = 0.1;
  if (seen > 0 && double(clipped) > kMostClippedJpeg * double(seen)) {
    char share[32];
    std::snprintf(share, sizeof share, "%.0f%%", 100.0 * double(clipped) / double(seen));
    throw Error(directory + ": the JPEG views' highlights are clipped over " + share +
                " of the object's pixels; JPEG compression spreads clipping into neighbouring pixels and colours, so "
                "R0 and Rd cannot be measured from them. Take the photographs at a shorter exposure or as PNG/TIFF, "
                "or " +
                remedy);
  }
  warn(std::to_string(eight_bit) + " of the " + std::to_string(samples.source_bits.size()) +
       " images are 8-bit (PNG, JPEG): their clipped highlights (dropped as saturated) and rounding limit the "
       "accuracy of the fit; " +
       remedy);
}

}  // namespace

nlohmann::json rgb_json(const RGB& c) { return {c[0], c[1], c[2]}; }

nlohmann::json material_json(const CaptureMaterial& material) {
  nlohmann::json entry = {{"R0", material.material.R0()}, {"Rd", rgb_json(material.material.Rd())}};
  if (!material.texture.empty()) entry["texture"] = material.texture;
  return entry;
}

nlohmann::json drops_json(const DropCounts& d) {
  return {{"grazing", d.grazing},     {"silhouette", d.silhouette}, {"non_finite", d.non_finite},
          {"saturated", d.saturated}, {"masked", d.masked},         {"hidden", d.hidden}};
}

FitInputs prepare_inputs(const InvertFitOptions& args, nlohmann::json& stage_seconds) {
  return prepare_inputs(read_transforms(args.captures), args.samples, stage_seconds);
}

FitInputs prepare_inputs(CaptureSet captures, const SampleOptions& options, nlohmann::json& stage_seconds) {
  FitInputs in;
  in.captures = std::move(captures);
  in.scene = capture_object_scene(in.captures, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  in.tracer = std::make_unique<RayTracer>(in.scene);
  const auto stage = Clock::now();
  in.samples = collect_samples(in.captures, *in.tracer, in.scene, options);
  stage_seconds["samples"] = seconds_since(stage);
  const DropCounts dropped = in.samples.total_dropped();
  std::printf(
      "%zu samples from %zu views (dropped: %zu grazing, %zu silhouette, %zu not finite, %zu saturated, %zu masked, "
      "%zu hidden)\n",
      in.samples.samples.size(), in.captures.frames.size(), dropped.grazing, dropped.silhouette, dropped.non_finite,
      dropped.saturated, dropped.masked, dropped.hidden);
  check_8bit(in.samples, in.captures.directory);
  return in;
}

void write_fit(OutputFolder& out, nlohmann::json& result, const std::string& solver_report) {
  if (!solver_report.empty()) out.write_text("solver.txt", solver_report);
  result["run"] = out.run();
  out.finish(result.dump(2) + "\n");
}

void write_renders(const InvertFitOptions& args, const FitInputs& in, const Scene& scene,
                   const Environment& environment, int lmax, int footprint, OutputFolder& out, nlohmann::json& result) {
  result["renders"] = rerender(in.captures.frames, scene, *in.tracer, environment, lmax, footprint, out, "view");
  const std::filesystem::path holdout = args.holdout_dir ? std::filesystem::path(*args.holdout_dir)
                                                         : std::filesystem::path(in.captures.directory) / "holdout";
  if (args.holdout_dir || std::filesystem::exists(holdout / "transforms.json")) {
    const CaptureSet held_out = read_transforms(holdout.string());
    result["holdout"] = rerender(held_out.frames, scene, *in.tracer, environment, lmax, footprint, out, "holdout");
  }
}

std::pair<int, int> capture_defaults(const CaptureSet& captures, int otherwise_lmax) {
  if (noise_free_captures(captures)) return {captures.renderer->supersampling, captures.renderer->lmax};
  return {4, otherwise_lmax};
}

bool noise_free_captures(const CaptureSet& captures) {
  return captures.renderer && captures.renderer->integrator == CaptureRenderer::Integrator::sh;
}

#if GLAZE_HAVE_PREVIEW
void begin_preview(FitPreview* preview, const FitInputs& in, int lmax, int footprint) {
  if (!preview) return;
  std::vector<FitPreview::View> views;
  for (const CaptureFrame& frame : in.captures.frames) views.push_back({frame.camera, read_image(frame.file_path)});
  preview->begin(std::move(views), *in.tracer, lmax, footprint);
}

void show_in_preview(FitPreview* preview, const Scene& object, float R0, const RGB& Rd,
                     std::function<std::shared_ptr<const Environment>()> environment, const std::string& label) {
  if (!preview) return;
  auto scene = std::make_shared<Scene>(object);
  for (SceneMaterial& m : scene->materials) m.R0 = R0, m.Rd = Rd;
  preview->show({scene, std::move(environment), label});
}

FinishPreview::~FinishPreview() {
  if (preview) preview->finish();
}
#else
void begin_preview(FitPreview*, const FitInputs&, int, int) {}
void show_in_preview(FitPreview*, const Scene&, float, const RGB&, std::function<std::shared_ptr<const Environment>()>,
                     const std::string&) {}
FinishPreview::~FinishPreview() = default;
#endif

std::string iterate_label(const FitIterate& it) {
  char text[160];
  std::snprintf(text, sizeof text, "iteration %d: R0 %.5f, Rd %.4f %.4f %.4f, cost %.4g", it.iteration, it.R0, it.Rd[0],
                it.Rd[1], it.Rd[2], it.cost);
  return text;
}

std::function<std::shared_ptr<const Environment>()> borrowed(const Environment& environment) {
  return
      [&environment] { return std::shared_ptr<const Environment>(std::shared_ptr<const Environment>{}, &environment); };
}

}  // namespace glaze::invert_fit
