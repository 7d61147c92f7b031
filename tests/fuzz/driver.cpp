// driver.cpp: a mutation driver for the LLVMFuzzerTestOneInput targets, for compilers
// without libFuzzer (GCC, in the sanitizer build). It takes libFuzzer's flags:
//
//   fuzz_X [-max_total_time=S] [-seed=N] [-runs=N] [-timeout=S] [-max_len=B]
//          [-artifact_prefix=DIR/] [-dict=FILE] CORPUS_DIR_OR_FILE...
//
// It runs every corpus entry once, then (unless -runs=0, or only files were named)
// mutated copies of them until -runs inputs or -max_total_time seconds. There is no coverage feedback: it is a bounded
// smoke run whose input sequence depends only on the seed and the corpus. Mutations:
// bit flips; bytes set to 0, 0x7f, 0x80 or 0xff; random bytes; chunks inserted, deleted or
// duplicated; two entries spliced; number tokens replaced by hostile values; runs of '['
// or '{' at nesting points; dictionary words inserted or put into strings; and, for JSON
// seeds, values replaced (hostile numbers, other types, words, nesting), members removed
// and elements duplicated in the parsed document.
//
// Findings are saved as ARTIFACT_PREFIX crash-<sha1> (a sanitizer report through its
// death callback, an exception other than the target's own refusal, abort()) or
// timeout-<sha1> (an input running past -timeout seconds, default 10; exit code 70).
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) __attribute__((weak));
extern "C" void __sanitizer_set_death_callback(void (*callback)()) __attribute__((weak));

