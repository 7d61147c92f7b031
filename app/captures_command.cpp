// captures_command.cpp: `glaze captures SHOOT --out DIR`, a photo shoot turned into a
// capture set that invert-fit reads unchanged (docs/design.md §7). The stages, in order:
//   1. HDR: every bracket (view_NNN, probe_NNN) merged with one camera response;
//   2. registration: intrinsics, lens and each view's pose on the chessboard;
//   3. the object: a sphere located from its outline in the views, or as shoot.json gives it;
//   4. the probe: the mirror ball located likewise, its photos merged into a lat-long map
//      in board coordinates, divided by the ball's reflectance (given, or estimated by
//      a joint fit of the object against the probe); a sphere located from its outline
//      is located again with the probe (what its rim mirrors, predicted);
//   5. DIR/transforms.json, captures_report.json and summary.txt.
#include "app/commands.h"
#include "app/invert_fit.h"
#include "app/photo_outputs.h"
#include "app/shared_options.h"
#include "app/timing.h"
#include "inverse/photos/bracket.h"
#include "inverse/photos/hdr_merge.h"
#include "inverse/photos/mirror_ball_probe.h"
#include "inverse/photos/registration.h"
#include "inverse/photos/shoot.h"
#include "inverse/photos/sphere_outline.h"
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/output_folder.h"
#include "renderer/progress_bar.h"

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <unistd.h>
#include <variant>

namespace glaze {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct CapturesOptions {
  std::string shoot;
  std::string out;
  std::optional<std::string> response;
  Resolution probe_resolution{256, 128};
  int threads = 0;
};

// A merged bracket kept for the later stages: the object's views for the sphere's
// outline and the capture set, the ball's for the probe.
struct MergedView {
  std::string name;  // view_000, probe_000
  Image radiance;
  std::vector<float> alpha;
  std::string image;  // the EXR written into the capture set's folder
};

bool is_probe(const std::string& name) { return name.starts_with("probe_"); }

json vector_json(const Vec3d& v) { return {v.x(), v.y(), v.z()}; }

json sphere_json(const SphereFit& fit) {
  json views = json::array();
  for (const SphereViewFit& view : fit.views)
    views.push_back({{"view", view.name},
                     {"edges", view.points},
                     {"searched", view.samples},
                     {"rms_px", view.rms_px},
                     {"mean_signed_px", view.mean_signed_px},
                     {"rim_mirror", view.rim_mirror}});
  return {{"located", true},
          {"center", vector_json(fit.center)},
          {"radius", fit.radius},
          {"rms_px", fit.rms_px},
          {"rms_mm", fit.rms_mm},
          {"under_probe",
           std::any_of(fit.views.begin(), fit.views.end(), [](const SphereViewFit& view) { return view.rim_mirror; })},
          {"views", views},
          {"solver", fit.solver_summary}};
}

std::string millimetres(const Vec3d& v) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.2f, %.2f, %.2f) mm", 1e3 * v.x(), 1e3 * v.y(), 1e3 * v.z());
  return text;
}

