// json_input.h: JSON read from files, with the nesting bounded.
//
// nlohmann's parser and destructor are iterative, but dump() and tinygltf's own JSON
// walk recurse once per level, so a file of 20,000 nested brackets overflows the stack
// wherever such a value is printed or handed on. Every JSON input is parsed here, with
// a depth limit far above what any real glTF, capture set or fit needs.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>

namespace glaze {

inline constexpr int kMaxJsonDepth = 100;

// Parses `text`; throws glaze::Error naming `file` for invalid JSON (with the byte) and
// for values nested deeper than `max_depth` levels.
nlohmann::json parse_json_limited(std::string_view text, const std::string& file, int max_depth = kMaxJsonDepth);

// read_whole_file (input_file.h) then parse_json_limited.
nlohmann::json read_json_file(const std::string& path, const std::string& what);

// `value` printed for a message, cut to `max_chars` characters (with "...") and with
// invalid UTF-8 replaced, so that a 10 MB array makes a short message.
std::string json_excerpt(const nlohmann::json& value, size_t max_chars = 200);

}  // namespace glaze
