#include "renderer/capture_set.h"

#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/input_file.h"
#include "renderer/json_input.h"
#include "renderer/output_folder.h"
#include "renderer/procedural_environment.h"
#include "renderer/scene.h"
#include "renderer/text_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <utility>

namespace glaze {
namespace {

using nlohmann::json;

// The keys of the material's parameters, as the registry names them.
std::string key(MaterialParameter parameter) { return std::string(parameter_spec(parameter).name); }

json rows(const auto& matrix) {
  json rows = json::array();
  for (int r = 0; r < matrix.rows(); ++r) {
    json row = json::array();
    for (int c = 0; c < matrix.cols(); ++c) row.push_back(matrix(r, c));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

json intrinsics_json(const PinholeCamera& c) {
  json entry = {{"w", c.width}, {"h", c.height}, {"fl_x", c.fl_x}, {"fl_y", c.fl_y}, {"cx", c.cx}, {"cy", c.cy}};
  LensDistortion lens = c.distortion;
  entry["camera_model"] = camera_model_name(lens.model);
  for (const char* name : kDistortionCoefficients)
    // OPENCV's k3 is optional (COLMAP's OPENCV has none).
    if (model_uses(lens.model, name) &&
        !(lens.model == LensDistortion::Model::opencv && name == std::string("k3") && lens.k3 == 0.0))
      entry[name] = coefficient(lens, name);
  return entry;
}

namespace {

json object_json(const CaptureObject& object) {
  if (const CaptureGltf* gltf = std::get_if<CaptureGltf>(&object)) return {{"gltf", gltf->file}};
  const CaptureSphere& sphere = std::get<CaptureSphere>(object);
  return {{"type", "sphere"},
          {"center", {sphere.center.x(), sphere.center.y(), sphere.center.z()}},
          {"radius", sphere.radius}};
}

json material_json(const CaptureMaterial& material) {
  const RGB& Rd = material.material.Rd();
  json entry = {{key(MaterialParameter::R0), material.material.R0()},
                {key(MaterialParameter::Rd), {Rd[0], Rd[1], Rd[2]}}};
  if (!material.texture.empty()) entry["texture"] = material.texture;
  return entry;
}

json renderer_json(const CaptureRenderer& renderer) {
  if (renderer.integrator == CaptureRenderer::Integrator::sh)
    return {{"integrator", "sh"}, {"ss", renderer.supersampling}, {"lmax", renderer.lmax}};
  return {{"integrator", "path"}, {"spp", renderer.spp}};
}

}  // namespace

void check_capture_camera(const PinholeCamera& camera) {
  if (camera.projection != Projection::perspective)
    throw Error("camera '" + camera.name +
                "' is orthographic; a capture set (transforms.json) holds perspective cameras only: leave it out, "
                "or give the view a perspective camera");
  camera.check_lens("camera '" + camera.name + "'");
}

std::string transforms_json(const CaptureSet& captures) {
  if (captures.frames.empty()) throw Error("a capture set needs at least one frame");
  for (const CaptureFrame& frame : captures.frames) check_capture_camera(frame.camera);
  json root = json::object();
  const json shared = intrinsics_json(captures.frames.front().camera);
  bool all_shared = true;
  for (const CaptureFrame& frame : captures.frames) all_shared = all_shared && intrinsics_json(frame.camera) == shared;
  if (all_shared) root.update(shared);
  if (captures.saturation) root["saturation"] = *captures.saturation;
  json frames = json::array();
  for (const CaptureFrame& frame : captures.frames) {
    json entry = {{"file_path", frame.file_path},
                  {"camera", frame.camera.name},
                  {"transform_matrix", rows(frame.camera.camera_to_world.matrix())}};
    if (!frame.mask_path.empty()) entry["mask_path"] = frame.mask_path;
    if (!all_shared) entry.update(intrinsics_json(frame.camera));
    frames.push_back(entry);
  }
  root["frames"] = frames;
  root["object"] = object_json(captures.object);
  if (captures.environment) root["environment"] = environment_json(*captures.environment);
  if (captures.material) root["material"] = material_json(*captures.material);
  if (captures.renderer) root["renderer"] = renderer_json(*captures.renderer);
  if (!captures.run.empty()) root["run"] = captures.run;
  return root.dump(2) + "\n";
}

void write_transforms(const std::string& directory, const CaptureSet& captures) {
  if (captures.frames.empty()) throw Error(directory + ": a capture set needs at least one frame");
  write_text_atomically((std::filesystem::path(directory) / "transforms.json").string(), transforms_json(captures));
}  // namespace

nlohmann::json environment_json(const CaptureEnvironment& environment) {
  json entry = {{"scale", environment.options.scale},
                {"rotation", environment.options.rotation_degrees},
                {"to_world", rows(environment.options.to_world)}};
  if (!environment.file.empty()) entry["file"] = environment.file;
  if (environment.options.format != EnvironmentFormat::automatic)
    entry["format"] = environment_format_name(environment.options.format);
  if (!environment.procedural.empty()) entry["procedural"] = environment.procedural;
  return entry;
}

// ---------------------------------------------------------------------------------------
// Reading. Every message starts with where the problem is ("DIR/transforms.json: frame 2
// ("view_002.exr")"), then says what is wrong and what is expected instead.
// ---------------------------------------------------------------------------------------

namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& where, const std::string& problem) { throw Error(where + ": " + problem); }

std::string quoted(const std::string& key) { return "\"" + key + "\""; }

// What a number must be, and how messages say it. Values are stored as floats, so even
// "any finite number" excludes those a float cannot hold (1e300 parses as a double).
struct Range {
  double low, high;
  bool low_excluded;
  bool integer;
  std::string text;
};
constexpr double kFloatMax = std::numeric_limits<float>::max();
const Range kFinite{-kFloatMax, kFloatMax, false, false, "a finite number"};
const Range kPositive{0.0, kFloatMax, true, false, "a finite number > 0"};
const Range kCoordinate{-kLargestCoordinate, kLargestCoordinate, false, false, "a finite number within +-1e15"};
const Range kNonNegative{0.0, kFloatMax, false, false, "a finite number >= 0"};
const Range kPixels{1.0, 65536.0, false, true, "a whole number of pixels from 1 to 65536"};
// Counts held exactly by a float.
const Range kCount{1.0, 16777216.0, false, true, "a whole number from 1 to 16777216"};
const Range kLmax{0.0, double(kShMaxLmax), false, true, "a whole number from 0 to " + std::to_string(kShMaxLmax)};

// A material parameter (material.h) within its bounds.
Range parameter_range(MaterialParameter parameter) {
  const ParameterSpec& spec = parameter_spec(parameter);
  const auto text = [](double x) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g", x);
    return std::string(buffer);
  };
  return {spec.lower, spec.upper, false, false, "a number in [" + text(spec.lower) + ", " + text(spec.upper) + "]"};
}

// Every number in the file is read through here: a JSON number within `range`.
double number_double(const json& value, const std::string& where, const std::string& key, const Range& range) {
  const double x = value.is_number() ? value.get<double>() : std::nan("");
  const bool ok = x >= range.low && x <= range.high && !(range.low_excluded && x == range.low) &&
                  !(range.integer && x != std::floor(x));
  if (!ok) fail(where, quoted(key) + " must be " + range.text + ", not " + json_excerpt(value));
  return x;
}
float number(const json& value, const std::string& where, const std::string& key, const Range& range) {
  return float(number_double(value, where, key, range));
}

// An array of `count` numbers, each in `range`.
std::vector<float> numbers(const json& value, size_t count, const std::string& where, const std::string& key,
                           const Range& range) {
  if (!value.is_array() || value.size() != count)
    fail(where, quoted(key) + " must be an array of " + std::to_string(count) + " numbers, not " + json_excerpt(value));
  std::vector<float> result;
  for (size_t i = 0; i < count; ++i)
    result.push_back(number(value[i], where, key + "[" + std::to_string(i) + "]", range));
  return result;
}

// object[key], which must be there; `expected` says what it should be.
const json& member(const json& object, const std::string& key, const std::string& where, const std::string& expected) {
  if (!object.contains(key)) fail(where, "no " + quoted(key) + " (" + expected + ")");
  return object.at(key);
}

// The transforms.json that `path` names: the file itself, or the one in a directory.
// What kind of file it is, read_json_file checks when it opens it.
fs::path transforms_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw Error(path + ": no such file or directory; give a capture directory or its transforms.json");
  const fs::path file = fs::is_directory(path, ec) ? fs::path(path) / "transforms.json" : fs::path(path);
  if (!fs::exists(file, ec))
    throw Error(file.string() +
                ": not found; a capture directory holds a transforms.json "
                "(glaze render --captures writes one)");
  return file;
}

// Reads one parsed transforms.json.
class TransformsReader {
 public:
  TransformsReader(const fs::path& file, const json& root)
      : file_(file.string()), directory_(file.has_parent_path() ? file.parent_path() : fs::path(".")), root_(root) {}

