// Cameras: the orthographic projection (rays, and the silhouette of a sphere against its
// closed form), a mirrored camera node, cameras named by node or glTF camera name, the
// default view of a file without a camera, and cameras placed with --look-from, --look-at
// and --fov. Every glTF is built in code (gltf_builder.h).
#include "app/orbit_camera.h"
#include "app/orbit_camera.h"
#include "app/shared_options.h"
#include "renderer/camera_placement.h"
#include "renderer/environment.h"
#include "renderer/image.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"
#include "gltf_builder.h"

#include <gtest/gtest.h>

#include <cmath>

namespace glaze {
namespace {

using namespace testing;

// The pose at `translation` turned 90 degrees about +Y: camera x -> world (0, 0, -1),
// y -> (0, 1, 0), z -> (1, 0, 0); the camera looks along world -X.
Eigen::Affine3f turned_pose(const Vec3& translation) {
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.translation() = translation;
  pose.linear() = Eigen::AngleAxisf(0.5f * kPi, Vec3::UnitY()).toRotationMatrix();
  return pose;
}

// ymag 2 on a 64 x 32 film: fl = 16 / 2 = 8 pixels per unit, centre (32, 16). Pixel
// (10, 5) has its centre at (10.5, 5.5): u = (10.5 - 32)/8 = -2.6875, v = -(5.5 - 16)/8 =
// 1.3125. The ray starts at (1, 2, 3) + u (0, 0, -1) + v (0, 1, 0) = (1, 3.3125, 5.6875)
// and runs along camera -Z = world (-1, 0, 0), whatever the pixel.
TEST(OrthographicCamera, RayStartsOnTheFilmPlaneAndRunsAlongMinusZ) {
  const PinholeCamera camera = PinholeCamera::orthographic("o", turned_pose(Vec3(1, 2, 3)), 2.0f, 64, 32);
  EXPECT_EQ(camera.fl_x, 8.0f);
  EXPECT_EQ(camera.fl_y, 8.0f);
  const Ray ray = camera.generate_ray(10.5f, 5.5f);
  expect_vec_near(ray.origin, Vec3(1, 3.3125f, 5.6875f), 1e-5f, "origin");
  expect_vec_near(ray.direction, Vec3(-1, 0, 0), 1e-6f, "direction");
  expect_vec_near(camera.generate_ray(60.0f, 30.0f).direction, Vec3(-1, 0, 0), 1e-6f, "another pixel's direction");
  // project() is generate_ray's inverse, at any depth along the ray.
  const Eigen::Affine3f world_to_camera = camera.camera_to_world.inverse();
  for (float depth : {0.5f, 7.0f}) {
    const std::optional<Vec2> film = camera.project(world_to_camera * (ray.origin + depth * ray.direction));
    ASSERT_TRUE(film.has_value());
    EXPECT_NEAR(film->x(), 10.5f, 1e-4f);
    EXPECT_NEAR(film->y(), 5.5f, 1e-4f);
  }
  EXPECT_FALSE(camera.project(world_to_camera * (ray.origin - ray.direction)).has_value()) << "behind the film";
}

// The perspective ray is the formula of docs/design.md §3 exactly (capture sets and the
// fits depend on it bit for bit).
TEST(PerspectiveCamera, RayIsTheDocumentedFormulaExactly) {
  const PinholeCamera camera = PinholeCamera::from_vertical_fov("p", turned_pose(Vec3(1, 2, 3)), 0.7f, 40, 30);
  const float x = 3.25f, y = 21.5f;
  const Vec3 local((x - camera.cx) / camera.fl_x, -(y - camera.cy) / camera.fl_y, -1.0f);
  const Ray ray = camera.generate_ray(x, y);
  EXPECT_EQ(ray.origin, camera.camera_to_world.translation());
  EXPECT_EQ(ray.direction, (camera.camera_to_world.linear() * local).normalized());
}

// A sphere of radius 0.9 at the origin, orthographic cameras "near" at z = 5 and "far" at
// z = 50 (ymag 2, xmag 2), and the constant environment.
json orthographic_scene() {
  json gltf = gltf_document({sphere_node(0.9, 0),
                             {{"name", "near"}, {"camera", 0}, {"translation", {0, 0, 5}}},
                             {{"name", "far"}, {"camera", 0}, {"translation", {0, 0, 50}}}},
                            {0, 1, 2});
  gltf["materials"] = {quiet_material({{"extras", {{"glaze", {{"R0", 0.04}, {"Rd", {0.5, 0.5, 0.5}}}}}}})};
  gltf["cameras"] = {{{"name", "ortho"},
                      {"type", "orthographic"},
                      {"orthographic", {{"xmag", 2.0}, {"ymag", 2.0}, {"znear", 0.1}, {"zfar", 100.0}}}}};
  return gltf;
}

// The orthographic silhouette of a sphere of radius r is a disc of radius r fl pixels,
// whatever the distance: on a 64 x 64 film with ymag 2 (fl = 16), pixel (i, j) is on the
// sphere when (i + 0.5 - 32)^2 + (j + 0.5 - 32)^2 < (0.9 * 16)^2 (no pixel centre lies
// within 0.14 square pixels of that circle). Rendered with the sh integrator at pixel
// centres on a black background, each row's lit pixels must be exactly that count, for
// the near and the far camera alike.
TEST(OrthographicCamera, SphereSilhouetteWidthIsTheClosedFormAtAnyDistance) {
  TemporaryDirectory dir;
  const Scene scene = load_scene(write_gltf(dir, "ortho.gltf", orthographic_scene()));
  ASSERT_EQ(scene.cameras.size(), 2u);
  const CameraSpec& spec = scene.camera("near");
  EXPECT_EQ(spec.projection, Projection::orthographic);
  EXPECT_EQ(spec.ymag, 2.0f);
  EXPECT_EQ(spec.aspect, 1.0f);
  const Environment environment = make_environment("procedural:constant", {}, 16, 8);
  const RayTracer tracer(scene);
  ShIntegratorOptions options;
  options.supersampling = 1;
  options.black_background = true;
  const float radius_pixels = 0.9f * 16.0f;
  for (const char* name : {"near", "far"}) {
    const PinholeCamera camera = scene.make_camera(scene.camera(name), std::pair(64, 64));
    EXPECT_EQ(camera.fl_y, 16.0f);
    const Image image = render_sh(scene, tracer, environment, camera, options);
    int widest = 0;
    for (int j = 0; j < 64; ++j) {
      int expected = 0, lit = 0;
      for (int i = 0; i < 64; ++i) {
        const float a = i + 0.5f - 32.0f, b = j + 0.5f - 32.0f;
        expected += a * a + b * b < radius_pixels * radius_pixels;
        lit += image.at(i, j)[0] > 0.0f;
      }
      EXPECT_EQ(lit, expected) << name << " row " << j;
      widest = std::max(widest, lit);
    }
    EXPECT_EQ(widest, 28) << name;  // 2 x 14.4 pixels, centres at half-integers: 28
  }
}

// Film from xmag / ymag: xmag 3, ymag 1.5 gives aspect 2, so 1024 x 512 and fl = 256/1.5.
// A zero magnification is refused, naming it.
TEST(OrthographicCamera, FilmAspectIsXmagOverYmagAndZeroIsRefused) {
  TemporaryDirectory dir;
  json gltf = orthographic_scene();
  gltf["cameras"][0]["orthographic"]["xmag"] = 3.0;
  gltf["cameras"][0]["orthographic"]["ymag"] = 1.5;
  const Scene scene = load_scene(write_gltf(dir, "wide.gltf", gltf));
  const PinholeCamera camera = scene.make_camera(scene.camera("near"), std::nullopt);
  EXPECT_EQ(camera.width, 1024);
  EXPECT_EQ(camera.height, 512);
  EXPECT_NEAR(camera.fl_y, 256.0f / 1.5f, 1e-3f);
  EXPECT_EQ(camera.fl_x, camera.fl_y);

  gltf["cameras"][0]["orthographic"]["xmag"] = 0.0;
  expect_load_error(dir, write_gltf(dir, "zero.gltf", gltf), {"xmag"});
}

// A capture set holds pinhole cameras only: `render --captures` refuses an orthographic
// one before rendering anything.
TEST(OrthographicCamera, CaptureSetRefusesIt) {
  TemporaryDirectory dir;
  const std::string path = write_gltf(dir, "ortho.gltf", orthographic_scene());
  const CommandResult run = run_glaze(
      "render " + quoted(path) + " --captures " + quoted(dir.file("caps")) + " --env procedural:constant --res 8x8",
      dir);
  expect_clear_failure(run, "orthographic");
  EXPECT_FALSE(std::filesystem::exists(dir.file("caps/view_000.exr")));
}

// The preview's orbit camera on an orthographic view (fl = 8 pixels per unit, at z = 5
// looking along -Z): moving it would change nothing seen, so zoom 0.5 doubles fl and
// leaves the camera where it was; a pan of 8 pixels to the right then moves the view
// 8 / fl = 0.5 units to the left (-X), at any depth.
TEST(OrthographicCamera, OrbitZoomMagnifiesAndPanMovesByPixelsOverFl) {
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.translation() = Vec3(0, 0, 5);
  OrbitCamera orbit(PinholeCamera::orthographic("o", pose, 2.0f, 32, 32), Vec3::Zero());
  orbit.zoom(0.5f);
  EXPECT_EQ(orbit.camera().fl_x, 16.0f);
  EXPECT_EQ(orbit.camera().fl_y, 16.0f);
  expect_vec_near(orbit.camera().position(), Vec3(0, 0, 5), 0.0f, "position after zoom");
  orbit.pan(8.0f, 0.0f);
  expect_vec_near(orbit.camera().position(), Vec3(-0.5f, 0, 5), 1e-6f, "position after pan");
}

// A camera node scaled by -1 along X (a mirror, determinant < 0) at (0, 0, 5): the
// camera looks along the node's -Z, at the sphere, (0, 0, -1) through the centre, with
// +Y up, and glaze warns.
TEST(MirroredCamera, LooksAlongTheNodesMinusZWithAWarning) {
  TemporaryDirectory dir;
  json gltf = orthographic_scene();
  gltf["nodes"][1]["scale"] = {-1, 1, 1};
  gltf["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}}}}};
  CapturedWarnings warnings;
  const Scene scene = load_scene(write_gltf(dir, "mirror.gltf", gltf));
  const PinholeCamera camera = scene.make_camera(scene.camera("near"), std::pair(9, 9));
  expect_vec_near(camera.generate_ray(4.5f, 4.5f).direction, Vec3(0, 0, -1), 1e-6f, "centre ray");
  // Not mirrored: the top row looks up (+Y), the right column right (+X).
  EXPECT_GT(camera.generate_ray(4.5f, 0.5f).direction.y(), 0.1f);
  EXPECT_GT(camera.generate_ray(8.5f, 4.5f).direction.x(), 0.1f);
  EXPECT_NEAR(camera.camera_to_world.linear().determinant(), 1.0f, 1e-5f);
  ASSERT_EQ(warnings.messages.size(), 1u);
  EXPECT_NE(warnings.messages[0].find("mirror"), std::string::npos) << warnings.messages[0];
}

// Cameras by name: glTF camera "lens" used by nodes "Left" and "Right", camera "solo_cam"
// by node "Solo", and an unnamed camera used by two unnamed nodes (camera_2, camera_2_4).
json named_cameras_scene() {
  json gltf = orthographic_scene();
  gltf["nodes"] = {sphere_node(0.9, 0),
                   {{"name", "Left"}, {"camera", 0}, {"translation", {-0.5, 0, 5}}},
                   {{"name", "Right"}, {"camera", 0}, {"translation", {0.5, 0, 5}}},
                   {{"name", "Solo"}, {"camera", 1}, {"translation", {0, 0.5, 5}}},
                   {{"camera", 2}, {"translation", {0, 0, 6}}},
                   {{"camera", 2}, {"translation", {0, 0, 7}}}};
  gltf["scenes"][0]["nodes"] = {0, 1, 2, 3, 4, 5};
  const json perspective = {{"yfov", 0.6}, {"znear", 0.1}};
  gltf["cameras"] = {{{"name", "lens"}, {"type", "perspective"}, {"perspective", perspective}},
                     {{"name", "solo_cam"}, {"type", "perspective"}, {"perspective", perspective}},
                     {{"type", "perspective"}, {"perspective", perspective}}};
  return gltf;
}

TEST(CameraNames, NodeNamesAndUnambiguousCameraNamesAreTaken) {
  TemporaryDirectory dir;
  const Scene scene = load_scene(write_gltf(dir, "named.gltf", named_cameras_scene()));
  ASSERT_EQ(scene.cameras.size(), 5u);
  EXPECT_EQ(scene.cameras[0].name, "Left");
  EXPECT_EQ(scene.cameras[1].name, "Right");
  EXPECT_EQ(scene.cameras[2].name, "Solo");
  EXPECT_EQ(scene.cameras[3].name, "camera_2");  // the automatic names of unnamed cameras
  EXPECT_EQ(scene.cameras[4].name, "camera_2_4");
  EXPECT_EQ(&scene.camera("solo_cam"), &scene.cameras[2]);
  expect_vec_near(scene.camera("Right").camera_to_world.translation(), Vec3(0.5f, 0, 5), 0.0f, "Right");
  try {
    scene.camera("lens");
    FAIL() << "an ambiguous glTF camera name was taken";
  } catch (const Error& e) {
    const std::string message = e.what();
    for (const char* word : {"lens", "2 nodes", "'Left'", "'Right'"})
      EXPECT_NE(message.find(word), std::string::npos) << word << " not in: " << message;
  }
}

// Through `glaze render`: --camera takes a node's name ("Right" renders what "Right" sees,
// not "Left") and a glTF camera's name used once ("solo_cam" is "Solo", bit for bit); an
// unknown name lists what can be given.
TEST(CameraNames, RenderTakesNodeNames) {
  TemporaryDirectory dir;
  const std::string path = write_gltf(dir, "named.gltf", named_cameras_scene());
  auto render = [&](const std::string& camera) {
    const std::string out = dir.file(camera + ".exr");
    const CommandResult run =
        run_glaze("render " + quoted(path) + " --camera " + camera +
                      " --integrator sh --ss 1 --res 24x24 --env procedural:constant --out " + quoted(out),
                  dir);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return read_image(out);
  };
  const Image left = render("Left"), right = render("Right"), solo = render("Solo"), solo_cam = render("solo_cam");
  EXPECT_NE(left.pixels, right.pixels);
  EXPECT_EQ(solo.pixels, solo_cam.pixels);
  // Right is at x = +0.5: the sphere (at the origin) is left of the image centre, so the
  // left half holds more of it (Rd 0.5 under radiance 1 is darker than the background).
  auto darker_half = [](const Image& image, bool left_half) {
    int count = 0;
    for (int j = 0; j < image.height; ++j)
      for (int i = left_half ? 0 : image.width / 2; i < (left_half ? image.width / 2 : image.width); ++i)
        count += image.at(i, j)[0] < 0.9f;
    return count;
  };
  EXPECT_GT(darker_half(right, true), darker_half(right, false));
  EXPECT_GT(darker_half(left, false), darker_half(left, true));

  const CommandResult unknown = run_glaze(
      "render " + quoted(path) + " --camera nope --env procedural:constant --out " + quoted(dir.file("x.exr")), dir);
  expect_clear_failure(unknown, "nope");
  for (const char* word : {"Left", "Right", "Solo (glTF camera 'solo_cam')", "camera_2_4", "node's name"})
    EXPECT_NE(unknown.err.find(word), std::string::npos) << word << " not in: " << unknown.err;
}

// Two analytic spheres of radius 1 at x = -2 and x = +2 and a triangle mesh between them
// (corners within the spheres' box), no camera: bounding box centre (0, 0, 0), bounding
// sphere radius 3.
json cameraless_scene() {
  GltfBuffer buffer;
  const int positions = buffer.floats({-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0, 0.5f, 0}, 3);
  json left = sphere_node(1.0, 0), right = sphere_node(1.0, 0);
  left["translation"] = {-2, 0, 0};
  right["translation"] = {2, 0, 0};
  json gltf = gltf_document({left, right, {{"mesh", 0}}}, {0, 1, 2});
  gltf["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", positions}}}, {"material", 0}}}}}};
  gltf["materials"] = {quiet_material({{"extras", {{"glaze", {{"R0", 0.04}, {"Rd", {0.0, 0.0, 0.0}}}}}}})};
  buffer.into(gltf);
  return gltf;
}

