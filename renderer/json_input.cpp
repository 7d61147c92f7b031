#include "renderer/json_input.h"

#include "renderer/error.h"
#include "renderer/input_file.h"

namespace glaze {

nlohmann::json parse_json_limited(std::string_view text, const std::string& file, int max_depth) {
  using nlohmann::json;
  const json::parser_callback_t limit_depth = [&](int depth, json::parse_event_t event, json&) {
    if ((event == json::parse_event_t::object_start || event == json::parse_event_t::array_start) && depth >= max_depth)
      throw Error(file + ": JSON nested deeper than " + std::to_string(max_depth) +
                  " levels; no glaze input needs that, so the file is refused");
    return true;
  };
  try {
    return json::parse(text, limit_depth);
  } catch (const json::exception& error) {  // parse_error, or out_of_range for a number like 1e999
    throw Error(file + ": not valid JSON (" + error.what() + ")");
  }
}

nlohmann::json read_json_file(const std::string& path, const std::string& what) {
  return parse_json_limited(read_whole_file(path, what), path);
}

std::string json_excerpt(const nlohmann::json& value, size_t max_chars) {
  std::string text = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (text.size() > max_chars) text = text.substr(0, max_chars) + "...";
  return text;
}

}  // namespace glaze
