// memory_budget.h: how much memory glaze lets itself allocate, checked before it does.
//
// A film of 65536x65536 pixels, an environment declared huge or an accessor count of a
// billion would otherwise end in std::bad_alloc or the OOM killer after minutes of
// swapping. Each large allocation site estimates its bytes first and calls
// require_memory, which refuses with the number, the limit and what to do.
//
// The limit is 80% of the smallest of the machine's memory, the cgroup's `memory.max`
// and the process's RLIMIT_AS/RLIMIT_DATA; the GLAZE_MEMORY_LIMIT environment variable
// or the `--memory-limit SIZE` option every command takes replace it. Each site checks
// its own allocation, not a running total: the limit bounds the largest single block.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace glaze {

// The limit in bytes now in force.
uint64_t memory_limit();

// Replaces the limit; nothing restores the default (GLAZE_MEMORY_LIMIT, else 80% of
// the machine's).
void set_memory_limit(std::optional<uint64_t> bytes);

// Throws glaze::Error when `bytes` is above the limit: "WHAT needs 320.0 GiB of memory;
// the limit is ...: lower the size, or raise it with --memory-limit SIZE".
void require_memory(uint64_t bytes, const std::string& what);

// "512M", "16G", "1.5GiB", "2048" (bytes), "none" (no limit) -> bytes; nothing when the
// text is none of these.
std::optional<uint64_t> parse_memory_size(const std::string& text);

// 1536 -> "1.5 KiB", for messages.
std::string format_bytes(uint64_t bytes);

}  // namespace glaze
