// Tests of the integrator interface (integrator.h) and its registry: every registered
// integrator is found by its name and renders through the interface exactly what calling
// it directly renders, with its parameters recorded; an unknown name is an error that
// lists the known ones. Also the sub-pixel grid (pixel_grid.h) that the sh integrator and
// the fits' footprints share.
#include "renderer/error.h"
#include "renderer/integrator_registry.h"
#include "renderer/pixel_grid.h"
#include "renderer/procedural_environment.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <string>

namespace glaze {
namespace {

using testing::front_camera;
using testing::sphere_scene;

TEST(IntegratorRegistry, EachIntegratorRendersThroughTheInterfaceWhatItRendersDirectly) {
  const Scene scene = sphere_scene(0.04f, RGB(0.8f, 0.1f, 0.1f));
  const Environment environment(make_procedural_environment("office", 128, 64), {});
  const RayTracer tracer(scene);
  const PinholeCamera camera = front_camera(24);
  IntegratorOptions options;
  options.path_render.spp = 4;
  options.path_render.seed = 9;
  options.sh.lmax = 6;
  options.sh.supersampling = 3;
  options.sh.refined_supersampling = 6;
  const uint64_t camera_index = 2;  // keys the path tracer's streams: passed on, not dropped
  const PathTracer path_tracer(scene, tracer, environment, options.path);
  const std::map<std::string, Image> direct = {
      {"path", render(path_tracer, camera, options.path_render, camera_index).image},
      {"sh", render_sh(scene, tracer, environment, camera, options.sh)}};
  const std::map<std::string, std::map<std::string, std::string>> parameters = {
      {"path", {{"glaze:integrator", "path"}, {"glaze:spp", "4"}, {"glaze:seed", "9"}, {"glaze:max_depth", "1"}}},
      {"sh", {{"glaze:integrator", "sh"}, {"glaze:lmax", "6"}, {"glaze:ss", "3"}, {"glaze:ss_refined", "6"}}}};
  const std::map<std::string, std::string> summaries = {{"path", "4 spp"}, {"sh", "sh, lmax 6, ss 3 refined 6"}};

  ASSERT_EQ(integrator_names().size(), direct.size());
  for (const std::string& name : integrator_names()) {
    ASSERT_TRUE(direct.count(name)) << name << ": registered but not rendered directly in this test";
    const std::unique_ptr<Integrator> integrator = make_integrator(name, scene, tracer, environment, options);
    EXPECT_EQ(integrator->name(), name);
    const IntegratorResult result = integrator->render(camera, camera_index);
    EXPECT_EQ(result.image.pixels, direct.at(name).pixels) << name;
    EXPECT_EQ(result.metadata, parameters.at(name));
    EXPECT_EQ(result.summary, summaries.at(name));
    EXPECT_GE(result.seconds, 0.0);
  }
  // A different camera index is a different image for the path tracer (its own streams).
  const Image other = make_integrator("path", scene, tracer, environment, options)->render(camera, 3).image;
  EXPECT_NE(other.pixels, direct.at("path").pixels);
}

TEST(IntegratorRegistry, AnUnknownNameIsAnErrorListingTheKnownOnes) {
  const Scene scene = sphere_scene(0.04f, RGB(0.5f, 0.5f, 0.5f));
  const Environment environment(make_procedural_environment("office", 32, 16), {});
  const RayTracer tracer(scene);
  EXPECT_EQ(integrator_names(), (std::vector<std::string>{"path", "sh"}));
  for (const std::string& name : integrator_names()) EXPECT_NO_THROW(require_integrator(name));
  try {
    make_integrator("photon", scene, tracer, environment, {});
    ADD_FAILURE() << "an unknown integrator was made";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown integrator 'photon' (known: path, sh)");
  }
  EXPECT_THROW(require_integrator("Path"), Error);  // names are exact
}

// Cell centres: a pixel's k points along an axis are 1/k apart and centred on the pixel's
// centre; the grid's columns run along x and its rows along y.
TEST(PixelGrid, PointsAreTheCentresOfTheGridsCells) {
  EXPECT_EQ(pixel_grid_coordinate(3, 0, 1), 3.5f);
  for (int k : {2, 3, 4, 7}) {
    float sum = 0.0f;
    for (int cell = 0; cell < k; ++cell) {
      const float x = pixel_grid_coordinate(5, cell, k);
      EXPECT_NEAR(x, 5.0f + (cell + 0.5f) / k, 1e-6f);
      sum += x;
    }
    EXPECT_NEAR(sum / k, 5.5f, 1e-5f) << k;
  }
  EXPECT_EQ(pixel_grid_point(2, 7, 1, 3, 4), Vec2(2.375f, 7.875f));
}

}  // namespace
}  // namespace glaze
