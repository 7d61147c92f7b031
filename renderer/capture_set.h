// capture_set.h: capture sets (docs/design.md §4), nerfstudio-style: a directory with
// transforms.json and the HDR images it names. `glaze render --captures` writes them;
// the inverse module reads them. One format, one implementation, used both ways: the
// file's JSON stays in capture_set.cpp, and everyone else sees the C++ types below,
// checked once when the file is read.
//
//   { "w": 512, "h": 512, "fl_x": .., "fl_y": .., "cx": ..,  "cy": ..,   (or per frame)
//     "saturation": s,                          (optional: pixel values >= s are saturated)
//     "frames": [ {"file_path": "view_000.exr", "camera": "name" (optional),
//                  "transform_matrix": [[4x4 row-major camera-to-world, OpenGL axes]],
//                  "mask_path": "mask_000.png" (optional)} ],
//     "object": {"type": "sphere", "center": [x, y, z], "radius": r}  or  {"gltf": FILE},
//     "environment": {"file": FILE and/or "procedural": NAME, "scale": s, "rotation": degrees,
//                     "to_world": [[3x3 row-major rotation]]},                    (optional)
//     "material": {"R0": x, "Rd": [r, g, b], "texture": FILE (optional)},       (optional)
//     "renderer": {"integrator": "path", "spp": N} or {"integrator": "sh", "ss": K, "lmax": L},
//     "run": ID }                      (optional: the glaze run that wrote the set and its images)
//
// Relative paths are relative to the directory holding transforms.json. A per-frame
// intrinsic overrides the top-level one. "camera_model" is PINHOLE or SIMPLE_PINHOLE (no
// distortion), OPENCV (k1 k2 p1 p2, optional k3) or OPENCV_FISHEYE (k1..k4), the lens
// models of lens_distortion.h; without it, distortion coefficients mean OPENCV. Read as
// other tools write them too: Blender's "camera_angle_x"/"camera_angle_y" (w, h from the
// image when absent), a "file_path" without an extension (+ ".png"), nerfstudio's
// "applied_transform"/"applied_scale" (undone on the poses: "object" and "environment"
// are in the original frame).
#pragma once

#include "renderer/camera.h"
#include "renderer/environment.h"
#include "renderer/material.h"

#include <nlohmann/json_fwd.hpp>

#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace glaze {

struct CaptureFrame {
  std::string file_path;  // to write: relative to the capture directory; as read: resolved
  PinholeCamera camera;   // intrinsics and camera-to-world pose
  std::string mask_path;  // optional; as read: resolved
};

// What was photographed ("object"): an analytic sphere, or a glTF scene.
struct CaptureSphere {
  Vec3 center = Vec3::Zero();
  float radius = 1.0f;
};
struct CaptureGltf {
  std::string file;  // as read: resolved
};
using CaptureObject = std::variant<CaptureSphere, CaptureGltf>;

// The lighting the images were taken under ("environment"), as make_environment() builds
// it: a lat-long map file, else the procedural map of that name; a file rendered from a
// procedural map names both.
struct CaptureEnvironment {
  std::string file;            // empty: none; as read: resolved
  std::string procedural;      // empty: none
  EnvironmentOptions options;  // "scale", "rotation" (degrees), "to_world"
};

// The object's known material ("material"), its keys the names of the material's
// parameters (kMaterialParameters).
struct CaptureMaterial {
  PolishedMaterial material;
  std::string texture;  // optional: the diffuse texture's image (then Rd is its factor); as read: resolved
};

// How glaze rendered the images ("renderer"), so that invert-fit models the pixels to match.
struct CaptureRenderer {
  enum class Integrator { path, sh };
  Integrator integrator = Integrator::path;
  int spp = 1;            // path: samples per pixel ("spp")
  int supersampling = 1;  // sh: the K x K sub-pixel grid of each pixel ("ss")
  int lmax = 0;           // sh: the band its diffuse term was cut at
};

struct CaptureSet {
  std::vector<CaptureFrame> frames;
  CaptureObject object;
  std::optional<CaptureEnvironment> environment;
  std::optional<CaptureMaterial> material;
  std::optional<CaptureRenderer> renderer;
  std::string directory;            // holding the transforms.json read; empty if built in memory
  std::string file;                 // the transforms file read (any name); empty if built in memory
  std::optional<float> saturation;  // pixel values at or above it are saturated
  std::string run;                  // the glaze run that wrote the set ("run"; output_folder.h), or empty
};

// The "environment" entry of a transforms.json: "scale", "rotation", "to_world" and
// "file" or "procedural".
nlohmann::json environment_json(const CaptureEnvironment& environment);

// A camera's intrinsics as transforms.json holds them: w, h, fl_x, fl_y, cx, cy,
// camera_model and the coefficients its lens model uses (nerfstudio's names).
nlohmann::json intrinsics_json(const PinholeCamera& camera);

// Throws glaze::Error unless `camera` is one a capture set can hold (perspective, with a
// lens model that is one-to-one over its film).
void check_capture_camera(const PinholeCamera& camera);

// The text of the transforms.json of `captures`. Intrinsics shared by every frame are
// written once at the top, others per frame.
std::string transforms_json(const CaptureSet& captures);

// Writes DIRECTORY/transforms.json (atomically).
void write_transforms(const std::string& directory, const CaptureSet& captures);

// Reads PATH, a transforms.json or a directory holding one, checking everything above
// (files exist, poses are rigid, numbers are finite and in range, values have their
// types). File paths come back resolved against the file's directory, ready to open.
// Refuses a set that a glaze run did not finish (output_folder.h), and one whose images
// were written by another run than its transforms.json (images without "glaze:run",
// photographs, are not checked).
// Throws glaze::Error naming the file, the frame and the key at fault.
CaptureSet read_transforms(const std::string& path);

}  // namespace glaze