  CaptureSet read() const {
    if (!root_.is_object())
      fail(file_, "the top level must be an object {\"frames\": [...], \"object\": {...}, ...}, not " +
                      std::string(root_.type_name()));
    const json& frames =
        member(root_, "frames", file_, "the views: [{\"file_path\": ..., \"transform_matrix\": ...}, ...]");
    if (!frames.is_array() || frames.empty())
      fail(file_,
           "\"frames\" must be a non-empty array of views {\"file_path\": ..., \"transform_matrix\": ...}, not " +
               json_excerpt(frames));
    CaptureSet set;
    set.directory = directory_.string();
    set.file = file_;
    for (size_t i = 0; i < frames.size(); ++i) set.frames.push_back(frame(frames[i], i));
    const AppliedTransform applied = applied_transform();
    for (CaptureFrame& frame : set.frames) frame.camera.camera_to_world = applied.undo(frame.camera.camera_to_world);
    set.object = object();
    set.environment = environment();
    set.material = material();
    if (root_.contains("saturation")) set.saturation = number(root_.at("saturation"), file_, "saturation", kPositive);
    set.renderer = renderer();
    return set;
  }

 private:
  // A path named in the file, resolved against its directory (operator/ keeps absolute
  // paths as they are).
  fs::path resolved_file(const json& value, const std::string& where, const std::string& key) const {
    if (!value.is_string() || value.get<std::string>().empty())
      fail(where, quoted(key) + " must be a file name (a non-empty string), not " + json_excerpt(value));
    return directory_ / value.get<std::string>();
  }

