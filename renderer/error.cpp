#include "renderer/error.h"

#include <iostream>
#include <mutex>
#include <set>
#include <utility>

namespace glaze {
namespace {

WarningSink& sink() {
  static WarningSink current = [](const std::string& message) { std::cerr << "glaze: warning: " << message << '\n'; };
  return current;
}

}  // namespace

void warn(const std::string& message) { sink()(message); }

void warn_once(const std::string& message) {
  static std::mutex mutex;
  static std::set<std::string> given;
  {
    std::lock_guard lock(mutex);
    if (!given.insert(message).second) return;
  }
  warn(message);
}

WarningSink set_warning_sink(WarningSink new_sink) { return std::exchange(sink(), std::move(new_sink)); }

}  // namespace glaze
