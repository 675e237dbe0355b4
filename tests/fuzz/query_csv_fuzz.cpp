// Fuzz target: the rational CSV query reader (both kinds), and the mma_bool truth-file reader on the same bytes.
#include "datasets/query_file.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using ccd::datasets::QueryKind;
  return ccd::fuzz::refuse_or_accept(data, size, [](const std::filesystem::path& path) {
    try {
      ccd::datasets::read_query_file(path, QueryKind::vertex_face);
    } catch (const ccd::InputError&) {
    }
    try {
      ccd::datasets::read_truth_file(path);
    } catch (const ccd::InputError&) {
    }
    ccd::datasets::read_query_file(path, QueryKind::edge_edge);
  });
}
