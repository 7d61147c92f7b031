// register_command.cpp: `glaze register SHOOT`, the camera of a photo shoot registered on
// its chessboard (inverse/photos/registration.h): the intrinsics and each view's pose,
// as JSON in transforms.json's vocabulary, and a table on stdout.
#include "app/commands.h"
#include "inverse/photos/registration.h"
#include "renderer/text_file.h"

#include <filesystem>
#include <iostream>
#include <memory>

namespace glaze {

namespace {

struct RegisterOptions {
  std::string shoot;
  std::string out;  // default SHOOT/registration.json
};

int register_views(const RegisterOptions& options) {
  const Shoot shoot = read_shoot(options.shoot);
  const Registration registration = register_shoot(shoot);
  const std::filesystem::path out =
      options.out.empty() ? shoot.folder / "registration.json" : std::filesystem::path(options.out);
  write_text_atomically(out.string(), registration_json(registration, shoot.folder).dump(2) + "\n");
  std::cout << registration_table(registration, shoot.folder) << "wrote " << out.string() << '\n';
  return 0;
}

}  // namespace

CommandRun declare_register(CLI::App& app) {
  auto options = std::make_shared<RegisterOptions>();
  app.description(
      "register a photo shoot's camera on its chessboard: intrinsics, lens distortion and each view's "
      "pose in the board's frame");
  add_text(app, "SHOOT", options->shoot, "the photo shoot: a folder with shoot.json (or the file itself)")->required();
  add_text(app, "--out FILE", options->out, "the registration's JSON (default: SHOOT/registration.json)");
  return [options] { return register_views(*options); };
}

}  // namespace glaze
