#include "renderer/memory_budget.h"

#include "renderer/error.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>

namespace glaze {
namespace {

constexpr double kShareOfMachine = 0.8;

// The smallest of what the machine, the cgroup and the rlimits allow this process.
uint64_t available_memory() {
  uint64_t bytes = UINT64_MAX;
  const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page_size > 0) bytes = uint64_t(pages) * uint64_t(page_size);
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");  // "max" when unlimited
  uint64_t cgroup_bytes = 0;
  if (cgroup >> cgroup_bytes && cgroup_bytes > 0) bytes = std::min(bytes, cgroup_bytes);
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit limit{};
    if (getrlimit(resource, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
      bytes = std::min<uint64_t>(bytes, limit.rlim_cur);
  }
  return bytes;
}

uint64_t default_limit() {
  if (const char* text = std::getenv("GLAZE_MEMORY_LIMIT")) {
    if (const auto bytes = parse_memory_size(text)) return *bytes;
    throw Error(std::string("GLAZE_MEMORY_LIMIT=") + text + " is not a size like 512M, 16G or none");
  }
  const uint64_t available = available_memory();
  return available == UINT64_MAX ? available : uint64_t(double(available) * kShareOfMachine);
}

std::mutex limit_mutex;
std::optional<uint64_t> chosen_limit;

}  // namespace

uint64_t memory_limit() {
  std::lock_guard lock(limit_mutex);
  if (!chosen_limit) chosen_limit = default_limit();
  return *chosen_limit;
}

void set_memory_limit(std::optional<uint64_t> bytes) {
  std::lock_guard lock(limit_mutex);
  chosen_limit = bytes;
}

void require_memory(uint64_t bytes, const std::string& what) {
  const uint64_t limit = memory_limit();
  if (bytes <= limit) return;
  throw Error(what + " needs " + (bytes == UINT64_MAX ? "more than 16 EiB" : format_bytes(bytes)) +
              " of memory; the limit is " + format_bytes(limit) +
              ": make it smaller, or raise the limit with --memory-limit SIZE (or GLAZE_MEMORY_LIMIT)");
}

std::optional<uint64_t> parse_memory_size(const std::string& text) {
  if (text == "none") return UINT64_MAX;
  size_t used = 0;
  double number = 0.0;
  try {
    number = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  std::string unit = text.substr(used);
  if (unit.ends_with("iB")) unit.erase(unit.size() - 2);
  if (unit.size() == 2 && unit[1] == 'B') unit.pop_back();  // "GB" as "G"
  int shift = 0;
  if (unit.size() == 1) {
    const auto position = std::string("KMGT").find(char(std::toupper(unsigned(unit[0]))));
    if (position == std::string::npos) return std::nullopt;
    shift = 10 * int(position + 1);
  } else if (!unit.empty()) {
    return std::nullopt;
  }
  const double bytes = std::ldexp(number, shift);
  if (!std::isfinite(bytes) || bytes < 1.0 || bytes >= 1.8e19) return std::nullopt;
  return uint64_t(bytes);
}

std::string format_bytes(uint64_t bytes) {
  static const char* const kUnits[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double value = double(bytes);
  int unit = 0;
  while (value >= 1024.0 && unit < 6) value /= 1024.0, ++unit;
  char text[48];
  if (unit == 0)
    std::snprintf(text, sizeof text, "%llu bytes", static_cast<unsigned long long>(bytes));
  else
    std::snprintf(text, sizeof text, "%.1f %s", value, kUnits[unit]);
  return text;
}

}  // namespace glaze
