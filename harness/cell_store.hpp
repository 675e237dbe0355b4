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
#include <map>
#include <optional>
#include <set>
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

/// OUT/results.jsonl: each finished cell of every run into OUT (its step records, then its summary), as OUT/cells holds
/// them, under an exclusive lock of OUT/.results.lock, so that two runs writing into one OUT at once never drop each
/// other's lines. Corrupt cell files are left out with a warning.
///
/// A run adds each cell as it finishes. The cell is appended when the log is still as this run left it and the cell
/// finished after every cell of its scene, δ and strategy in it: a sweep of hundreds of cells must not parse every
/// cell file again after each one (that made a run quadratic in its cells, on rank 0's coordinating thread under
/// MPI). Otherwise (another run wrote the log, the first cell of a run, a cell older than one of its key) the log is
/// rebuilt from every cell file, cells in the order they finished. A cell computed again is appended too, its earlier
/// lines left until the run's end (every reader takes a cell's latest summary and steps), when the log is rebuilt
/// without them. Appended cells are in the order they reached the writer.
class ResultsLog {
 public:
  explicit ResultsLog(std::filesystem::path out) : out_(std::move(out)) {}

  /// The cell just written to `file` (in OUT/cells), as written: appended, or the whole log rebuilt.
  void add(const std::filesystem::path& file, const nlohmann::json& cell, std::ostream& warnings);
  /// At the end of a run, or when it stops on an error: rebuilds the log unless this run wrote it last, appended no
  /// cell it held already, and no one changed it since. An append cut short (a run killed while writing it leaves half
  /// a line) is repaired by the next run into OUT, even one that computes nothing. Where there is no log and this run
  /// added no cell, it writes none.
  void finish(std::ostream& warnings);

  /// The log's identity as a process last left it: inode, size and modification time.
  struct FileState {
    unsigned long long inode = 0, size = 0;
    long long modified_ns = 0;
    bool operator==(const FileState&) const = default;
  };

 private:
  void rebuild(std::ostream& warnings);

  std::filesystem::path out_;
  /// The cell files the log holds and the latest `finished_at` among them, when this run wrote it last (else empty).
  std::set<std::string> names_;
  /// By a reader's key (scene, δ, strategy): the latest finished_at in the log.
  std::map<std::string, std::string> latest_;
  /// The log holds an earlier copy of a cell appended again: rebuilt at the run's end.
  bool stale_ = false;
  std::optional<FileState> written_;
};

}  // namespace ccd::harness