// summary.txt: the report for people, a line or a few per stage.
std::string summary_text(const json& report, const std::string& shoot, const std::string& out) {
  std::ostringstream s;
  char line[512];
  s << "glaze captures: " << shoot << " -> " << out << "\n";
  const json& response = report["response"];
  if (response["method"] == "linear") {
    s << "response      linear (" << response["bits"].get<int>() << "-bit photos)\n";
  } else {
    std::snprintf(line, sizeof line, "response      %s, from %zu sample pixels of every bracket (response.png)\n",
                  response["method"].get<std::string>().c_str(), response["samples"].get<size_t>());
    s << line;
  }
  for (const json& bracket : report["brackets"]) {
    const json& exposures = bracket["exposures"];
    std::snprintf(line, sizeof line,
                  "%-13s %zu exposures, %.4g to %.4g s; saturated in every exposure %s, underexposed in every "
                  "exposure %s\n",
                  bracket["name"].get<std::string>().c_str(), exposures.size(),
                  exposures.front()["exposure"].get<double>(), exposures.back()["exposure"].get<double>(),
                  percent_text(bracket["saturated_fraction"].get<double>()).c_str(),
                  percent_text(bracket["underexposed_fraction"].get<double>()).c_str());
    s << line;
  }
  const json& registration = report["registration"];
  if (registration["intrinsics"] == "calibrated") {
    std::snprintf(line, sizeof line,
                  "registration  intrinsics and lens calibrated from %zu board photos, RMS %.3f px\n",
                  registration["calibration"]["photos"].size(),
                  registration["calibration"]["reprojection_error_px"].get<double>());
    s << line;
  } else {
    s << "registration  intrinsics and lens as shoot.json gives them\n";
  }
  for (const json& frame : registration["frames"]) {
    std::snprintf(line, sizeof line, "%-13s reprojection error %.3f px\n", frame["view"].get<std::string>().c_str(),
                  frame["reprojection_error_px"].get<double>());
    s << line;
  }
  for (const char* key : {"object", "ball"}) {
    if (!report.contains(key) || !report[key].contains("radius")) continue;
    const json& sphere = report[key];
    const Vec3d center(sphere["center"][0].get<double>(), sphere["center"][1].get<double>(),
                       sphere["center"][2].get<double>());
    std::snprintf(line, sizeof line, "%-13s centre %s, radius %.3f mm",
                  key == std::string("object") ? "sphere" : "ball", millimetres(center).c_str(),
                  1e3 * sphere["radius"].get<double>());
    s << line;
    if (sphere["located"].get<bool>()) {
      std::snprintf(line, sizeof line, ", located from its outline%s: RMS %.3f px (%.3f mm at the sphere)",
                    sphere.value("under_probe", false) ? " and the probe's reflection in its rim" : "",
                    sphere["rms_px"].get<double>(), sphere["rms_mm"].get<double>());
      s << line;
      for (const json& view : sphere["views"]) {
        std::snprintf(line, sizeof line, "; %s %.3f px", view["view"].get<std::string>().c_str(),
                      view["rms_px"].get<double>());
        s << line;
      }
    } else {
      s << ", as shoot.json gives it";
    }
    s << "\n";
  }
  if (report.contains("probe")) {
    const json& probe = report["probe"];
    std::snprintf(line, sizeof line,
                  "probe         %dx%d lat-long (environment.exr), %.1f%% of directions covered; reflectance %.4f "
                  "%.4f %.4f (%s)\n",
                  probe["resolution"][0].get<int>(), probe["resolution"][1].get<int>(),
                  100 * probe["covered_fraction"].get<double>(), probe["reflectance"][0].get<double>(),
                  probe["reflectance"][1].get<double>(), probe["reflectance"][2].get<double>(),
                  probe["reflectance_source"].get<std::string>().c_str());
    s << line;
  } else {
    s << "probe         none (no probe_NNN folder): fit the lighting with invert-fit --mode joint\n";
  }
  s << "seconds      ";
  for (const auto& [stage, seconds] : report["stage_seconds"].items()) {
    std::snprintf(line, sizeof line, " %s %.2f,", stage.c_str(), seconds.get<double>());
    s << line;
  }
  s.seekp(-1, std::ios_base::cur);
  s << "\n";
  return s.str();
}

class CapturesRun {
 public:
  CapturesRun(const CapturesOptions& args, const Shoot& shoot, const std::vector<Bracket>& brackets)
      : args_(args),
        shoot_(shoot),
        brackets_(brackets),
        out_(args.out, "captures_report.json", "capture set"),
        // Steps: the response (one per bracket read), each merge, registration, sphere, probe,
        // the sphere under the probe, the reflectance, output (a stage skipped still counts).
        progress_(isatty(STDERR_FILENO), int(2 * brackets.size()) + 6) {}

  int run() {
    merge_brackets();
    register_views();
    locate_object();
    build_probe();
    locate_object_under_probe();
    estimate_reflectance();
    write_capture_set();
    return 0;
  }

 private:
  void stage(const std::string& label) {
    progress_.label(label);
    stage_start_ = Clock::now();
  }
  void end_stage(const std::string& name, int steps = 1) {
    seconds_[name] = seconds_since(stage_start_);
    progress_.advance(steps);
  }

  void merge_brackets() {
    stage("camera response");
    response_ = bracket_response(brackets_, args_.response);
    end_stage("response", int(brackets_.size()));
    report_["response"] = response_json(response_);
    write_response(out_, response_, report_);
    report_["brackets"] = json::array();
    stage("merging brackets");
    for (const Bracket& bracket : brackets_) {
      progress_.label("merging " + bracket.name());
      MergedBracket merged = read_and_merge(bracket, response_);
      json entry = write_merged(out_, bracket, merged, response_);
      views_.push_back({bracket.name(), std::move(merged.merge.radiance), std::move(merged.merge.alpha),
                        entry["image"].get<std::string>()});
      report_["brackets"].push_back(entry);
      progress_.advance();
    }
    seconds_["hdr_merge"] = seconds_since(stage_start_);
  }