// The default view: from (0, sin 20, cos 20) 3 / sin 20 away (the bounding sphere just
// fits the 40-degree field of view of a square film), looking at the centre.
TEST(DefaultCamera, FramesTheBoundingSphereFromTheFrontAndAbove) {
  TemporaryDirectory dir;
  Scene scene = load_scene(write_gltf(dir, "cameraless.gltf", cameraless_scene()));
  ASSERT_TRUE(scene.cameras.empty());
  const BoundingSphere bounds = bounding_sphere(scene);
  expect_vec_near(bounds.centre, Vec3::Zero(), 1e-6f, "centre");
  EXPECT_NEAR(bounds.radius, 3.0f, 1e-6f);
  CapturedWarnings warnings;
  const std::string name = choose_camera(scene, {}, std::nullopt);
  EXPECT_EQ(name, "default");
  const float elevation = 20.0f * kPi / 180.0f, distance = 3.0f / std::sin(20.0f * kPi / 180.0f);
  const PinholeCamera camera = scene.make_camera(scene.camera(name), std::nullopt);
  EXPECT_EQ(camera.width, 512);
  EXPECT_EQ(camera.height, 512);
  expect_vec_near(camera.position(), distance * Vec3(0, std::sin(elevation), std::cos(elevation)), 1e-4f, "position");
  expect_vec_near(camera.generate_ray(256.0f, 256.0f).direction, -Vec3(0, std::sin(elevation), std::cos(elevation)),
                  1e-6f, "centre ray");
  ASSERT_EQ(warnings.messages.size(), 1u);
  for (const char* word : {"no camera", "--look-from", "--look-at", "--fov 40"})
    EXPECT_NE(warnings.messages[0].find(word), std::string::npos) << word << " not in: " << warnings.messages[0];
}

