// arguments.h: the command line of one glaze command: positionals and `--key value`
// options, checked against the options the command accepts. Every accessor validates
// what it reads (whole token consumed, finite, in range) and throws glaze::Error naming
// the option otherwise.
#pragma once

#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace glaze {

class Arguments {
 public:
  // `allowed` options take a value; `flags` take none (has() tells whether one is given).
  Arguments(const std::vector<std::string>& args, const std::set<std::string>& allowed,
            const std::set<std::string>& flags = {});

  const std::vector<std::string>& positionals() const { return positionals_; }
  bool has(const std::string& key) const { return options_.count(key) > 0; }
  std::string text(const std::string& key, const std::string& fallback) const;
  // A finite number that also fits a float.
  float real(const std::string& key, float fallback) const;
  long integer(const std::string& key, long fallback, long minimum, long maximum) const;
  // "WxH", each side in [1, 65536].
  std::pair<int, int> resolution(const std::string& key, std::pair<int, int> fallback) const;
  // Comma-separated finite numbers.
  std::vector<float> reals(const std::string& key) const;
  // Comma-separated names (empty items skipped); `fallback` when the option is absent.
  std::vector<std::string> names(const std::string& key, const std::string& fallback = "") const;

 private:
  std::vector<std::string> positionals_;
  std::map<std::string, std::string> options_;
};

}  // namespace glaze
