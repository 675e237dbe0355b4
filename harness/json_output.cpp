#include "harness/json_output.hpp"

#include "datasets/atomic_file.hpp"

#include <nlohmann/json.hpp>

namespace ccd::harness {

void write_json_file(const std::filesystem::path& path, const nlohmann::json& document) {
  datasets::AtomicFile file(path, std::ios::out);
  file.stream() << document.dump(2) << '\n';
  file.commit();
}

}  // namespace ccd::harness
