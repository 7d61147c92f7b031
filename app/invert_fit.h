// invert_fit.h: the parts of `glaze invert-fit` that its modes share: the inputs every
// mode starts from (capture set, object, samples), the defaults that match how the
// captures were rendered, the outputs (fit.json, re-renders, residual images), and the
// hooks of --preview. The modes live in invert_material.cpp (material, texture) and
// invert_lighting.cpp (lighting, joint); invert_command.cpp declares the command line.
#pragma once

#include "app/shared_options.h"
#include "app/timing.h"
#include "inverse/fit_progress.h"
#include "inverse/joint_fit.h"
#include "inverse/lighting_fit.h"
#include "inverse/samples.h"
#include "renderer/capture_set.h"
#include "renderer/environment.h"
#include "renderer/output_folder.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"
#include "renderer/sh.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace glaze {

class FitPreview;  // app/fit_preview.h (built with GLAZE_PREVIEW)

namespace invert_fit {

// What the sh integrator's warning about a concave object advises in invert-fit, whose
// fits model every pixel as that integrator does (and which has no other integrator).
inline constexpr const char* kFitModelAdvice =
    "invert-fit models every pixel so: expect a bias where the object shadows or reflects itself, "
    "or leave those pixels out with masks (mask_path in transforms.json)";

// The command line of `glaze invert-fit` (declared in invert_command.cpp). Options left
// empty take defaults that depend on the mode or on how the captures were rendered.
struct InvertFitOptions {
  std::string captures;  // CAPTURES/transforms.json, or its folder
  std::string mode;      // material, texture, lighting or joint
  std::string out;
  SampleOptions samples;  // --min-cos, --points, --seed
  std::optional<int> lmax, pixel_footprint, max_iterations;
  EnvironmentOverride environment;  // the known lighting of material and texture
  std::optional<std::string> holdout_dir;
  int threads = 0;
  // --mode material and texture.
  std::string loss = "none";
  float loss_scale = 0.05f;
  Resolution texture_resolution{256, 128};
  // --mode lighting and joint.
  std::optional<float> R0;
  std::vector<float> Rd;  // r, g, b; empty: the capture set's
  Resolution lighting_resolution{256, 128};
  std::optional<Resolution> solve_resolution;
  std::optional<float> ridge;
  int diffuse_lmax = kFullBandDiffuseLmax;
  std::optional<int> max_passes;
  // --preview.
  bool preview = false;
  WindowOptions window;
  DisplaySettings display;
};

nlohmann::json rgb_json(const RGB& c);
// A capture set's known material as fit.json reports it ("reference_material").
nlohmann::json material_json(const CaptureMaterial& material);
nlohmann::json drops_json(const DropCounts& d);

// What every mode starts from: the capture set, its object in the renderer's ray
// tracer, and the samples.
struct FitInputs {
  CaptureSet captures;
  Scene scene;
  std::unique_ptr<RayTracer> tracer;
  SampleSet samples;
};
FitInputs prepare_inputs(const InvertFitOptions& args, nlohmann::json& stage_seconds);
// The same for a capture set already read or built in memory (its images on disk).
FitInputs prepare_inputs(CaptureSet captures, const SampleOptions& options, nlohmann::json& stage_seconds);

// What --mode lighting and joint solve: the options, with the defaults that match how
// the captures were made, and the samples' lighting data.
struct LightingProblem {
  int lmax = 4, footprint = 4;
  int diffuse_lmax = 4;       // the diffuse term is modelled up to this band
  bool band_limited = false;  // the captures' diffuse term stops at lmax (sh captures)
  LightingFitOptions options;
  LightingData data;
};
LightingProblem lighting_problem(const InvertFitOptions& args, const FitInputs& in);
// --mode joint's fit of `problem` (whose data its later passes replace).
JointFit solve_joint(LightingProblem& problem, const SampleSet& samples, const InvertFitOptions& args,
                     const FitObserver& observer = {});

// Writes the solver's report, then fit.json (with the run's id, "run") last.
void write_fit(OutputFolder& out, nlohmann::json& result, const std::string& solver_report);

// Re-renders the inputs and the held-out views (CAPTURES/holdout or --holdout-dir) with
// `scene`'s material under `environment`, with residual images; per-view figures go to
// result["renders"] and result["holdout"].
void write_renders(const InvertFitOptions& args, const FitInputs& in, const Scene& scene,
                   const Environment& environment, int lmax, int footprint, OutputFolder& out, nlohmann::json& result);

// Defaults that match how glaze rendered the captures, when transforms.json says: the sh
// integrator's K x K sub-pixel grid is exactly a footprint of K, and its lmax is the
// band its diffuse term was truncated at. Otherwise a footprint of 4 (a camera's, or the
// path tracer's, box-filtered pixel) and `otherwise_lmax`. Returns {footprint, lmax}.
std::pair<int, int> capture_defaults(const CaptureSet& captures, int otherwise_lmax);

// Whether transforms.json says glaze's sh integrator rendered the captures: those carry no
// noise (it is deterministic).
bool noise_free_captures(const CaptureSet& captures);

// --preview (each a no-op when `preview` is null or the build has no preview):
// hands the window every capture view, observed, and the fit's pixel model;
void begin_preview(FitPreview* preview, const FitInputs& in, int lmax, int footprint);
// shows the object with material (R0, Rd) under the lighting `environment` gives;
void show_in_preview(FitPreview* preview, const Scene& object, float R0, const RGB& Rd,
                     std::function<std::shared_ptr<const Environment>()> environment, const std::string& label);
// a label for the title bar from a solver iterate.
std::string iterate_label(const FitIterate& it);
// A borrowed environment as the preview's lighting function.
std::function<std::shared_ptr<const Environment>()> borrowed(const Environment& environment);

// Waits, when the scope ends, until the preview has drawn the last state: its render
// thread reads the fit's geometry and lighting, which die with the scope. Declare it
// after everything the preview's states borrow.
struct FinishPreview {
  FitPreview* preview;
  ~FinishPreview();
};

// The modes. `preview` may be null.
// Each writes into the folder `out` (output_folder.h, with fit.json as its final file),
// which it locks once the fit is done, before the first file.
int invert_material(const InvertFitOptions& args, const std::filesystem::path& out, const std::string& mode,
                    FitPreview* preview);
int invert_lighting(const InvertFitOptions& args, const std::filesystem::path& out, bool joint, FitPreview* preview);

}  // namespace invert_fit
}  // namespace glaze
