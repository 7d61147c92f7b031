// command_line.h: how the glaze commands declare and parse their command lines (CLI11).
//
// Each command declares every option once, in its declare_* function (commands.h): bound
// straight into its options struct, with its bounds, allowed values, default and help,
// from which CLI11 makes the command's --help. The helpers below add one option of a kind
// with the check that kind needs (an integer in bounds, a finite number, WxH, ...), so
// that no option can miss it; shared_options.h declares the options that several
// commands take. run_command parses a command line and turns CLI11's errors into
// glaze::Error naming the option.
#pragma once

#include <CLI/CLI.hpp>

#include <cfloat>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace glaze {

// A command, declared: it has added its description, positionals and options to an app,
// bound into an options object that this function runs the command with.
using CommandRun = std::function<int()>;
using CommandDeclaration = CommandRun (*)(CLI::App& app);

// Parses `args` (what follows the command's name) with an app that `declare` fills, then
// runs the command. --help prints the command's help and returns 0; an unknown option, a
// bad value or a refused combination throws glaze::Error that names the option.
int run_command(const std::string& name, CommandDeclaration declare, const std::vector<std::string>& args);

// An app for command `name` (or the overview, "glaze"), with glaze's help layout.
std::unique_ptr<CLI::App> make_command_app(const std::string& name);

// The help of command `name`, as `glaze NAME --help` prints it.
std::string command_help(const std::string& name, CommandDeclaration declare);

// A resolution "WxH", each side in [1, 65536].
struct Resolution {
  int width = 0, height = 0;
  std::pair<int, int> pair() const { return {width, height}; }
};
std::istream& operator>>(std::istream& in, Resolution& resolution);
std::ostream& operator<<(std::ostream& out, const Resolution& resolution);
std::string to_string(const Resolution& resolution);  // "WxH"

// Checks of a value as typed; their messages name the value, CLI11 adds the option's name.
// A decimal integer in [minimum, maximum]: a transform (Option::transform), which rewrites
// the value in the form CLI11 then converts as meant.
CLI::Validator integer_in(long long minimum, long long maximum);
// A finite number that fits a float, in [minimum, maximum]; a transform too, so that a
// float gets float(strtod(text)), as glaze has always read numbers.
CLI::Validator real_in(float minimum = -FLT_MAX, float maximum = FLT_MAX);
extern const CLI::Validator kResolution;
CLI::Validator one_of(const std::vector<std::string>& names);

namespace detail {

template <typename T>
struct is_optional : std::false_type {};
template <typename T>
struct is_optional<std::optional<T>> : std::true_type {};

// `name` is "--name METAVAR" (the metavariable shown in the help, optional).
std::pair<std::string, std::string> split_metavar(const std::string& name);

// Adds the option; its default (the target's value now) is shown in the help unless the
// target is optional (an absent option then means what its help says).
template <typename T>
CLI::Option* add(CLI::App& app, const std::string& name, T& target, const std::string& help) {
  const auto [flag, metavar] = split_metavar(name);
  CLI::Option* option = app.add_option(flag, target, help);
  if (!metavar.empty()) option->type_name(metavar);
  if constexpr (!is_optional<T>::value) option->capture_default_str();
  return option;
}

}  // namespace detail

// Each adds one option "--name METAVAR" to `app`, bound to `target` (T or std::optional<T>),
// and returns it for more (needs, excludes, group).
template <typename T>
CLI::Option* add_integer(CLI::App& app, const std::string& name, T& target, long long minimum, long long maximum,
                         const std::string& help) {
  return detail::add(app, name, target, help)->transform(integer_in(minimum, maximum));
}

template <typename T>
CLI::Option* add_real(CLI::App& app, const std::string& name, T& target, const std::string& help,
                      float minimum = -FLT_MAX, float maximum = FLT_MAX) {
  return detail::add(app, name, target, help)->transform(real_in(minimum, maximum));
}

template <typename T>
CLI::Option* add_resolution(CLI::App& app, const std::string& name, T& target, const std::string& help) {
  return detail::add(app, name, target, help)->check(kResolution);
}

// Text: a file, a folder, a name.
template <typename T>
CLI::Option* add_text(CLI::App& app, const std::string& name, T& target, const std::string& help) {
  return detail::add(app, name, target, help);
}

// One of `choices`.
template <typename T>
CLI::Option* add_choice(CLI::App& app, const std::string& name, T& target, const std::vector<std::string>& choices,
                        const std::string& help) {
  return detail::add(app, name, target, help)->check(one_of(choices));
}

// `count` comma-separated finite numbers "a,b,...", in one argument.
CLI::Option* add_reals(CLI::App& app, const std::string& name, std::vector<float>& target, size_t count,
                       const std::string& help);

// Comma-separated names "a,b,..." in one argument (empty ones skipped) into a
// std::vector<std::string>, which holds the default, or an optional one.
std::vector<std::string> split_names(const std::string& list);
template <typename T>
CLI::Option* add_names(CLI::App& app, const std::string& name, T& target, const std::string& help) {
  const auto [flag, metavar] = detail::split_metavar(name);
  CLI::Option* option = app.add_option_function<std::string>(
      flag, [&target](const std::string& list) { target = split_names(list); }, help);
  option->type_name(metavar);
  if constexpr (!detail::is_optional<T>::value) option->default_str(CLI::detail::join(target, ","));
  return option;
}

}  // namespace glaze
