// 8-bit captures (docs/guide.md, "8-bit captures"): the red sphere rendered as linear
// EXRs by glaze, then stored as a camera would at the lighting's exposure, 8-bit sRGB
// PNG and JPEG, whose highlights (the red channel over most of the sphere) clip at 255.
// The fit on them must match the fit on the EXRs or refuse, saying why; never return a
// wrong material quietly.
#include "renderer/image.h"
#include "test_support.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace glaze {
namespace {

using nlohmann::json;
using testing::TemporaryDirectory;
namespace fs = std::filesystem;

// Stores `image` as an 8-bit sRGB file (PNG or JPEG by the extension), clipping at 1.
void write_8bit(const std::string& path, const Image& image) {
  std::vector<unsigned char> codes;
  for (float value : image.pixels)
    codes.push_back((unsigned char)std::lround(255.0f * linear_to_srgb(std::clamp(value, 0.0f, 1.0f))));
  auto out = OIIO::ImageOutput::create(path);
  OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:90");  // a camera's usual quality; PNG ignores it
  ASSERT_TRUE(out && out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT8, codes.data()) && out->close());
}

// A copy of the capture set at `from` with its views stored as 8-bit `extension` files.
std::string eight_bit_copy(const std::string& from, const std::string& to, const std::string& extension) {
  fs::create_directories(to);
  json root = testing::read_json(from + "/transforms.json");
  root.erase("run");  // the images are no longer the run's
  fs::copy_file(from + "/" + root["environment"]["file"].get<std::string>(),
                to + "/" + root["environment"]["file"].get<std::string>());
  for (json& frame : root["frames"]) {
    const std::string name = fs::path(frame["file_path"].get<std::string>()).replace_extension(extension).string();
    write_8bit(to + "/" + name, read_image(from + "/" + frame["file_path"].get<std::string>()));
    frame["file_path"] = name;
  }
  std::ofstream(to + "/transforms.json") << root.dump(2);
  return to;
}

struct Fit {
  testing::CommandResult run;
  json result;
};

Fit fit(const std::string& folder, const TemporaryDirectory& dir) {
  Fit fit{testing::run_glaze("invert-fit " + folder + " --mode material --out " + folder + "_fit", dir), {}};
  if (fit.run.exit_code == 0) fit.result = testing::read_json(folder + "_fit/fit.json");
  return fit;
}

void expect_matches(const Fit& ldr, const Fit& hdr, const std::string& what) {
  EXPECT_NEAR(ldr.result["R0"].get<double>(), hdr.result["R0"].get<double>(), 0.003) << what;
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(ldr.result["Rd"][c].get<double>(), hdr.result["Rd"][c].get<double>(), 0.01) << what << " Rd " << c;
}

TEST(LdrCaptures, ClippedPngAndJpegMatchTheHdrFitOrRefuse) {
  TemporaryDirectory dir;
  const std::string hdr_folder = dir.file("hdr");
  const testing::CommandResult render =
      testing::run_glaze("render " + testing::scenes_dir() + "red_sphere_office.gltf --captures " + hdr_folder +
                             " --integrator sh --ss 1 --lmax 16 --res 96x96",
                         dir);
  ASSERT_EQ(render.exit_code, 0) << render.err;
  const Fit hdr = fit(hdr_folder, dir);
  ASSERT_EQ(hdr.run.exit_code, 0) << hdr.run.err;
  EXPECT_EQ(hdr.run.err.find("8-bit"), std::string::npos) << hdr.run.err;

  // PNG: the clipped codes are dropped as saturated, and the rest fits.
  const Fit png = fit(eight_bit_copy(hdr_folder, dir.file("png"), ".png"), dir);
  ASSERT_EQ(png.run.exit_code, 0) << png.run.err;
  EXPECT_NE(png.run.err.find("merge brackets into HDR (glaze hdr-merge)"), std::string::npos) << png.run.err;
  EXPECT_GT(png.result["dropped"]["saturated"].get<double>(), 0.5 * png.result["samples"].get<double>());
  expect_matches(png, hdr, "PNG");

  // JPEG: a match within the same bounds, with the warning, or a refusal saying why.
  const Fit jpeg = fit(eight_bit_copy(hdr_folder, dir.file("jpeg"), ".jpg"), dir);
  if (jpeg.run.exit_code == 0) {
    EXPECT_NE(jpeg.run.err.find("glaze hdr-merge"), std::string::npos) << jpeg.run.err;
    expect_matches(jpeg, hdr, "JPEG");
  } else {
    testing::expect_clear_failure(jpeg.run, "clipped");
  }
}

}  // namespace
}  // namespace glaze
