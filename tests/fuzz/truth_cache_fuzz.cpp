// Fuzz target: the truth-cache reader against a fixed two-object scene. Mutated files almost never keep a valid
// checksum, so when the first byte is odd the target writes the rest with a correct checksum appended: the
// fuzzer then reaches the count, bounds and pair checks behind the checksum too.
#include "datasets/content_hash.hpp"
#include "harness/truth_cache.hpp"
#include "tests/fuzz/fuzz_input.hpp"

#include <vector>

namespace {

const ccd::Scene& scene() {
  static const ccd::Scene fixed = [] {
    std::vector<ccd::Face> faces;
    for (ccd::VertexId i = 0; i < 3; ++i) {
      for (ccd::VertexId j = 0; j < 3; ++j) {
        const ccd::VertexId a = i * 4 + j;
        faces.push_back({a, a + 1, a + 5});
        faces.push_back({a, a + 5, a + 4});
      }
    }
    return ccd::Scene({{"lower", ccd::ObjectKind::deformable, true, 16, faces}, {"upper", ccd::ObjectKind::deformable, false, 16, faces}}, {{0, 1}},
                      0.0);
  }();
  return fixed;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  if (size > 0 && (data[0] & 1)) {
    bytes.assign(data + 1, data + size);
    const std::uint64_t checksum = ccd::datasets::checksum64(bytes.data(), bytes.size());
    for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<std::uint8_t>(checksum >> (8 * i)));
  }
  return ccd::fuzz::refuse_or_accept(bytes.data(), bytes.size(),
                                     [](const std::filesystem::path& path) { ccd::harness::read_truth_file(path, scene()); });
}
