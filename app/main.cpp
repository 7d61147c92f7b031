// main.cpp: the `glaze` command. Thin by design: it finds the command named first, which
// parses the rest of the command line (command_line.h) and calls the renderer and inverse
// libraries; it turns glaze::Error (and a file system error, with its path) into a clear
// message and exit status 1. `glaze help` is made from the commands' own declarations.
#include "app/commands.h"
#include "renderer/error.h"

#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>
#include <string>
#include <vector>

namespace glaze {

#if !GLAZE_HAVE_PREVIEW
CommandRun declare_preview(CLI::App& app) {
  app.description("a window that shows the render as it refines: not in this glaze (GLAZE_PREVIEW=OFF)");
  app.allow_extras();
  return []() -> int { throw Error(kNoPreview); };
}
#endif

namespace {

CommandRun declare_help(CLI::App& app);

struct Command {
  const char* name;
  CommandDeclaration declare;
};

// Every command, in the order `glaze help` lists them.
constexpr Command kCommands[] = {{"demo", declare_demo},
                                 {"sh", declare_sh},
                                 {"env", declare_env},
                                 {"env-convert", declare_env_convert},
                                 {"render", declare_render},
                                 {"convergence", declare_convergence},
                                 {"invert-fit", declare_invert_fit},
                                 {"hdr-merge", declare_hdr_merge},
                                 {"register", declare_register},
                                 {"captures", declare_captures},
                                 {"simulate-shoot", declare_simulate_shoot},
                                 {"preview", declare_preview},
                                 {"reproduce", declare_reproduce},
                                 {"help", declare_help}};

const Command& find_command(const std::string& name) {
  for (const Command& command : kCommands)
    if (name == command.name) return command;
  throw Error("unknown command '" + name + "' (see `glaze help`)");
}

std::string overview() {
  const auto app = make_command_app("glaze");
  app->description("glaze: render polished materials under environment lighting, and invert.");
  std::vector<CommandRun> runs;  // they own the options the declarations bind
  for (const Command& command : kCommands) {
    CLI::App* sub = app->add_subcommand(command.name);
    sub->group("Commands");
    runs.push_back(command.declare(*sub));
  }
  app->footer("`glaze COMMAND --help` (or `glaze help COMMAND`) lists the command's options.");
  return app->help();
}

CommandRun declare_help(CLI::App& app) {
  auto command = std::make_shared<std::string>();
  app.description("this overview, or the options of COMMAND");
  add_text(app, "COMMAND", *command, "a command");
  return [command] {
    std::cout << (command->empty() ? overview() : command_help(*command, find_command(*command).declare));
    return 0;
  };
}

int run(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << overview();
    return args.empty() ? 2 : 0;
  }
  const Command& command = find_command(args[0]);
  return run_command(command.name, command.declare, std::vector<std::string>(args.begin() + 1, args.end()));
}

}  // namespace
}  // namespace glaze

int main(int argc, char** argv) {
  // A file over `ulimit -f` fails its write (EFBIG), which glaze reports, instead of
  // killing the process midway.
  std::signal(SIGXFSZ, SIG_IGN);
  try {
    return glaze::run(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const glaze::Error& error) {
    std::cerr << "glaze: error: " << error.what() << '\n';
    return 1;
  } catch (const std::filesystem::filesystem_error& error) {
    // A file system call that glaze does not check itself: the system's word, with the path.
    const std::string path = error.path1().string();
    std::cerr << "glaze: error: " << (path.empty() ? error.what() : path + ": " + error.code().message()) << '\n';
    return 1;
  } catch (const std::bad_alloc&) {  // every large allocation is checked first (memory_budget.h)
    std::cerr << "glaze: error: out of memory (glaze's estimate missed this: please report it)\n";
    return 1;
  } catch (const std::exception& error) {
    std::cerr << "glaze: internal error: " << error.what() << '\n';
    return 3;
  }
}