  void register_views() {
    stage("registration");
    registration_ = register_shoot(shoot_);
    report_["registration"] = registration_json(registration_, shoot_.folder);
    end_stage("registration");
  }

  // The registered camera of the bracket named `name` (view_000 ...).
  PinholeCamera camera_of(const std::string& name) const {
    for (size_t k = 0; k < registration_.views.size(); ++k)
      if (registration_.views[k].name == name) return registered_camera(registration_, k);
    throw Error(shoot_.folder.string() + "/" + name + ": was not registered (no board photo?)");
  }

  // The sphere that the object's views (or the ball's, `probe`) show, from its outline.
  // `lighting`: what the sphere's rim mirrors (locate_sphere).
  SphereFit locate(bool probe, const Environment* lighting = nullptr) {
    std::vector<SphereView> views;
    for (const MergedView& view : views_)
      if (is_probe(view.name) == probe)
        views.push_back({(shoot_.folder / view.name).string(), view.radiance, view.alpha, {}, camera_of(view.name)});
    return locate_sphere(views, {}, lighting);
  }

  void locate_object() {
    stage("locating the sphere");
    const ShootObject& object = *shoot_.object;
    json entry;
    if (object.kind == ShootObject::Kind::gltf) {
      object_ = CaptureGltf{object.gltf.string()};
      entry = {{"gltf", object.gltf.string()}, {"located", false}};
    } else if (object.kind == ShootObject::Kind::sphere) {
      object_ = CaptureSphere{Vec3d(object.center[0], object.center[1], object.center[2]).cast<float>(),
                              float(object.radius)};
      entry = {{"center", object.center}, {"radius", object.radius}, {"located", false}};
    } else {
      set_located_object(locate(false));
      entry = sphere_json(*sphere_);
    }
    report_["object"] = entry;
    end_stage("sphere");
  }

  void set_located_object(SphereFit fit) {
    sphere_ = std::move(fit);
    object_ = CaptureSphere{sphere_->center.cast<float>(), float(sphere_->radius)};
  }

  void build_probe() {
    stage("light probe");
    make_probe();
    end_stage("probe");
  }

  // The probe from the probe_NNN views, if any, and its report.
  void make_probe() {
    std::vector<ProbeView> views;
    for (const MergedView& view : views_)
      if (is_probe(view.name)) views.push_back({view.name, view.radiance, view.alpha, camera_of(view.name)});
    if (views.empty()) return;
    const MirrorBall ball = locate_ball();
    MirrorBallProbeOptions options;
    std::tie(options.width, options.height) = args_.probe_resolution.pair();
    // Made with reflectance 1 (the ball's radiance as seen) when the reflectance is to be
    // estimated: then it is the lighting times the reflectance.
    if (shoot_.probe.reflectance) options.reflectance = RGBd(shoot_.probe.reflectance->data()).cast<float>();
    probe_ = build_mirror_ball_probe(views, ball, options);
    report_["probe"] = {{"resolution", {options.width, options.height}},
                        {"covered_fraction", probe_->covered_fraction},
                        {"reflectance", invert_fit::rgb_json(options.reflectance)},
                        {"reflectance_source", shoot_.probe.reflectance ? "given" : "estimated"}};
    for (const ProbeViewContribution& view : probe_->views)
      report_["probe"]["views"].push_back(
          {{"view", view.name}, {"weight_share", view.weight_share}, {"covered_fraction", view.covered_fraction}});
  }

  // Under a detailed background the coat's rim mirrors detail that the outline's model
  // does not follow, and the probe says what it mirrors (locate_sphere's lighting): the
  // sphere located from its outline is located again under the probe (its scale does not
  // matter: each view's is taken from its background). A ball placed where the object
  // rests follows it, and its probe is built again.
  // Should the second location fail (too few edges, its views in disagreement), the
  // first stands, with a warning.
  void locate_object_under_probe() {
    if (!sphere_ || !probe_) return progress_.advance();
    stage("locating the sphere under the probe");
    EnvironmentOptions options;
    options.to_world = probe_->to_world;
    const Environment lighting(probe_->map, options, "the light probe");
    try {
      set_located_object(locate(false, &lighting));
      report_["object"] = sphere_json(*sphere_);
      if (ball_rests_on_object()) make_probe();
    } catch (const Error& error) {
      warn(std::string(error.what()) + " (locating the sphere again with the probe's reflection in its rim: " +
           "the sphere located from its outline alone is kept)");
    }
    end_stage("sphere_under_probe");
  }

