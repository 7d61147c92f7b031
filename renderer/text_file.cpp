#include "renderer/text_file.h"

#include "renderer/error.h"

#include <filesystem>
#include <fstream>

namespace glaze {

void write_text_atomically(const std::string& path, const std::string& text) {
  const std::filesystem::path target(path);
  const std::filesystem::path temporary = target.parent_path() / ("." + target.filename().string() + ".tmp");
  {
    std::ofstream file(temporary);
    file << text;
    if (!file) throw Error(path + ": could not be written");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, target, ec);
  if (ec) throw Error(path + ": could not be written (" + ec.message() + ")");
}

}  // namespace glaze
