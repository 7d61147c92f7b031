#include "app/command_line.h"

#include "renderer/error.h"
#include "renderer/memory_budget.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>

namespace glaze {
namespace {

// Parses the whole of `token` as an integer, or returns false.
bool parse_integer(const std::string& token, long long* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  *value = std::strtoll(token.c_str(), &end, 10);
  return end == token.c_str() + token.size() && errno != ERANGE;
}

// Parses the whole of `token` as a finite number that fits a float, or returns false.
bool parse_real(const std::string& token, float* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double parsed = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size() || errno == ERANGE || !std::isfinite(parsed) || std::abs(parsed) > FLT_MAX)
    return false;
  *value = static_cast<float>(parsed);
  return true;
}

bool parse_resolution(const std::string& token, Resolution* resolution) {
  const size_t x = token.find('x');
  long long width = 0, height = 0;
  if (x == std::string::npos || !parse_integer(token.substr(0, x), &width) ||
      !parse_integer(token.substr(x + 1), &height) || width < 1 || height < 1 || width > 65536 || height > 65536)
    return false;
  *resolution = {int(width), int(height)};
  return true;
}

std::string number_text(float value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// The help's layout: the metavariable beside the option, and what bounds it (its range,
// its allowed values, its default, the options it needs or excludes) after its help.
class HelpFormatter : public CLI::Formatter {
 public:
  HelpFormatter() {
    column_width(24);
    label("SUBCOMMAND", "COMMAND");
  }

  std::string make_option_opts(const CLI::Option* option) const override {
    if (option->get_positional() || option->get_type_size() == 0) return "";
    const std::string metavar = type_parts(option).front();
    return metavar.empty() ? "" : " " + metavar;
  }

  std::string make_option_desc(const CLI::Option* option) const override {
    std::vector<std::string> notes;
    if (!option->get_positional() && option->get_type_size() != 0) {
      const std::vector<std::string> parts = type_parts(option);
      notes.assign(parts.begin() + 1, parts.end());
    }
    if (!option->get_default_str().empty()) notes.push_back("default " + option->get_default_str());
    if (option->get_required() && !option->get_positional()) notes.push_back("required");
    for (const CLI::Option* other : option->get_needs()) notes.push_back("needs " + other->get_name());
    for (const CLI::Option* other : option->get_excludes()) notes.push_back("not with " + other->get_name());
    std::string text = option->get_description();
    if (notes.empty()) return text;
    const std::string bracket = "[" + CLI::detail::join(notes, "; ") + "]";
    const size_t last_line = text.size() - (text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1);
    return text + (last_line + bracket.size() > 90 ? "\n" : " ") + bracket;
  }

  // A command in the overview: its name and positionals, and its description.
  std::string make_subcommand(const CLI::App* command) const override {
    std::string usage = command->get_name();
    for (const CLI::Option* positional : command->get_options([](const CLI::Option* o) { return o->get_positional(); }))
      usage += " " + positional->get_name();
    std::stringstream out;
    CLI::detail::format_help(out, usage, command->get_description(), column_width_);
    return out.str();
  }

 private:
  // The metavariable, then the validators' descriptions (CLI11 joins them with ':').
  static std::vector<std::string> type_parts(const CLI::Option* option) {
    std::stringstream stream(option->get_type_name());
    std::vector<std::string> parts(1);
    std::getline(stream, parts[0], ':');
    for (std::string part; std::getline(stream, part, ':');)
      if (!part.empty()) parts.push_back(part);
    return parts;
  }
};

// Levenshtein distance, for "did you mean".
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::vector<std::string> option_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options())
    for (const std::string& name : option->get_lnames()) names.push_back(name);
  return names;
}

// ", did you mean --X?" for the closest option within two edits (or one that the key
// begins with, or begins: --output for --out), else "".
std::string suggestion(const std::string& key, const CLI::App& app) {
  std::string best;
  size_t best_distance = 3;
  for (const std::string& name : option_names(app))
    if (const size_t d = key.starts_with(name) || name.starts_with(key) ? 1 : edit_distance(key, name);
        d < best_distance)
      best_distance = d, best = name;
  return best.empty() ? "" : ", did you mean --" + best + "?";
}

// What CLI11 left over: an unknown option, or an argument too many.
std::string unexpected(const CLI::App& app) {
  const std::vector<std::string> left = app.remaining();
  for (const std::string& arg : left) {
    const size_t start = arg.find_first_not_of('-');
    if (start == 0 || start == std::string::npos || std::isdigit(static_cast<unsigned char>(arg[start])) ||
        arg[start] == '.')
      continue;  // not an option: a value, or a negative number
    const std::string flag = arg.substr(0, arg.find('='));
    return "unknown option " + flag + suggestion(flag.substr(start), app);
  }
  return "unexpected argument '" + (left.empty() ? std::string() : left.front()) + "'";
}

// CLI11 would report an option given twice as a count of values; say it plainly.
void refuse_repeats(const CLI::App& app, const std::vector<std::string>& args, const std::string& see) {
  for (const std::string& name : option_names(app)) {
    const std::string flag = "--" + name;
    const auto given = std::count_if(
        args.begin(), args.end(), [&](const std::string& arg) { return arg == flag || arg.starts_with(flag + "="); });
    if (given > 1) throw Error("option " + flag + " is given twice" + see);
  }
}

}  // namespace

std::istream& operator>>(std::istream& in, Resolution& resolution) {
  std::string token;
  in >> token;
  if (!parse_resolution(token, &resolution)) in.setstate(std::ios::failbit);
  return in;
}

