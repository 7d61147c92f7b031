// commands.h: the glaze commands. Each declares its command line on a CLI11 app
// (command_line.h) and returns how it runs with it; command_NAME runs one on an argument
// list, as `demo` and `reproduce` do for the steps they take.
#pragma once

#include "app/command_line.h"

#include <string>
#include <vector>

namespace glaze {

CommandRun declare_demo(CLI::App& app);            // demo_command.cpp
CommandRun declare_sh(CLI::App& app);              // environment_commands.cpp
CommandRun declare_env(CLI::App& app);             // environment_commands.cpp
CommandRun declare_env_convert(CLI::App& app);     // environment_commands.cpp
CommandRun declare_render(CLI::App& app);          // render_command.cpp
CommandRun declare_convergence(CLI::App& app);     // convergence_command.cpp
CommandRun declare_invert_fit(CLI::App& app);      // invert_command.cpp
CommandRun declare_preview(CLI::App& app);         // preview_command.cpp, built with GLAZE_PREVIEW
CommandRun declare_reproduce(CLI::App& app);       // reproduce_command.cpp
CommandRun declare_hdr_merge(CLI::App& app);       // hdr_merge_command.cpp
CommandRun declare_register(CLI::App& app);        // register_command.cpp
CommandRun declare_captures(CLI::App& app);        // captures_command.cpp
CommandRun declare_simulate_shoot(CLI::App& app);  // simulate_shoot_command.cpp

inline int command_render(const std::vector<std::string>& args) { return run_command("render", declare_render, args); }
inline int command_convergence(const std::vector<std::string>& args) {
  return run_command("convergence", declare_convergence, args);
}
inline int command_invert_fit(const std::vector<std::string>& args) {
  return run_command("invert-fit", declare_invert_fit, args);
}
inline int command_captures(const std::vector<std::string>& args) {
  return run_command("captures", declare_captures, args);
}
inline int command_simulate_shoot(const std::vector<std::string>& args) {
  return run_command("simulate-shoot", declare_simulate_shoot, args);
}

// What `glaze preview` and `invert-fit --preview` say in a build without the window.
inline constexpr const char* kNoPreview =
    "this glaze was built without the preview window (GLAZE_PREVIEW=OFF); rebuild with cmake -DGLAZE_PREVIEW=ON "
    "(needs libglfw3-dev and OpenGL), or render without a window: glaze render";

}  // namespace glaze
