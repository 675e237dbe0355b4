#pragma once
/// @file
/// The finished cells of `ccdbench run` (one scene x strategy x δ each), kept in OUT/cells so that an interrupted
/// or repeated run reuses them, and the results log OUT/results.jsonl built from them.
///
/// A cell is reused only when its key covers everything that can change one of its numbers (docs/DESIGN.md §6): the
/// scene's content (topology, objects, collision filter and every frame the cell steps through), the step count,
/// δ, the resolved strategy, verification, repeats, the thread count (timings depend on it, verdicts do not) and a
/// digest of the executable that computed it (a git revision reads "-dirty" for every uncommitted build, so it
/// cannot tell two builds apart). Cell files carry a checksum; a corrupt one is an error, never a result.

#include "core/scene.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace ccd::harness {

struct CellKey {
  std::string scene;
  std::string scene_content;
  std::size_t steps = 0;
  double thickness = 0.0;
  /// "scene" or "command line": where δ came from (the gate matches on it).
  std::string thickness_from;
  std::string strategy;
  bool verify = true;
  bool toi = false;
  int repeats = 1;
  std::size_t threads = 1;
  std::string executable;

  nlohmann::json to_json() const;
};

/// Digest of everything in a scene that a step's answer depends on, and of frames[0..frames.size()).
std::string scene_content_digest(const Scene& scene, std::span<const std::vector<Vec3>> frames);

/// Digest of the running executable's bytes (computed once per process).
const std::string& executable_digest();

/// "SCENE__STRATEGY_KEYDIGEST.json", made of characters safe in a file name.
std::string cell_file_name(const CellKey& key);

/// A label or name made safe as one path component: [A-Za-z0-9._-] kept, the rest '_', never "." or "..".
std::string safe_path_component(const std::string& text);

/// The cell kept in `file` for `key`: nullopt when there is none or its stored key differs (then it is computed
/// again). @throws InputError (file, where, reason) when the file is corrupt: unreadable JSON, a checksum that does
/// not match, or missing parts.
std::optional<nlohmann::json> read_cell(const std::filesystem::path& file, const CellKey& key);

/// Writes a cell ({"key", "summary", "steps"}) with its checksum, atomically.
void write_cell(const std::filesystem::path& file, nlohmann::json cell);

/// Rewrites OUT/results.jsonl from every cell file in OUT/cells (each cell's step records, then its summary; cells
/// in the order they finished), under an exclusive lock of OUT/.results.lock: every finished cell of every run into
/// OUT is kept, and two runs writing into one OUT at once never drop each other's lines. Corrupt cell files are
/// skipped with a warning on `warnings`.
void rebuild_results_log(const std::filesystem::path& out, std::ostream& warnings);

}  // namespace ccd::harness
