// commands.h: the glaze subcommands that live outside main.cpp.
#pragma once

#include <string>
#include <vector>

namespace glaze {

int command_demo(const std::vector<std::string>& args);
int command_render(const std::vector<std::string>& args);
int command_convergence(const std::vector<std::string>& args);
int command_invert_fit(const std::vector<std::string>& args);

}  // namespace glaze