  // The same, which must name an existing file.
  std::string existing_file(const json& value, const std::string& where, const std::string& key) const {
    const fs::path resolved = resolved_file(value, where, key);
    std::error_code ec;
    if (!fs::exists(resolved, ec))
      fail(where, quoted(key) + " names " + resolved.string() +
                      ", which does not exist; relative paths are relative to " + directory_.string());
    try {
      require_regular_file(resolved.string(), quoted(key));
    } catch (const Error& e) {
      fail(where, quoted(key) + " names something that is not a file: " + e.what());
    }
    return resolved.string();
  }

  // A frame's own value for `key`, else the top-level one shared by all frames (null if
  // neither), with where it came from.
  std::pair<const json*, std::string> setting(const json& frame, const std::string& frame_where,
                                              const std::string& key) const {
    if (frame.contains(key)) return {&frame.at(key), frame_where};
    if (root_.contains(key)) return {&root_.at(key), file_};
    return {nullptr, frame_where};
  }

  CaptureFrame frame(const json& entry, size_t index) const {
    std::string where = file_ + ": frame " + std::to_string(index);
    if (!entry.is_object())
      fail(where, "must be an object {\"file_path\": ..., \"transform_matrix\": ...}, not " + json_excerpt(entry));
    const json& file_path = member(entry, "file_path", where, "the image's file name");
    where += " (" + json_excerpt(file_path) + ")";
    CaptureFrame frame;
    frame.file_path = image_file(file_path, where);
    if (entry.contains("mask_path")) frame.mask_path = existing_file(entry.at("mask_path"), where, "mask_path");
    frame.camera = camera(with_image_intrinsics(entry, where, frame.file_path), index, where);
    return frame;
  }

  // "file_path" as nerfstudio resolves it: the path as given, else, for a path without an
  // extension (NeRF-synthetic's "./train/r_0"), that path + ".png" (nerfstudio's Blender
  // data parser appends ".png" to every path; its own format takes paths as they are).
  std::string image_file(const json& value, const std::string& where) const {
    const fs::path resolved = resolved_file(value, where, "file_path");
    std::error_code ec;
    if (resolved.has_extension() || fs::exists(resolved, ec)) return existing_file(value, where, "file_path");
    const fs::path png = fs::path(resolved).concat(".png");
    if (!fs::exists(png, ec))
      fail(where, "\"file_path\" names " + resolved.string() + ", which does not exist, nor does " + png.string() +
                      " (tried for a path without an extension, as NeRF-synthetic sets write them); relative "
                      "paths are relative to " +
                      directory_.string());
    return existing_file(json(value.get<std::string>() + ".png"), where, "file_path");
  }