namespace {

using Bytes = std::vector<uint8_t>;

// SHA-1 (FIPS 180-4) of the input, for artifact names as libFuzzer gives them. Allocation
// free, so that signal handlers can call it.
void sha1_hex(const uint8_t* data, size_t size, char out[41]) {
  uint32_t h[5] = {0x67452301, 0xEFCDAB89, 0x98BADCFE, 0x10325476, 0xC3D2E1F0};
  const auto rotl = [](uint32_t x, int n) { return (x << n) | (x >> (32 - n)); };
  const uint64_t bits = uint64_t(size) * 8;
  const size_t total = (size + 9 + 63) / 64 * 64;
  for (size_t block = 0; block < total; block += 64) {
    uint32_t w[80];
    for (int i = 0; i < 64; ++i) {
      const size_t at = block + size_t(i);
      uint8_t byte = at < size ? data[at] : at == size ? 0x80 : 0;
      if (at >= total - 8) byte = uint8_t(bits >> (8 * (total - 1 - at)));
      if (i % 4 == 0) w[i / 4] = 0;
      w[i / 4] |= uint32_t(byte) << (8 * (3 - i % 4));
    }
    for (int i = 16; i < 80; ++i) w[i] = rotl(w[i - 3] ^ w[i - 8] ^ w[i - 14] ^ w[i - 16], 1);
    uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4];
    for (int i = 0; i < 80; ++i) {
      const uint32_t f = i < 20   ? ((b & c) | (~b & d)) + 0x5A827999
                         : i < 40 ? (b ^ c ^ d) + 0x6ED9EBA1
                         : i < 60 ? ((b & c) | (b & d) | (c & d)) + 0x8F1BBCDC
                                  : (b ^ c ^ d) + 0xCA62C1D6;
      const uint32_t t = rotl(a, 5) + f + e + w[i];
      e = d, d = c, c = rotl(b, 30), b = a, a = t;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e;
  }
  for (int i = 0; i < 40; ++i) out[i] = "0123456789abcdef"[(h[i / 8] >> (28 - 4 * (i % 8))) & 15];
  out[40] = 0;
}

// The input being run, for the handlers that save it.
struct Current {
  const uint8_t* data = nullptr;
  size_t size = 0;
  char prefix[4096] = "./";
} current;

// Writes the current input as PREFIX KIND-<sha1> with system calls only (async-signal-safe).
void save_current(const char* kind) {
  if (!current.data) return;
  char name[4200], hash[41];
  sha1_hex(current.data, current.size, hash);
  const int length = std::snprintf(name, sizeof name, "%s%s-%s", current.prefix, kind, hash);
  if (length <= 0 || size_t(length) >= sizeof name) return;
  const int fd = ::open(name, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return;
  for (size_t done = 0; done < current.size;) {
    const ssize_t n = ::write(fd, current.data + done, current.size - done);
    if (n <= 0) break;
    done += size_t(n);
  }
  ::close(fd);
  const char note[] = "\n== fuzz driver: the input is saved as ";
  [[maybe_unused]] ssize_t ignored = ::write(2, note, sizeof note - 1);
  ignored = ::write(2, name, size_t(length));
  ignored = ::write(2, "\n", 1);
  current.data = nullptr;  // saved once, whichever handler comes first
}

void on_death() { save_current("crash"); }
void on_abort(int) {
  save_current("crash");
  ::signal(SIGABRT, SIG_DFL);
  ::raise(SIGABRT);
}
void on_timeout(int) {
  const char note[] = "\n== fuzz driver: an input ran past the timeout\n";
  [[maybe_unused]] ssize_t ignored = ::write(2, note, sizeof note - 1);
  save_current("timeout");
  ::_exit(70);
}

// splitmix64: the whole sequence follows from -seed.
struct Random {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  size_t below(size_t n) { return n ? size_t(next() % n) : 0; }
};

const char* const kHostileNumbers[] = {
    "-1",  "0",     "2147483648",  "4294967296", "18446744073709551615", "6148914691236517206", "1e300",
    "NaN", "1e-45", "-2147483649", "1e38"};
const uint8_t kSpecialBytes[] = {0x00, 0xff, 0x7f, 0x80};
const size_t kNestingRuns[] = {1, 2, 8, 101, 1000, 20000};

// Spans [begin, end) of number tokens (-?digits[.digits][e[+-]digits]) in `input`.
std::vector<std::pair<size_t, size_t>> number_tokens(const Bytes& input) {
  std::vector<std::pair<size_t, size_t>> spans;
  const auto digit = [&](size_t i) { return i < input.size() && input[i] >= '0' && input[i] <= '9'; };
  for (size_t i = 0; i < input.size();) {
    const size_t begin = i;
    if (input[i] == '-' && digit(i + 1)) ++i;
    if (!digit(i) || (begin > 0 && (std::isalnum(input[begin - 1]) || input[begin - 1] == '.'))) {
      i = begin + 1;
      continue;
    }
    while (digit(i) || (i < input.size() && std::strchr(".eE+-", input[i]) && digit(i + 1))) ++i;
    spans.push_back({begin, i});
  }
  return spans;
}

class Mutator {
 public:
  Mutator(uint64_t seed, const std::vector<Bytes>& corpus, std::vector<std::string> dictionary, size_t max_len)
      : random_{seed}, corpus_(corpus), dictionary_(std::move(dictionary)), max_len_(max_len) {}

  // A corpus entry with one to four stacked mutations.
  Bytes next() {
    Bytes input = corpus_[random_.below(corpus_.size())];
    const size_t count = 1 + random_.below(4);
    // Half the time a JSON seed gets only structural mutations: most byte mutations make
    // text that is not JSON, which the readers refuse before they look at any value.
    if (random_.below(2) && mutate_json(input, count)) return input;
    for (size_t k = 0; k < count; ++k) mutate(input);
    if (input.size() > max_len_) input.resize(max_len_);
    return input;
  }

 private:
  void insert(Bytes& input, size_t at, const std::string& text) {
    input.insert(input.begin() + at, text.begin(), text.end());
  }

  // `count` changes to values of `input` parsed as JSON, written back compactly; false
  // (input untouched) when it is not JSON. A value is replaced by a hostile number, by a
  // value of another type, by a dictionary word, or by itself nested; a member or an
  // element is removed or duplicated.
  bool mutate_json(Bytes& input, size_t count) {
    using nlohmann::json;
    json document = json::parse(input.begin(), input.end(), nullptr, false);
    if (document.is_discarded() || !document.is_structured()) return false;
    for (size_t k = 0; k < count; ++k) {
      std::vector<json*> values;  // every value, in document order
      std::vector<json*> stack = {&document};
      while (!stack.empty()) {
        json* value = stack.back();
        stack.pop_back();
        values.push_back(value);
        if (value->is_structured())
          for (json& child : *value) stack.push_back(&child);
      }
      json& target = *values[random_.below(values.size())];
      switch (random_.below(6)) {
        case 0:
          target = json::parse(kHostileNumbers[random_.below(std::size(kHostileNumbers))], nullptr, false);
          if (target.is_discarded()) target = nullptr;  // "NaN": not JSON (the byte mutations write it)
          break;
        case 1: {
          const json others[] = {nullptr, true, "", json::array(), json::object(), -0.0, 0.5};
          target = others[random_.below(std::size(others))];
          break;
        }
        case 2:
          if (!dictionary_.empty()) target = dictionary_[random_.below(dictionary_.size())];
          break;
        case 3:
          target = json::array({target});
          break;
        case 4:
          if (target.is_object() && !target.empty()) {
            auto member = target.begin();
            std::advance(member, random_.below(target.size()));
            target.erase(member);
          } else if (target.is_array() && !target.empty()) {
            target.erase(target.begin() + std::ptrdiff_t(random_.below(target.size())));
          }
          break;
        case 5:
          if (target.is_array() && !target.empty()) target.push_back(target[random_.below(target.size())]);
          break;
      }
    }
    const std::string text = document.dump(-1, ' ', false, json::error_handler_t::replace);
    input.assign(text.begin(), text.end());
    return true;
  }

  void mutate(Bytes& input) {
    const size_t n = input.size(), at = random_.below(n + 1), length = 1 + random_.below(std::min<size_t>(n + 1, 64));
    switch (random_.below(10)) {
      case 0:
        if (n) input[random_.below(n)] ^= uint8_t(1u << random_.below(8));
        break;
      case 1:
        if (n) input[random_.below(n)] = kSpecialBytes[random_.below(std::size(kSpecialBytes))];
        break;
      case 2:
        if (n) input[random_.below(n)] = uint8_t(random_.next());
        break;
      case 3: {  // insert random bytes
        Bytes chunk(length);
        for (uint8_t& b : chunk) b = uint8_t(random_.next());
        input.insert(input.begin() + at, chunk.begin(), chunk.end());
        break;
      }
      case 4:  // delete a chunk
        if (at < n) input.erase(input.begin() + at, input.begin() + std::min(n, at + length));
        break;
      case 5:  // duplicate a chunk in place
        if (at < n) {
          const Bytes chunk(input.begin() + at, input.begin() + std::min(n, at + length));
          input.insert(input.begin() + at, chunk.begin(), chunk.end());
        }
        break;
      case 6: {  // splice: a prefix of this entry, the suffix of another
        const Bytes& other = corpus_[random_.below(corpus_.size())];
        input.resize(at);
        input.insert(input.end(), other.begin() + random_.below(other.size() + 1), other.end());
        break;
      }
      case 7: {  // a number token replaced by a hostile value
        const auto spans = number_tokens(input);
        if (spans.empty()) break;
        const auto [begin, end] = spans[random_.below(spans.size())];
        input.erase(input.begin() + begin, input.begin() + end);
        insert(input, begin, kHostileNumbers[random_.below(std::size(kHostileNumbers))]);
        break;
      }
      case 8: {  // nesting: a number token wrapped in balanced arrays or objects, or a run of '[' or '{'
        const size_t depth = kNestingRuns[random_.below(std::size(kNestingRuns))];
        const auto spans = number_tokens(input);
        if (!spans.empty() && random_.below(2)) {
          const auto [begin, end] = spans[random_.below(spans.size())];
          const bool arrays = random_.below(2);
          std::string open, close;
          for (size_t d = 0; d < depth; ++d) open += arrays ? "[" : "{\"a\":", close += arrays ? ']' : '}';
          input.insert(input.begin() + end, close.begin(), close.end());
          insert(input, begin, open);
          break;
        }
        std::vector<size_t> points;
        for (size_t i = 0; i < n; ++i)
          if (std::strchr("[{:,", input[i])) points.push_back(i + 1);
        const size_t where = points.empty() ? at : points[random_.below(points.size())];
        insert(input, where, std::string(depth, random_.below(2) ? '[' : '{'));
        break;
      }
      case 9: {  // a dictionary word, into a string or as a new quoted one
        if (dictionary_.empty()) break;
        const std::string& word = dictionary_[random_.below(dictionary_.size())];
        std::vector<size_t> quotes;
        for (size_t i = 0; i < n; ++i)
          if (input[i] == '"') quotes.push_back(i);
        if (quotes.size() >= 2 && random_.below(2)) {
          const size_t q = random_.below(quotes.size() - 1), begin = quotes[q] + 1, end = quotes[q + 1];
          input.erase(input.begin() + begin, input.begin() + end);
          insert(input, begin, word);
        } else {
          insert(input, at, "\"" + word + "\"");
        }
        break;
      }
    }
  }

  Random random_;
  const std::vector<Bytes>& corpus_;
  std::vector<std::string> dictionary_;
  size_t max_len_;
};

Bytes read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// libFuzzer's dictionary format: one `"word"` or `name="word"` a line, \\ \" \xNN escapes, # comments.
std::vector<std::string> read_dictionary(const std::string& path) {
  std::vector<std::string> words;
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "fuzz driver: cannot read the dictionary %s\n", path.c_str());
    std::exit(1);
  }
  for (std::string line; std::getline(in, line);) {
    const size_t open = line.find('"'), close = line.rfind('"');
    if (line.empty() || line[0] == '#' || open == std::string::npos || close <= open) continue;
    std::string word;
    for (size_t i = open + 1; i < close; ++i) {
      if (line[i] == '\\' && i + 1 < close && line[i + 1] == 'x' && i + 3 < close) {
        word += char(std::stoi(line.substr(i + 2, 2), nullptr, 16));
        i += 3;
      } else if (line[i] == '\\' && i + 1 < close) {
        word += line[++i];
      } else {
        word += line[i];
      }
    }
    words.push_back(word);
  }
  return words;
}

