// commands.h: the glaze subcommands that live outside main.cpp.
#pragma once

#include <string>
#include <vector>

namespace glaze {

int command_demo(const std::vector<std::string>& args);
int command_render(const std::vector<std::string>& args);
int command_convergence(const std::vector<std::string>& args);
int command_invert_fit(const std::vector<std::string>& args);
int command_preview(const std::vector<std::string>& args);
int command_reproduce(const std::vector<std::string>& args);

// What `glaze preview` and `invert-fit --preview` say in a build without the window.
inline constexpr const char* kNoPreview =
    "this glaze was built without the preview window (GLAZE_PREVIEW=OFF); rebuild with cmake -DGLAZE_PREVIEW=ON "
    "(needs libglfw3-dev and OpenGL), or render without a window: glaze render";

}  // namespace glaze