  // The mirror ball: as shoot.json gives it; else, given its radius, resting where the
  // object rests (the simulator's and a tripod-free shoot's setup: the ball put in the
  // object's place on the table, the board's plane z = 0); else located from its outline.
  // A chrome ball's outline is weak where it mirrors the background at grazing angles:
  // its location is the least reliable of the three, hence the warning.
  // shoot.json gives the ball's radius alone: it is placed where the object rests.
  bool ball_rests_on_object() const { return !shoot_.probe.center && shoot_.probe.radius; }

  MirrorBall locate_ball() {
    const ShootProbe& given = shoot_.probe;
    if (given.center) {
      report_["ball"] = {{"center", *given.center}, {"radius", *given.radius}, {"located", false}};
      return {Vec3d(given.center->data()), *given.radius};
    }
    if (ball_rests_on_object()) {
      const CaptureSphere* sphere = std::get_if<CaptureSphere>(&object_);
      if (!sphere)
        throw Error(shoot_.file +
                    ": \"probe\" gives the ball's radius but not its centre, which is taken from the object's place "
                    "on the table when the object is a sphere; with a glTF object give \"probe\": {\"center\": [x, y, "
                    "z], \"radius\": r} in board coordinates");
      const Vec3d center = sphere->center.cast<double>() + Vec3d(0, 0, *given.radius - sphere->radius);
      report_["ball"] = {{"center", vector_json(center)},
                         {"radius", *given.radius},
                         {"located", false},
                         {"placed", "resting where the object rests"}};
      return {center, *given.radius};
    }
    warn(shoot_.file +
         ": the mirror ball is located from its outline, which a chrome ball shows weakly where it mirrors the "
         "background; give its radius (\"probe\": {\"radius\": r}) to place it where the object rests");
    ball_ = locate(true);
    report_["ball"] = sphere_json(*ball_);
    return {ball_->center, ball_->radius};
  }

  // The capture set as it stands, in memory, its images already in the output folder.
  CaptureSet capture_set() const {
    CaptureSet captures;
    for (const MergedView& view : views_)
      if (!is_probe(view.name)) captures.frames.push_back({out_.file(view.image).string(), camera_of(view.name), ""});
    captures.object = object_;
    captures.directory = out_.path().string();
    return captures;
  }

  // Without a given reflectance: the joint fit of the object (invert-fit --mode joint)
  // recovers the lighting at its absolute scale, which the probe (made with reflectance
  // 1) shows times the reflectance; their ratio over the directions both see is it.
  void estimate_reflectance() {
    if (!probe_ || shoot_.probe.reflectance) return progress_.advance();
    stage("estimating the ball's reflectance");
    json seconds;
    invert_fit::InvertFitOptions fit_options;
    invert_fit::FitInputs in = invert_fit::prepare_inputs(capture_set(), fit_options.samples, seconds);
    invert_fit::LightingProblem problem = invert_fit::lighting_problem(fit_options, in);
    const JointFit joint = invert_fit::solve_joint(problem, in.samples, fit_options);
    // The joint fit's map (world frame) and coverage, read in the probe's frame.
    const LatlongResample absolute = resample_into_probe_frame(joint.lighting.map, joint.lighting.covered,
                                                               Mat3::Identity(), probe_->map.width, probe_->map.height);
    const ReflectanceRatio ratio = reflectance_ratio(probe_->map, probe_->covered, absolute.map, absolute.covered);
    if (!(ratio.reflectance > 0.0).all() || !ratio.reflectance.isFinite().all())
      throw Error(shoot_.file +
                  ": the mirror ball's reflectance could not be estimated (the joint fit's lighting and "
                  "the probe share " +
                  std::to_string(ratio.texels) +
                  " directions); give it as \"probe\": {\"reflectance\": x} (a chrome ball: about 0.6)");
    if ((ratio.reflectance > 1.0).any() || (ratio.reflectance < 0.2).any())
      warn(shoot_.file + ": the mirror ball's reflectance is estimated at " +
           invert_fit::rgb_json(ratio.reflectance.cast<float>()).dump() +
           ", outside what mirror balls have (0.2 to 1): check the probe and the joint fit in captures_report.json, "
           "or give the reflectance in shoot.json");
    for (size_t k = 0; k < probe_->map.pixels.size(); ++k) probe_->map.pixels[k] /= float(ratio.reflectance[k % 3]);
    report_["probe"]["reflectance"] = invert_fit::rgb_json(ratio.reflectance.cast<float>());
    report_["probe"]["reflectance_fit"] = {{"texels", ratio.texels},
                                           {"relative_rms", invert_fit::rgb_json(ratio.relative_rms.cast<float>())}};
    report_["probe"]["joint_fit"] = {{"R0", joint.R0},
                                     {"Rd", invert_fit::rgb_json(joint.Rd)},
                                     {"rms", joint.rms},
                                     {"converged", joint.converged},
                                     {"covered_fraction", joint.lighting.covered_fraction}};
    end_stage("reflectance");
  }