// Runs one input under the timeout. Exceptions that escape the target are findings.
void run_one(const Bytes& input, unsigned timeout) {
  current.data = input.data();
  current.size = input.size();
  ::alarm(timeout);
  try {
    LLVMFuzzerTestOneInput(input.data(), input.size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "== fuzz driver: uncaught exception: %s\n", e.what());
    save_current("crash");
    std::_Exit(1);
  } catch (...) {
    std::fprintf(stderr, "== fuzz driver: uncaught exception of an unknown type\n");
    save_current("crash");
    std::_Exit(1);
  }
  ::alarm(0);
  current.data = nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  if (LLVMFuzzerInitialize) LLVMFuzzerInitialize(&argc, &argv);
  long long max_total_time = 0, runs = -1, seed = 1;
  unsigned timeout = 10;
  size_t max_len = 0;
  std::vector<std::string> dictionary;
  std::vector<std::filesystem::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&](const char* flag) -> const char* {
      const size_t length = std::strlen(flag);
      return arg.compare(0, length, flag) == 0 ? argv[i] + length : nullptr;
    };
    if (const char* v = value("-max_total_time="))
      max_total_time = std::atoll(v);
    else if (const char* v = value("-seed="))
      seed = std::atoll(v);
    else if (const char* v = value("-runs="))
      runs = std::atoll(v);
    else if (const char* v = value("-timeout="))
      timeout = unsigned(std::atoi(v));
    else if (const char* v = value("-max_len="))
      max_len = size_t(std::atoll(v));
    else if (const char* v = value("-dict="))
      dictionary = read_dictionary(v);
    else if (const char* v = value("-artifact_prefix="))
      std::snprintf(current.prefix, sizeof current.prefix, "%s", v);
    else if (arg.size() > 1 && arg[0] == '-')
      std::fprintf(stderr, "fuzz driver: ignoring the flag %s\n", argv[i]);
    else
      inputs.push_back(arg);
  }
  std::vector<std::filesystem::path> files;
  bool any_directory = false;
  for (const auto& input : inputs) {
    if (std::filesystem::is_directory(input)) {
      any_directory = true;
      for (const auto& entry : std::filesystem::directory_iterator(input))
        if (entry.is_regular_file()) files.push_back(entry.path());
    } else if (std::filesystem::exists(input)) {
      files.push_back(input);
    } else {
      std::fprintf(stderr, "fuzz driver: %s does not exist\n", input.c_str());
      return 1;
    }
  }
  // The sequence of inputs must not depend on the directories' order. Files alone are
  // only run (libFuzzer does the same).
  std::sort(files.begin(), files.end());
  if (!inputs.empty() && !any_directory && runs < 0) runs = 0;

  if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(on_death);
  ::signal(SIGABRT, on_abort);
  ::signal(SIGALRM, on_timeout);
  const auto start = std::chrono::steady_clock::now();
  const auto seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };

  std::vector<Bytes> corpus;
  for (const auto& file : files) {
    corpus.push_back(read_file(file));
    run_one(corpus.back(), timeout);
  }
  std::fprintf(stderr, "#%zu INITED: %zu corpus inputs replayed in %.1f s\n", corpus.size(), corpus.size(), seconds());
  if (corpus.empty()) corpus.push_back(Bytes{});
  if (max_len == 0)
    for (const Bytes& entry : corpus) max_len = std::max(max_len, std::max<size_t>(65536, 4 * entry.size()));

  std::fprintf(stderr, "fuzz driver: seed %lld\n", seed);
  Mutator mutator(uint64_t(seed), corpus, dictionary, max_len);
  long long executed = 0;
  while (runs != 0 && (runs < 0 || executed < runs) && (max_total_time <= 0 || seconds() < double(max_total_time))) {
    run_one(mutator.next(), timeout);
    if (++executed % 1000 == 0)
      std::fprintf(stderr, "#%lld execs, %.0f exec/s\n", executed, double(executed) / std::max(1e-9, seconds()));
  }
  std::fprintf(stderr, "Done %lld runs in %.0f second(s)\n", executed, seconds());
  return 0;
}
