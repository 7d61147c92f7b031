#include "renderer/json_input.h"

#include "renderer/error.h"
#include "renderer/input_file.h"

namespace glaze {

namespace {

// A first, SAX pass that only counts the depth. (nlohmann's callback parser would do it
// in one pass, but it scans the whole enclosing array each time an object ends, which
// makes an array of 100,000 objects take seconds: quadratic.)
class DepthCheck final : public nlohmann::json::json_sax_t {
 public:
  explicit DepthCheck(int max_depth) : max_depth_(max_depth) {}
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool key(string_t&) override { return true; }
  bool start_object(std::size_t) override { return enter(); }
  bool end_object() override { return --depth_, true; }
  bool start_array(std::size_t) override { return enter(); }
  bool end_array() override { return --depth_, true; }
  bool parse_error(std::size_t, const std::string&, const nlohmann::json::exception& error) override {
    error_ = error.what();
    return false;
  }
  bool too_deep() const { return too_deep_; }
  const std::string& error() const { return error_; }

 private:
  bool enter() {
    too_deep_ = ++depth_ > max_depth_;
    return !too_deep_;
  }
  int max_depth_, depth_ = 0;
  bool too_deep_ = false;
  std::string error_;
};

}  // namespace

nlohmann::json parse_json_limited(std::string_view text, const std::string& file, int max_depth) {
  DepthCheck check(max_depth);
  if (!nlohmann::json::sax_parse(text, &check)) {
    if (check.too_deep())
      throw Error(file + ": JSON nested deeper than " + std::to_string(max_depth) +
                  " levels; no glaze input needs that, so the file is refused");
    throw Error(file + ": not valid JSON (" + check.error() + ")");
  }
  try {
    return nlohmann::json::parse(text);               // valid and shallow: the check above has read it all
  } catch (const nlohmann::json::exception& error) {  // (the check reports these; kept as a boundary)
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