  // `entry` with the intrinsics it leaves out derived as Blender and NeRF-synthetic sets
  // imply them: "w" and "h" from the image file's header; from "camera_angle_x" (the
  // horizontal field of view in radians) fl_x = w / 2 / tan(camera_angle_x / 2), fl_y the
  // same from "camera_angle_y" if given, else fl_x (square pixels); cx = w / 2, cy = h / 2.
  // A value given in the file, per frame or at the top, wins over a derived one.
  json with_image_intrinsics(const json& entry, const std::string& where, const std::string& image) const {
    const auto given = [&](const std::string& key) { return setting(entry, where, key).first != nullptr; };
    json completed = entry;
    if (!given("w") || !given("h")) {
      ImageSize size;
      try {
        size = image_size(image);
      } catch (const Error& e) {
        fail(where, std::string("the image's size (\"w\", \"h\" are not given) cannot be read: ") + e.what());
      }
      if (!given("w")) completed["w"] = size.width;
      if (!given("h")) completed["h"] = size.height;
    }
    const auto value = [&](const std::string& key) {
      const auto [v, v_where] = setting(completed, where, key);
      return double(number(*v, v_where, key, kPixels));
    };
    const double width = value("w"), height = value("h");
    const auto focal = [&](const std::string& angle_key, double pixels) -> std::optional<double> {
      const auto [angle, angle_where] = setting(entry, where, angle_key);
      if (!angle) return std::nullopt;
      const Range kAngle{0.0, 3.14, true, false, "an angle of view in radians, in (0, 3.14]"};
      return 0.5 * pixels / std::tan(0.5 * double(number(*angle, angle_where, angle_key, kAngle)));
    };
    const std::optional<double> fl_x = focal("camera_angle_x", width), fl_y = focal("camera_angle_y", height);
    if (!given("fl_x") && (fl_x || fl_y)) completed["fl_x"] = fl_x ? *fl_x : *fl_y;
    if (!given("fl_y") && (fl_x || fl_y)) completed["fl_y"] = fl_y ? *fl_y : *fl_x;
    if ((fl_x || fl_y) && !given("cx")) completed["cx"] = 0.5 * width;
    if ((fl_x || fl_y) && !given("cy")) completed["cy"] = 0.5 * height;
    return completed;
  }

  PinholeCamera camera(const json& frame, size_t index, const std::string& where) const {
    PinholeCamera camera;
    if (frame.contains("camera")) {
      if (!frame.at("camera").is_string())
        fail(where, "\"camera\" must be the camera's name (a string), not " + json_excerpt(frame.at("camera")));
      camera.name = frame.at("camera").get<std::string>();
    } else {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%03zu", index);
      camera.name = name;
    }
    const auto intrinsic = [&](const std::string& key, const Range& range) {
      const auto [value, value_where] = setting(frame, where, key);
      if (!value)
        fail(where, "no " + quoted(key) +
                        "; give the intrinsics w, h, fl_x, fl_y, cx, cy (in pixels) at the top level, "
                        "shared by all frames, or in each frame");
      return number(*value, value_where, key, range);
    };
    camera.width = int(intrinsic("w", kPixels));
    camera.height = int(intrinsic("h", kPixels));
    camera.fl_x = intrinsic("fl_x", kPositive);
    camera.fl_y = intrinsic("fl_y", kPositive);
    camera.cx = intrinsic("cx", kFinite);
    camera.cy = intrinsic("cy", kFinite);
    camera.camera_to_world = pose(frame, where);
    camera.distortion = lens(frame, where);
    camera.check_lens(where);
    return camera;
  }