// Through `glaze render` with no --camera: it renders (exit 0, the note on stderr), and
// the two dark spheres lie inside the frame (no dark pixel on the border), centred
// (left and right margins within 2 pixels) and across most of its width (over half).
TEST(DefaultCamera, FileWithoutACameraRendersFramed) {
  TemporaryDirectory dir;
  const std::string path = write_gltf(dir, "cameraless.gltf", cameraless_scene());
  const std::string out = dir.file("framed.exr");
  const CommandResult run = run_glaze(
      "render " + quoted(path) + " --integrator sh --ss 1 --res 64x48 --env procedural:constant --out " + quoted(out),
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("the file has no camera"), std::string::npos) << run.err;
  const Image image = read_image(out);
  ASSERT_EQ(image.width, 64);
  ASSERT_EQ(image.height, 48);
  int left = image.width, right = -1, top = image.height, bottom = -1;
  for (int j = 0; j < image.height; ++j)
    for (int i = 0; i < image.width; ++i)
      if (image.at(i, j)[0] < 0.5f)  // Rd 0, R0 0.04: dark except at grazing angles; background 1
        left = std::min(left, i), right = std::max(right, i), top = std::min(top, j), bottom = std::max(bottom, j);
  ASSERT_GE(right, 0) << "nothing of the scene in view";
  EXPECT_GT(left, 0);
  EXPECT_LT(right, image.width - 1);
  EXPECT_GT(top, 0);
  EXPECT_LT(bottom, image.height - 1);
  EXPECT_LE(std::abs(left - (image.width - 1 - right)), 2) << left << " " << right;
  EXPECT_GT(right - left + 1, image.width / 2);

  // Without --env (the file has no environment either): an error that says to give one.
  expect_clear_failure(run_glaze("render " + quoted(path) + " --out " + quoted(dir.file("y.exr")), dir),
                       "--env FILE (a lat-long map");

  // --camera naming another camera: the error says there is none and what to do.
  const CommandResult named = run_glaze(
      "render " + quoted(path) + " --camera Camera --env procedural:constant --out " + quoted(dir.file("x.exr")), dir);
  expect_clear_failure(named, "without --camera, glaze renders a default view");
  EXPECT_EQ(named.err.find("warning"), std::string::npos) << named.err;
}