std::ostream& operator<<(std::ostream& out, const Resolution& resolution) { return out << to_string(resolution); }

std::string to_string(const Resolution& resolution) {
  return std::to_string(resolution.width) + "x" + std::to_string(resolution.height);
}

CLI::Validator integer_in(long long minimum, long long maximum) {
  const std::string range = "[" + std::to_string(minimum) + ", " + std::to_string(maximum) + "]";
  return CLI::Validator(
      [=](std::string& token) {
        long long value = 0;
        if (!parse_integer(token, &value) || value < minimum || value > maximum)
          return "'" + token + "' is not an integer in " + range;
        token = std::to_string(value);  // in base 10: CLI11 would read "010" as octal
        return std::string();
      },
      std::to_string(minimum) + " to " + std::to_string(maximum));
}

CLI::Validator real_in(float minimum, float maximum) {
  const std::string low = number_text(minimum), high = number_text(maximum);
  const std::string help = maximum == FLT_MAX    ? (minimum == -FLT_MAX ? "" : ">= " + low)
                           : minimum == -FLT_MAX ? "<= " + high
                                                 : low + " to " + high;
  const std::string range = minimum > -FLT_MAX && maximum < FLT_MAX ? "in [" + low + ", " + high + "]" : help;
  return CLI::Validator(
      [=](std::string& token) {
        float value = 0.0f;
        if (!parse_real(token, &value)) return "'" + token + "' is not a finite number";
        if (value < minimum || value > maximum) return "'" + token + "' is not a number " + range;
        // Written back exactly (9 digits round-trip a float): CLI11's own conversion, through
        // long double, can round the text to the float one above or below.
        char exact[32];
        std::snprintf(exact, sizeof exact, "%.9g", value);
        token = exact;
        return std::string();
      },
      help);
}

const CLI::Validator kResolution(
    [](std::string& token) {
      Resolution resolution;
      return parse_resolution(token, &resolution)
                 ? std::string()
                 : "'" + token + "' is not a resolution like 1024x512 (sides 1 to 65536)";
    },
    "");

CLI::Validator one_of(const std::vector<std::string>& names) {
  CLI::Validator member = CLI::IsMember(names);
  member.description("one of " + CLI::detail::join(names, ", "));
  return member;
}

namespace detail {

std::pair<std::string, std::string> split_metavar(const std::string& name) {
  const size_t space = name.find(' ');
  if (space == std::string::npos) return {name, ""};
  return {name.substr(0, space), name.substr(space + 1)};
}

}  // namespace detail

CLI::Option* add_reals(CLI::App& app, const std::string& name, std::vector<float>& target, size_t count,
                       const std::string& help) {
  const auto [flag, metavar] = detail::split_metavar(name);
  auto split = [count](const std::string& token, std::vector<float>* values) {
    std::stringstream stream(token);
    values->clear();
    for (std::string item; std::getline(stream, item, ',');) {
      float value = 0.0f;
      if (!parse_real(item, &value)) return false;
      values->push_back(value);
    }
    return values->size() == count && !token.ends_with(',');
  };
  return app
      .add_option_function<std::string>(
          flag, [&target, split](const std::string& token) { split(token, &target); }, help)
      ->type_name(metavar)
      ->check(CLI::Validator(
          [split, count](std::string& token) {
            std::vector<float> values;
            return split(token, &values)
                       ? std::string()
                       : "'" + token + "' is not " + std::to_string(count) + " comma-separated finite numbers";
          },
          ""));
}

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> names;
  std::stringstream stream(list);
  for (std::string name; std::getline(stream, name, ',');)
    if (!name.empty()) names.push_back(name);
  return names;
}

std::unique_ptr<CLI::App> make_command_app(const std::string& name) {
  auto app = std::make_unique<CLI::App>("", name == "glaze" ? name : "glaze " + name);
  app->formatter(std::make_shared<HelpFormatter>());
  app->set_help_flag("-h,--help", "print this help and exit");
  if (name != "glaze" && name != "help") {
    // Every command allocates according to its input; each allocation checks this limit.
    app->add_option_function<std::string>(
           "--memory-limit", [](const std::string& size) { set_memory_limit(parse_memory_size(size)); },
           "the most memory one allocation may take, like 512M, 16G or none (default: 80% of the machine's, "
           "or GLAZE_MEMORY_LIMIT)")
        ->type_name("SIZE")
        ->check(CLI::Validator(
            [](std::string& size) {
              return parse_memory_size(size) ? std::string() : "'" + size + "' is not a size like 512M, 16G or none";
            },
            ""));
  }
  return app;
}

std::string command_help(const std::string& name, CommandDeclaration declare) {
  const auto app = make_command_app(name);
  declare(*app);
  return app->help();
}

int run_command(const std::string& name, CommandDeclaration declare, const std::vector<std::string>& args) {
  const auto app = make_command_app(name);
  const CommandRun run = declare(*app);
  set_memory_limit(std::nullopt);  // the default, unless this command line sets one
  const std::string see = " (see `glaze " + name + " --help`)";
  refuse_repeats(*app, args, see);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // as CLI11 takes them
  try {
    app->parse(reversed);
  } catch (const CLI::CallForHelp&) {
    std::cout << app->help();
    return 0;
  } catch (const CLI::ExtrasError&) {
    throw Error(unexpected(*app) + see);
  } catch (const CLI::ParseError& error) {
    throw Error(error.what() + see);
  } catch (const Error& error) {  // a refusal of the command's callback
    throw Error(error.what() + see);
  }
  return run();
}

}  // namespace glaze