  // The lens ("camera_model" and the coefficients), as nerfstudio reads them: without a
  // model, coefficients mean OPENCV. Models glaze does not cast rays through are refused
  // rather than read as a pinhole, which would misplace every pixel but the centre.
  LensDistortion lens(const json& frame, const std::string& where) const {
    LensDistortion lens;
    bool any = false;
    for (const char* key : kDistortionCoefficients) {
      const auto [value, value_where] = setting(frame, where, key);
      if (!value) continue;
      coefficient(lens, key) = number_double(*value, value_where, key, kFinite);
      any = any || coefficient(lens, key) != 0.0;
    }
    const auto [model, model_where] = setting(frame, where, "camera_model");
    const std::string remedy = std::string("; ") + kSupportedCameraModels +
                               ": undistort the images to one of these (e.g. with COLMAP's image_undistorter)";
    if (model && !model->is_string())
      fail(model_where, "\"camera_model\" must be a string" + remedy + ", not " + json_excerpt(*model));
    const std::string name = model ? model->get<std::string>() : "OPENCV";
    const std::optional<LensDistortion::Model> parsed = camera_model_from_name(name);
    if (!parsed) fail(model_where, "\"camera_model\" " + json_excerpt(*model) + " is not supported" + remedy);
    for (const char* key : kDistortionCoefficients)
      if (coefficient(lens, key) != 0.0 && !model_uses(*parsed, key))
        fail(model ? model_where : where, quoted(key) + " = " + json_excerpt(coefficient(lens, key)) +
                                              " is not a coefficient of the " + name + " camera model" +
                                              (model ? "" : " (assumed: no \"camera_model\" given)") + remedy);
    // OPENCV with zero coefficients is a pinhole; OPENCV_FISHEYE with zeros is not (theta' = theta).
    lens.model = *parsed == LensDistortion::Model::opencv && !any ? LensDistortion::Model::none : *parsed;
    return lens;
  }

