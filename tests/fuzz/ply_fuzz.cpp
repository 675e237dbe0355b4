// Fuzz target: the PLY reader (ASCII, binary little and big endian).
#include "datasets/ply.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ccd::fuzz::refuse_or_accept(data, size, [](const std::filesystem::path& path) { ccd::datasets::read_ply(path); });
}