  void write_capture_set() {
    stage("writing the capture set");
    CaptureSet captures = capture_set();
    for (CaptureFrame& frame : captures.frames) frame.file_path = fs::path(frame.file_path).filename().string();
    if (probe_) {
      write_mirror_ball_probe(out_, *probe_, "environment.exr", "environment_coverage.png");
      EnvironmentOptions options;
      options.to_world = probe_->to_world;
      captures.environment = CaptureEnvironment{"environment.exr", "", options};
    }
    captures.run = out_.run();
    write_transforms(out_.path().string(), captures);
    end_stage("output");
    report_["stage_seconds"] = seconds_;
    const std::string summary = summary_text(report_, shoot_.folder.string(), out_.path().string());
    out_.write_text("summary.txt", summary);
    report_["summary"] = "summary.txt";
    report_["run"] = out_.run();
    out_.finish(report_.dump(2) + "\n");
    std::cout << summary;
  }

  const CapturesOptions& args_;
  const Shoot& shoot_;
  const std::vector<Bracket>& brackets_;
  OutputFolder out_;
  ProgressBar progress_;
  Clock::time_point stage_start_ = Clock::now();
  json report_;
  json seconds_;
  CameraResponse response_;
  std::vector<MergedView> views_;
  Registration registration_;
  CaptureObject object_;
  std::optional<SphereFit> sphere_, ball_;
  std::optional<MirrorBallProbe> probe_;
};

int captures(const CapturesOptions& args) {
  const auto start = Clock::now();
  const Shoot shoot = read_shoot(args.shoot);
  if (!shoot.object)
    throw Error(shoot.file +
                ": \"object\" is missing: say what was photographed, {\"type\": \"sphere\"} to locate a sphere from "
                "its outline, {\"type\": \"sphere\", \"center\": [x, y, z], \"radius\": r} in board coordinates, or "
                "{\"gltf\": FILE}");
  shoot_views(shoot);  // every view and probe folder has its board photo, before hours of work
  const std::vector<Bracket> brackets = find_brackets(shoot.folder);
  CapturesRun(args, shoot, brackets).run();
  std::printf("wrote %s (%.1f s)\n", (fs::path(args.out) / "transforms.json").string().c_str(), seconds_since(start));
  return 0;
}

}  // namespace

CommandRun declare_captures(CLI::App& app) {
  auto args = std::make_shared<CapturesOptions>();
  app.description(
      "turn a photo shoot into a capture set: HDR merge, registration on the chessboard, the sphere from its "
      "outline and the light probe from the mirror ball");
  add_text(app, "SHOOT", args->shoot, "the photo shoot: a folder with shoot.json (or the file itself)")->required();
  add_text(app, "--out DIR", args->out,
           "the capture set: transforms.json, the views' HDR images, environment.exr (the probe), "
           "captures_report.json, summary.txt")
      ->required();
  add_text(app, "--response FILE.json", args->response, "a response.json to use instead of recovering one");
  add_resolution(app, "--probe-res WxH", args->probe_resolution, "the probe's lat-long map (default 256x128)");
  add_threads(app, args->threads)->description("worker threads (0: all cores; the results do not depend on it)");
  return [args] {
    tbb::task_arena arena(args->threads > 0 ? args->threads : tbb::task_arena::automatic);
    return arena.execute([&] { return captures(*args); });
  };
}

}  // namespace glaze