  // "transform_matrix": 4x4 row-major camera-to-world, which must be rigid (the renderer
  // and the fit assume unit-length rays and an undistorted frame).
  Eigen::Affine3f pose(const json& frame, const std::string& where) const {
    const json& rows = member(frame, "transform_matrix", where, "the 4x4 row-major camera-to-world pose");
    if (!rows.is_array() || rows.size() != 4)
      fail(where,
           "\"transform_matrix\" must be 4 rows of 4 numbers (row-major camera-to-world), not " + json_excerpt(rows));
    Eigen::Matrix4f m;
    for (int r = 0; r < 4; ++r) {
      const std::vector<float> row =
          numbers(rows[r], 4, where, "transform_matrix[" + std::to_string(r) + "]", kCoordinate);
      for (int c = 0; c < 4; ++c) m(r, c) = row[c];
    }
    const std::string rigid =
        "; the pose must be a rigid camera-to-world transform (rotation and translation, "
        "no scale, shear or mirroring)";
    if ((m.row(3) - Eigen::RowVector4f(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-4f)
      fail(where, "the last row of \"transform_matrix\" is " + json_excerpt(rows[3]) + ", not [0, 0, 0, 1]" + rigid);
    const Mat3 rotation = m.topLeftCorner<3, 3>();
    const float deviation = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
    if (deviation > 1e-3f || rotation.determinant() <= 0.0f)
      fail(where, "the upper-left 3x3 of \"transform_matrix\" is not a rotation (R^T R differs from I by up to " +
                      std::to_string(deviation) + ", det R = " + std::to_string(rotation.determinant()) + ")" + rigid);
    Eigen::Affine3f pose = Eigen::Affine3f::Identity();
    pose.linear() = rotation;
    pose.translation() = m.topRightCorner<3, 1>();
    return pose;
  }

  // nerfstudio's ns-process-data maps COLMAP's poses into its own world frame (z up) and
  // says how: "applied_transform" A (3x4, rigid) and optionally "applied_scale" s. The
  // poses as written are A times COLMAP's, their positions then scaled by s (nerfstudio
  // maps COLMAP's point cloud by s A to match). glaze takes "object" and "environment" in
  // the original frame (COLMAP's, where a user measures what the reconstruction shows),
  // and so undoes the transform on the poses.
  struct AppliedTransform {
    Eigen::Affine3f transform = Eigen::Affine3f::Identity();
    float scale = 1.0f;
    Eigen::Affine3f undo(Eigen::Affine3f pose) const {
      pose.translation() /= scale;
      return transform.inverse() * pose;
    }
  };
  AppliedTransform applied_transform() const {
    AppliedTransform applied;
    if (root_.contains("applied_transform")) {
      const json& rows = root_.at("applied_transform");
      const std::string where = file_ + ": \"applied_transform\"";
      if (!rows.is_array() || (rows.size() != 3 && rows.size() != 4))
        fail(where,
             "must be 3 rows of 4 numbers (the rigid transform applied to the poses), not " + json_excerpt(rows));
      Eigen::Matrix<float, 3, 4> m;
      for (int r = 0; r < 3; ++r) {
        const std::vector<float> row = numbers(rows[r], 4, where, "row " + std::to_string(r), kCoordinate);
        for (int c = 0; c < 4; ++c) m(r, c) = row[c];
      }
      const Mat3 rotation = m.leftCols<3>();
      const float deviation = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
      if (deviation > 1e-3f || rotation.determinant() <= 0.0f)
        fail(where, "its left 3x3 is not a rotation (R^T R differs from I by up to " + std::to_string(deviation) +
                        "); nerfstudio writes a rotation and translation here");
      applied.transform.linear() = rotation;
      applied.transform.translation() = m.col(3);
    }
    if (root_.contains("applied_scale"))
      applied.scale = number(root_.at("applied_scale"), file_, "applied_scale", kPositive);
    return applied;
  }

  CaptureObject object() const {
    const std::string shapes = "{\"type\": \"sphere\", \"center\": [x, y, z], \"radius\": r} or {\"gltf\": FILE}";
    const json& object = member(root_, "object", file_, "what was photographed: " + shapes);
    const std::string where = file_ + ": \"object\"";
    const bool gltf = object.is_object() && object.contains("gltf");
    const bool typed = object.is_object() && object.contains("type");
    if (gltf == typed || (typed && object["type"] != "sphere"))
      fail(where, "must be " + shapes + ", not " + json_excerpt(object));
    if (gltf) return CaptureGltf{existing_file(object["gltf"], where, "gltf")};
    const std::vector<float> center =
        numbers(member(object, "center", where, "the sphere's centre [x, y, z]"), 3, where, "center", kCoordinate);
    return CaptureSphere{Vec3(center[0], center[1], center[2]),
                         number(member(object, "radius", where, "the sphere's radius"), where, "radius", kPositive)};
  }

  std::optional<CaptureEnvironment> environment() const {
    if (!root_.contains("environment")) return std::nullopt;
    const json& entry = root_.at("environment");
    const std::string where = file_ + ": \"environment\"";
    if (!entry.is_object() || !(entry.contains("file") || entry.contains("procedural")))
      fail(where, "must be {\"file\": FILE, ...} or {\"procedural\": NAME, ...}, not " + json_excerpt(entry));
    CaptureEnvironment environment;
    if (entry.contains("file")) environment.file = existing_file(entry["file"], where, "file");
    if (entry.contains("procedural")) {
      if (!entry["procedural"].is_string())
        fail(where, "\"procedural\" must be the name of a procedural environment (a string), not " +
                        json_excerpt(entry["procedural"]));
      environment.procedural = entry["procedural"].get<std::string>();
      const auto& names = procedural_environment_names();
      if (std::find(names.begin(), names.end(), environment.procedural) == names.end()) {
        std::string known;
        for (const std::string& name : names) known += (known.empty() ? "" : ", ") + name;
        fail(where, "\"procedural\" is " + json_excerpt(entry["procedural"]) + ", not a procedural environment (" +
                        known + ")");
      }
    }
    if (entry.contains("scale")) environment.options.scale = number(entry["scale"], where, "scale", kNonNegative);
    if (entry.contains("rotation"))
      environment.options.rotation_degrees = number(entry["rotation"], where, "rotation", kFinite);
    if (entry.contains("to_world")) {
      const json& rows = entry["to_world"];
      if (!rows.is_array() || rows.size() != 3)
        fail(where, "\"to_world\" must be 3 rows of 3 numbers (a rotation, row-major), not " + json_excerpt(rows));
      for (int r = 0; r < 3; ++r) {
        const std::vector<float> row = numbers(rows[r], 3, where, "to_world[" + std::to_string(r) + "]", kFinite);
        for (int c = 0; c < 3; ++c) environment.options.to_world(r, c) = row[c];
      }
    }
    if (entry.contains("format")) {
      if (!entry["format"].is_string())
        fail(where,
             "\"format\" must be latlong, angular or mirror_ball (a string), not " + json_excerpt(entry["format"]));
      environment.options.format = parse_environment_format(entry["format"].get<std::string>(), where);
    }
    return environment;
  }

  std::optional<CaptureMaterial> material() const {
    if (!root_.contains("material")) return std::nullopt;
    const json& entry = root_.at("material");
    const std::string where = file_ + ": \"material\"";
    const std::string R0 = key(MaterialParameter::R0), Rd = key(MaterialParameter::Rd);
    if (!entry.is_object())
      fail(where, "must be {" + quoted(R0) + ": x, " + quoted(Rd) + ": [r, g, b]}, not " + json_excerpt(entry));
    const float specular = number(member(entry, R0, where, "the specular reflectance at normal incidence"), where, R0,
                                  parameter_range(MaterialParameter::R0));
    const std::vector<float> diffuse = numbers(member(entry, Rd, where, "the diffuse albedo [r, g, b]"), 3, where, Rd,
                                               parameter_range(MaterialParameter::Rd));
    CaptureMaterial material{PolishedMaterial(specular, RGB(diffuse[0], diffuse[1], diffuse[2])), {}};
    // The texture is for comparisons only: it need not exist (embedded in a .glb, say).
    if (entry.contains("texture")) material.texture = resolved_file(entry["texture"], where, "texture").string();
    return material;
  }

  std::optional<CaptureRenderer> renderer() const {
    if (!root_.contains("renderer")) return std::nullopt;
    const json& entry = root_.at("renderer");
    const std::string where = file_ + ": \"renderer\"";
    const std::string forms =
        "{\"integrator\": \"path\", \"spp\": N} or {\"integrator\": \"sh\", \"ss\": K, \"lmax\": L}";
    if (!entry.is_object()) fail(where, "must be " + forms + ", not " + json_excerpt(entry));
    const json& integrator = member(entry, "integrator", where, "\"path\" or \"sh\"");
    CaptureRenderer renderer;
    if (integrator == "path") {
      renderer.integrator = CaptureRenderer::Integrator::path;
      renderer.spp = int(number(member(entry, "spp", where, "the samples per pixel"), where, "spp", kCount));
    } else if (integrator == "sh") {
      renderer.integrator = CaptureRenderer::Integrator::sh;
      const json& supersampling = member(entry, "ss", where, "the K of its K x K rays per pixel");
      renderer.supersampling = int(number(supersampling, where, "ss", kCount));
      renderer.lmax = int(number(member(entry, "lmax", where, "the band of its diffuse term"), where, "lmax", kLmax));
    } else {
      fail(where, "\"integrator\" must be \"path\" or \"sh\", not " + json_excerpt(integrator));
    }
    return renderer;
  }

  std::string file_;
  fs::path directory_;
  const json& root_;
};

}  // namespace

// ---------------------------------------------------------------------------------------
// Whole sets only: a set that `glaze render --captures` did not finish, or whose images
// come from another run than its transforms.json, is refused (output_folder.h).
// ---------------------------------------------------------------------------------------

namespace {

void require_finished(const std::string& path) {
  std::error_code ec;
  const fs::path folder = fs::is_directory(path, ec) ? fs::path(path) : fs::path(path).parent_path();
  if (interrupted_run(folder.empty() ? "." : folder))
    throw Error(folder.string() + " is an incomplete capture set (a `glaze render --captures` run was interrupted, " +
                kIncompleteMarker + " is there); render it again");
}

// The set's "run", and every frame's image of the same run.
void require_one_run(CaptureSet& set, const fs::path& file, const json& root) {
  if (!root.contains("run")) return;
  if (!root.at("run").is_string()) fail(file.string(), "\"run\" must be a string (a glaze run's id)");
  set.run = root.at("run").get<std::string>();
  for (const CaptureFrame& frame : set.frames) {
    const std::string run = image_attribute(frame.file_path, "glaze:run");
    if (!run.empty() && run != set.run)
      throw Error(frame.file_path + " was written by another run than " + file.string() +
                  " (mixed set: a view was copied in from another set, or a run was interrupted); render the set "
                  "again");
  }
}

}  // namespace

CaptureSet read_transforms(const std::string& path) {
  require_finished(path);
  const fs::path file = transforms_file(path);
  const json root = read_json_file(file.string(), "capture set (transforms.json)");
  // Every key is type-checked above; a JSON exception here is a key that was missed.
  CaptureSet set;
  try {
    set = TransformsReader(file, root).read();
  } catch (const json::exception& e) {
    throw Error(file.string() + ": " + e.what() +
                " (a value of the wrong type that glaze did not check: please report it)");
  }
  require_one_run(set, file, root);
  return set;
}

}  // namespace glaze
