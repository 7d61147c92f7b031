// input_file.h: opening what the user names as an input, without hanging or overreading.
//
// A FIFO as the environment blocks forever in open(); /dev/zero as a scene never ends.
// Every file glaze reads by path is checked here first: it must be a regular file,
// opened without blocking, and its size known before anything is allocated for it.
#pragma once

#include <cstdint>
#include <string>

namespace glaze {

// The size in bytes of `path` when it is a regular file that can be read. Otherwise
// throws glaze::Error "PATH: WHAT is a FIFO (named pipe), not a regular file" (or is
// missing, is a folder, cannot be read: with the system's reason).
uint64_t require_regular_file(const std::string& path, const std::string& what);

// The whole content of the regular file `path` (as require_regular_file checks it),
// its size checked against the memory limit (memory_budget.h) first.
std::string read_whole_file(const std::string& path, const std::string& what);

}  // namespace glaze
