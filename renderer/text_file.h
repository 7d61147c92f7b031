// text_file.h: text files (JSON, Markdown) written so that a good file is never
// replaced by a half-written one: the text goes to a hidden temporary file beside the
// target, renamed over it only when complete (image.h does the same for images).
#pragma once

#include <string>

namespace glaze {

// Writes `text` to `path` atomically. Throws glaze::Error naming the file on failure.
void write_text_atomically(const std::string& path, const std::string& text);

}  // namespace glaze
