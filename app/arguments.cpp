#include "app/arguments.h"

#include "renderer/error.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace glaze {
namespace {

// Parses the whole of `token` as a finite float, or returns false.
bool parse_real(const std::string& token, float* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double parsed = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size() || errno == ERANGE || !std::isfinite(parsed) ||
      std::abs(parsed) > std::numeric_limits<float>::max())
    return false;
  *value = static_cast<float>(parsed);
  return true;
}

bool parse_integer(const std::string& token, long* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const long parsed = std::strtol(token.c_str(), &end, 10);
  if (end != token.c_str() + token.size() || errno == ERANGE) return false;
  *value = parsed;
  return true;
}

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

// ", did you mean --X?" for the closest known option within two edits (or one that the
// key begins with, or begins: --output for --out), else "".
std::string suggestion(const std::string& key, const std::set<std::string>& allowed, const std::set<std::string>& flags) {
  std::string best;
  size_t best_distance = 3;
  for (const std::set<std::string>* names : {&allowed, &flags})
    for (const std::string& name : *names)
      if (const size_t d = key.starts_with(name) || name.starts_with(key) ? 1 : edit_distance(key, name); d < best_distance)
        best_distance = d, best = name;
  return best.empty() ? "" : ", did you mean --" + best + "?";
}

}  // namespace

Arguments::Arguments(const std::vector<std::string>& args, const std::set<std::string>& allowed,
                     const std::set<std::string>& flags) {
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg.starts_with("--")) {
      const std::string key = arg.substr(2);
      if (flags.count(key)) {
        if (options_.count(key)) throw Error("option --" + key + " is given twice");
        options_[key] = "";
        continue;
      }
      if (!allowed.count(key)) throw Error("unknown option --" + key + suggestion(key, allowed, flags) + " (see `glaze help`)");
      if (i + 1 >= args.size()) throw Error("option --" + key + " needs a value");
      if (options_.count(key)) throw Error("option --" + key + " is given twice");
      options_[key] = args[++i];
    } else {
      positionals_.push_back(arg);
    }
  }
}

std::string Arguments::text(const std::string& key, const std::string& fallback) const {
  const auto it = options_.find(key);
  return it == options_.end() ? fallback : it->second;
}

float Arguments::real(const std::string& key, float fallback) const {
  if (!has(key)) return fallback;
  float value = 0.0f;
  if (!parse_real(options_.at(key), &value))
    throw Error("option --" + key + ": '" + options_.at(key) + "' is not a finite number");
  return value;
}

long Arguments::integer(const std::string& key, long fallback, long minimum, long maximum) const {
  if (!has(key)) return fallback;
  long value = 0;
  if (!parse_integer(options_.at(key), &value) || value < minimum || value > maximum) {
    throw Error("option --" + key + ": '" + options_.at(key) + "' is not an integer in [" +
                std::to_string(minimum) + ", " + std::to_string(maximum) + "]");
  }
  return value;
}

std::pair<int, int> Arguments::resolution(const std::string& key, std::pair<int, int> fallback) const {
  if (!has(key)) return fallback;
  const std::string& token = options_.at(key);
  const size_t x = token.find('x');
  long width = 0, height = 0;
  if (x == std::string::npos || !parse_integer(token.substr(0, x), &width) ||
      !parse_integer(token.substr(x + 1), &height) || width < 1 || height < 1 || width > 65536 || height > 65536)
    throw Error("option --" + key + ": '" + token + "' is not a resolution like 1024x512 (sides 1 to 65536)");
  return {static_cast<int>(width), static_cast<int>(height)};
}

std::vector<float> Arguments::reals(const std::string& key) const {
  std::vector<float> values;
  const std::string token = text(key, "");
  size_t start = 0;
  while (true) {
    const size_t comma = token.find(',', start);
    const std::string item = token.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    float value = 0.0f;
    if (!parse_real(item, &value)) throw Error("option --" + key + ": '" + item + "' is not a finite number");
    values.push_back(value);
    if (comma == std::string::npos) return values;
    start = comma + 1;
  }
}

std::vector<std::string> Arguments::names(const std::string& key, const std::string& fallback) const {
  std::vector<std::string> names;
  std::stringstream stream(text(key, fallback));
  for (std::string name; std::getline(stream, name, ',');)
    if (!name.empty()) names.push_back(name);
  return names;
}

}  // namespace glaze
