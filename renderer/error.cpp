#include "renderer/error.h"

#include <iostream>
#include <utility>

namespace glaze {
namespace {

WarningSink& sink() {
  static WarningSink current = [](const std::string& message) {
    std::cerr << "glaze: warning: " << message << '\n';
  };
  return current;
}

}  // namespace

void warn(const std::string& message) { sink()(message); }

WarningSink set_warning_sink(WarningSink new_sink) { return std::exchange(sink(), std::move(new_sink)); }

}  // namespace glaze