// --look-from 1,2,3 --look-at 4,2,3 --fov 90 on a 3 x 3 film: the centre pixel's ray runs
// from (1, 2, 3) along +X. fl = 1.5 / tan 45 = 1.5; the camera's right is up x back =
// (0, 1, 0) x (-1, 0, 0) = (0, 0, 1), so pixel (0, 1), u = (0.5 - 1.5)/1.5 = -2/3, looks
// along (1, 0, -2/3), normalised.
TEST(PlacedCamera, LookFromLookAtFovGiveTheHandComputedRays) {
  TemporaryDirectory dir;
  Scene scene = load_scene(write_gltf(dir, "named.gltf", named_cameras_scene()));
  CameraChoice choice;
  choice.look_from = {1, 2, 3};
  choice.look_at = {4, 2, 3};
  choice.fov_degrees = 90.0f;
  const Resolution film{3, 3};
  const std::string name = choose_camera(scene, choice, film);
  EXPECT_EQ(name, "placed");
  const PinholeCamera camera = scene.make_camera(scene.camera(name), film.pair());
  const Ray centre = camera.generate_ray(1.5f, 1.5f);
  expect_vec_near(centre.origin, Vec3(1, 2, 3), 0.0f, "origin");
  expect_vec_near(centre.direction, Vec3(1, 0, 0), 1e-6f, "centre direction");
  EXPECT_NEAR(camera.fl_y, 1.5f, 1e-5f);
  expect_vec_near(camera.generate_ray(0.5f, 1.5f).direction, Vec3(1, 0, -2.0f / 3.0f).normalized(), 1e-6f,
                  "left pixel");
}

