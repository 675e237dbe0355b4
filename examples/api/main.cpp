// ccdbench as a library: the exact oracle over query files (each query's answer against its label), then a run of
// `full` and `apccd` on a built-in scene, every step verified against the exact truth, printed from the typed
// results. Exit 0 when the oracle agrees with every label and neither strategy misses a pair.
#include <ccdbench/ccdbench.hpp>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const ccdbench::Version v = ccdbench::version();
  std::printf("ccdbench library %d.%d.%d (header %d.%d.%d)\n", v.major, v.minor, v.patch, CCDBENCH_API_VERSION_MAJOR, CCDBENCH_API_VERSION_MINOR,
              CCDBENCH_API_VERSION_PATCH);
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s QUERY_FILE_OR_FOLDER...\n", argv[0]);
    return 2;
  }
  try {
    // 1. The oracle on each query's own rationals, at δ = 0 (the labels' thickness).
    std::size_t queries = 0, disagreements = 0;
    for (int a = 1; a < argc; ++a) {
      std::vector<std::filesystem::path> files;
      if (std::filesystem::is_directory(argv[a])) {
        for (const auto& entry : std::filesystem::recursive_directory_iterator(argv[a])) {
          if (entry.path().extension() == ".csv") files.push_back(entry.path());
        }
      } else {
        files.emplace_back(argv[a]);
      }
      for (const std::filesystem::path& path : files) {
        const ccdbench::QueryFile file = ccdbench::read_query_file(path.string());
        std::size_t collide = 0, wrong = 0;
        for (std::size_t q = 0; q < file.exact.size(); ++q) {
          const ccdbench::ExactAnswer answer = ccdbench::exact_oracle(file.kind, file.exact[q], "0");
          collide += answer.collides ? 1 : 0;
          if (file.truth[q] >= 0 && answer.collides != (file.truth[q] == 1)) ++wrong;
        }
        std::printf("oracle %s: %zu queries, %zu collide, %zu against their label\n",
                    (path.parent_path().filename() / path.filename()).string().c_str(), file.exact.size(), collide, wrong);
        queries += file.exact.size();
        disagreements += wrong;
      }
    }
    // 2. full and apccd on the kinematic fold (8 x 8 cloth, 8 frames), verified, TOIs checked.
    ccdbench::RunRequest request;
    request.scenes = {ccdbench::generate_scene("fold", {{"resolution", 8}, {"frames", 8}})};
    request.strategies = {"full", "apccd"};
    request.toi = true;
    request.out = (std::filesystem::temp_directory_path() / "ccdbench-api-example").string();
    std::size_t missed = 0;
    std::printf("%-8s %-8s %6s %10s %7s %9s %9s\n", "scene", "strategy", "steps", "colliding", "missed", "TOI late", "ms/step");
    for (const ccdbench::CellSummary& cell : ccdbench::run(request)) {
      std::printf("%-8s %-8s %6zu %10zu %7zu %9zu %9.3f\n", cell.scene.c_str(), cell.spec.c_str(), cell.steps, cell.colliding.value_or(0),
                  cell.missed.value_or(0), cell.toi_late.value_or(0), cell.ms_per_step);
      missed += cell.missed.value_or(0);
    }
    std::printf("%zu queries, %zu against their label; %zu pairs missed\n", queries, disagreements, missed);
    return disagreements == 0 && missed == 0 ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "api_example: %s\n", error.what());
    return 2;
  }
}
