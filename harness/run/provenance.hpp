#pragma once
/// @file
/// What every run record carries about where and how it was made (docs/DESIGN.md §5): the machine, the build, the thread
/// count, the git revision and the executable's digest, and its provenance (the versions of ccdbench, the compiler
/// and every library); and the clock that orders finished cells.

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>

namespace ccd::harness {

/// The worker threads this process may use (--threads, or every core).
std::size_t worker_threads();

/// ccdbench's version and revision, the build type and flags, the compiler, and the version of every library it
/// was built with (header-only ones as configured; shared ones as loaded, where they can say so): what a result
/// from another machine needs to be reproduced. `ccdbench --version --verbose` prints the same.
nlohmann::json build_provenance();

/// machine, build_type, git_revision, executable, threads, rank, and `provenance` (build_provenance).
nlohmann::json environment();

/// "2026-11-22T21:30:00.123456Z": orders the cells of results.jsonl by when they finished.
std::string utc_now();

}  // namespace ccd::harness