// Only --look-at: the default view's direction from the target, moved back by the
// target's offset from the bounding sphere's centre: (r + |at - c|) / sin 20 = (3 + 1) /
// sin 20 from (1, 0, 0). Only --fov 30 (16:9 film): the default view at the distance
// where the sphere fits the vertical 30 degrees (narrower than the horizontal).
TEST(PlacedCamera, MissingValuesComeFromTheDefaultView) {
  TemporaryDirectory dir;
  const std::string path = write_gltf(dir, "cameraless.gltf", cameraless_scene());
  const Vec3 front_above(0, std::sin(20.0f * kPi / 180.0f), std::cos(20.0f * kPi / 180.0f));
  {
    Scene scene = load_scene(path);
    CameraChoice choice;
    choice.look_at = {1, 0, 0};
    const PinholeCamera camera = scene.make_camera(scene.camera(choose_camera(scene, choice, std::nullopt)), {});
    expect_vec_near(camera.position(), Vec3(1, 0, 0) + 4.0f / front_above.y() * front_above, 1e-4f, "position");
    EXPECT_NEAR(camera.fl_y, 256.0f / std::tan(20.0f * kPi / 180.0f), 1e-2f);
  }
  {
    Scene scene = load_scene(path);
    CameraChoice choice;
    choice.fov_degrees = 30.0f;
    const PinholeCamera camera =
        scene.make_camera(scene.camera(choose_camera(scene, choice, Resolution{160, 90})), std::pair(160, 90));
    expect_vec_near(camera.position(), 3.0f / std::sin(15.0f * kPi / 180.0f) * front_above, 1e-4f, "position");
  }
  // --camera and a placement exclude each other.
  const CommandResult both = run_glaze("render " + quoted(path) + " --camera default --fov 30 --out " +
                                           quoted(dir.file("x.exr")) + " --env procedural:constant",
                                       dir);
  expect_clear_failure(both, "--fov");
}

}  // namespace
}  // namespace glaze
