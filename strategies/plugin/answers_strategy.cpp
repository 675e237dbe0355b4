// `answers:DIR` (plugin_strategy.hpp): a folder of per-step answer files judged as a strategy, for CCD code that
// cannot be loaded into ccdbench (a CUDA program, a Python prototype, a run on another machine).
//
// DIR/LABEL/step_0000.csv, step_0001.csv, ... for a scene labelled LABEL in results (the suite's scene name, or a
// scene file's folder). Each line is one colliding pair (docs/audit.md "Answer files"):
//   vf,VERTEX,FACE[,TOI]
//   ee,A0,A1,B0,B1[,TOI]
// with the scene's global vertex and face ids (0-based) and an optional TOI in [0, 1]; '#' starts a comment line.
// An empty file is a step with no contact. The folder's step files (and nothing else of it) are read once per
// process, when its entry is made; every file of the scene is parsed and checked in init, before any step:
// a malformed line, an index out of range, a pair that cannot collide, a pair given twice or a line cut short is
// refused as FILE:line N: REASON, a missing scene folder as FOLDER: REASON; a step past the last file is refused
// (FILE: missing) when the run reaches it.
#include "ccd/config.hpp"
#include "core/error.hpp"
#include "strategies/plugin/contact_check.hpp"
#include "strategies/plugin/digest.hpp"
#include "strategies/plugin/library.hpp"
#include "strategies/plugin/plugin_strategy.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

namespace ccd::plugin {
namespace {

std::string step_file_name(std::size_t step) {
  char name[32];
  std::snprintf(name, sizeof name, "step_%04zu.csv", step);
  return name;
}

/// A folder of answers as read once (docs/DESIGN.md §10 "Identity"): the bytes of every step file (SCENE/step_NNNN.csv,
/// SCENE any folder path under it) by its path relative to the folder, and the digest of exactly those bytes. Its
/// steps are judged from these bytes, never from a second read, so that a file rewritten during the run cannot put
/// one answer's digest on another's verdict. Nothing else under the folder is read (a log or a core file beside the
/// steps costs nothing), and each step file is read in bounded memory: its size is checked first, and it is read no
/// further than that size.
struct FolderSnapshot {
  std::map<std::string, std::string> files;
  std::string digest;
};

/// A step file is at most this large: about 35 million pairs at 30 bytes a line, far beyond any mesh's contacts in one
/// step (the 1M-triangle ball's most contact-rich step has about 500,000). Larger is refused before it is read.
constexpr std::uintmax_t kMaxStepFileBytes = std::uintmax_t{1} << 30;

/// Whether `name` is a step file's name: step_ then four digits or more, then .csv.
bool is_step_file_name(const std::string& name) {
  constexpr std::size_t kDigitsFrom = 5, kSuffix = 4;  // "step_", ".csv"
  if (name.size() < kDigitsFrom + 4 + kSuffix || name.rfind("step_", 0) != 0 || name.substr(name.size() - kSuffix) != ".csv") return false;
  const std::string digits = name.substr(kDigitsFrom, name.size() - kDigitsFrom - kSuffix);
  return std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
}

/// What a path that should be a step file is, when it is not a regular file (or a link to one): "" when it is.
std::string not_a_regular_file(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::file_status own = std::filesystem::symlink_status(path, error);
  auto kind = [](std::filesystem::file_type type) -> std::string {
    switch (type) {
      case std::filesystem::file_type::directory: return "a folder";
      case std::filesystem::file_type::fifo: return "a FIFO (named pipe)";
      case std::filesystem::file_type::character: return "a character device";
      case std::filesystem::file_type::block: return "a block device";
      case std::filesystem::file_type::socket: return "a socket";
      default: return "not a regular file";
    }
  };
  if (own.type() == std::filesystem::file_type::regular) return {};
  if (own.type() != std::filesystem::file_type::symlink) return "is " + kind(own.type()) + ", not a step file (a regular file)";
  const std::filesystem::file_status target = std::filesystem::status(path, error);
  if (error) {
    return error == std::errc::too_many_symbolic_link_levels
               ? "is a link in a loop of links, not a step file"
               : "is a link to " + std::filesystem::read_symlink(path, error).string() + ", which does not exist";
  }
  if (target.type() == std::filesystem::file_type::regular) return {};
  return "is a link to " + kind(target.type()) + ", not to a step file (a regular file)";
}

/// The step file at `path` whole, its size checked first. @throws InputError(FILE, REASON) for one that is not a
/// regular file or a link to one, is larger than kMaxStepFileBytes, or cannot be read to its size.
std::string read_step_bytes(const std::filesystem::path& path) {
  if (const std::string why = not_a_regular_file(path); !why.empty()) throw InputError(path, {}, why);
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) throw InputError(path, {}, "cannot be read: " + error.message());
  if (size > kMaxStepFileBytes) {
    throw InputError(path, {}, std::to_string(size) + " bytes, more than a step file may hold (" + std::to_string(kMaxStepFileBytes) + ")");
  }
  std::ifstream in(path, std::ios::binary);
  std::string bytes(static_cast<std::size_t>(size), '\0');
  if (!in || !in.read(bytes.data(), static_cast<std::streamsize>(size))) throw InputError(path, {}, "cannot be read to its size");
  return bytes;
}

/// The step files under `folder` (scene folders found through links too, each folder once), by relative path.
void find_step_files(const std::filesystem::path& folder, const std::filesystem::path& relative, std::vector<std::filesystem::path>& visited,
                     std::vector<std::string>& found) {
  std::error_code error;
  const std::filesystem::path real = std::filesystem::canonical(folder, error);
  if (error || std::find(visited.begin(), visited.end(), real) != visited.end()) return;  // a loop of folders: once
  visited.push_back(real);
  std::vector<std::filesystem::directory_entry> entries;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) entries.push_back(entry);
  for (const auto& entry : entries) {
    const std::string name = entry.path().filename().string();
    const std::filesystem::path path = relative / name;
    if (is_step_file_name(name)) {
      found.push_back(path.generic_string());  // whatever it is: read_step_bytes says what is wrong with it
    } else if (std::filesystem::is_directory(entry.path(), error)) {
      find_step_files(entry.path(), path, visited, found);
    }
  }
}

std::shared_ptr<const FolderSnapshot> read_folder(const std::filesystem::path& folder) {
  auto snapshot = std::make_shared<FolderSnapshot>();
  std::vector<std::filesystem::path> visited;
  std::vector<std::string> names;
  find_step_files(folder, {}, visited, names);
  std::sort(names.begin(), names.end());
  // Each name and each file's bytes with its length before it: no two folders give the same stream (a file's bytes
  // may hold anything, a name's end included). The digest is taken as the files are read, not of a copy of them all.
  StreamDigest stream;
  auto append = [&](const std::string& part) {
    const std::uint64_t size = part.size();
    stream.update(std::string_view(reinterpret_cast<const char*>(&size), sizeof size));
    stream.update(part);
  };
  for (const std::string& name : names) {
    std::string bytes = read_step_bytes(folder / name);
    append(name);
    append(bytes);
    snapshot->files.emplace(name, std::move(bytes));
  }
  snapshot->digest = stream.hex();
  return snapshot;
}

/// One step's file, checked against the scene. @throws InputError (the file, "line N", why).
CollisionSet read_step_file(const std::filesystem::path& path, const std::string& text, ContactCheck& check) {
  CollisionSet set;
  check.reset();
  std::size_t line_number = 0;
  for (std::size_t begin = 0; begin < text.size();) {
    ++line_number;
    const std::size_t end = text.find('\n', begin);
    const std::string where = "line " + std::to_string(line_number);
    // A last line without its newline is a file cut short (a writer that stopped), never a whole answer.
    if (end == std::string::npos) throw InputError(path, where, "the file ends inside this line (cut short?): every line ends with a newline");
    std::string line = text.substr(begin, end - begin);
    begin = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line.front() == '#') continue;
    std::vector<std::string> fields;
    std::stringstream split(line);
    for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    const bool vertex_face = fields[0] == "vf";
    if (!vertex_face && fields[0] != "ee") throw InputError(path, where, "'" + fields[0] + "' is neither vf nor ee");
    const std::size_t ids = vertex_face ? 2 : 4;
    if (fields.size() != ids + 1 && fields.size() != ids + 2) {
      throw InputError(
          path, where,
          fields[0] + " takes " + std::to_string(ids) + " indices and an optional TOI, not " + std::to_string(fields.size() - 1) + " fields");
    }
    std::uint64_t id[4] = {};
    for (std::size_t k = 0; k < ids; ++k) {
      const std::string& field = fields[k + 1];
      const auto [at, error] = std::from_chars(field.data(), field.data() + field.size(), id[k]);
      if (error != std::errc() || at != field.data() + field.size() || field.empty()) {
        throw InputError(path, where, "index " + std::to_string(k + 1) + " '" + field + "' is not a whole number");
      }
    }
    double toi = kNoToi;
    if (fields.size() == ids + 2 && !fields.back().empty()) {
      const std::string& field = fields.back();
      const auto [at, error] = std::from_chars(field.data(), field.data() + field.size(), toi);
      if (error != std::errc() || at != field.data() + field.size() || std::isnan(toi)) {
        throw InputError(path, where, "TOI '" + field + "' is not a number");
      }
    }
    std::string why;
    if (vertex_face) {
      const auto pair = check.vertex_face(id[0], id[1], toi, why);
      if (!pair) throw InputError(path, where, why);
      set.add(*pair, toi);
    } else {
      const auto pair = check.edge_edge(id[0], id[1], id[2], id[3], toi, why);
      if (!pair) throw InputError(path, where, why);
      set.add(*pair, toi);
    }
  }
  set.normalize();
  return set;
}

void refuse_answer_shapes(const std::string& name, const Scene& scene) { refuse_shapes(name, scene, "answer files name no analytic shapes"); }

void refuse_other_digest(const std::filesystem::path& folder, const std::string& given, const std::string& digest) {
  if (!given.empty() && given != digest) {
    throw std::invalid_argument("answers " + folder.string() + ": its files changed (digest " + digest + ", the spec asks for " + given + ")");
  }
}

class AnswersStrategy final : public strategies::Strategy {
 public:
  AnswersStrategy(std::filesystem::path folder, std::shared_ptr<const FolderSnapshot> snapshot)
      : folder_(std::move(folder)), snapshot_(std::move(snapshot)) {}

  std::string name() const override { return std::string(narrowphase::kAnswersHead) + ":" + folder_.string() + ":digest=" + snapshot_->digest; }

  void name_scene(const std::string& label) override { label_ = label; }

  void init(const Scene& scene, std::span<const Vec3>) override {
    refuse_answer_shapes(name(), scene);
    const std::filesystem::path folder = folder_ / label_;
    auto step_file = [&](std::size_t k) { return snapshot_->files.find(std::filesystem::path(label_).generic_string() + "/" + step_file_name(k)); };
    if (label_.empty() || step_file(0) == snapshot_->files.end()) {
      throw InputError(folder, {},
                       "no answer folder for scene '" + label_ + "' (answers:DIR reads DIR/SCENE/" + step_file_name(0) +
                           ", one file per step; docs/audit.md, \"Answer files\")");
    }
    ContactCheck check(scene, ContactCheck::Toi::optional);
    steps_.clear();
    for (std::size_t k = 0; step_file(k) != snapshot_->files.end(); ++k) {
      steps_.push_back(read_step_file(folder / step_file_name(k), step_file(k)->second, check));
    }
    folder_of_scene_ = folder;
  }

  strategies::StepResult step(const StepView& view, bool) override {
    if (view.index >= steps_.size()) {
      throw InputError(folder_of_scene_ / step_file_name(view.index), {},
                       "missing: the folder answers steps 0 to " + std::to_string(steps_.size()) + " - 1 only, and the run has step " +
                           std::to_string(view.index));
    }
    strategies::StepResult result;
    result.collisions = steps_[view.index];
    result.counters.elementary_tests = result.collisions.vertex_face().size() + result.collisions.edge_edge().size();
    return result;
  }

 private:
  std::filesystem::path folder_;
  std::shared_ptr<const FolderSnapshot> snapshot_;
  std::string label_;
  std::filesystem::path folder_of_scene_;
  std::vector<CollisionSet> steps_;
};

}  // namespace

strategies::StrategyEntry answers_entry(const std::string& name) {
  const std::filesystem::path given = name.substr(std::strlen(narrowphase::kAnswersHead) + 1);
  if (!std::filesystem::is_directory(given)) {
    throw std::invalid_argument(name + ": " + given.string() + " is not a folder (answers:DIR reads DIR/SCENE/" + step_file_name(0) + ", ...)");
  }
  const std::filesystem::path folder = std::filesystem::weakly_canonical(std::filesystem::absolute(given));
  strategies::StrategyEntry entry;
  entry.name = name;
  entry.help = "answers read from " + folder.string() + " (one file per scene and step)";
  entry.keys = {narrowphase::KeySpec::text("digest", "the folder's digest (filled in; a cell kept for other answers is never reused)")};
  entry.takes_narrow_phase = false;
  // Read from files: no time of its own, so no speed-up over anything.
  entry.baseline.clear();
  entry.explain_miss = [](const narrowphase::PairRows&, bool) { return std::string("unreported"); };
  // Read once, when the entry is made (once per process): every cell of the run judges these bytes.
  std::shared_ptr<const FolderSnapshot> snapshot = read_folder(folder);
  entry.resolve = [folder, snapshot](const narrowphase::SpecReader&, const narrowphase::ResolvedNarrowPhase&) {
    return std::string(narrowphase::kAnswersHead) + ":" + folder.string() + ":digest=" + snapshot->digest;
  };
  entry.check = [folder, snapshot](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase&) {
    refuse_other_digest(folder, keys.text("digest"), snapshot->digest);
  };
  entry.check_scene = [name](const narrowphase::SpecReader&, const Scene& scene) { refuse_answer_shapes(name, scene); };
  entry.make = [folder, snapshot](strategies::StrategyRequest request) -> std::unique_ptr<strategies::Strategy> {
#if CCDBENCH_GUARD_READ_ONCE
    std::shared_ptr<const FolderSnapshot> judged = snapshot;
#else
    // Without the guard: each strategy made reads the folder again, and its name's digest is of another read.
    auto judged = std::make_shared<FolderSnapshot>(*read_folder(folder));
    judged->digest = content_digest(folder);
#endif
    refuse_other_digest(folder, request.keys.text("digest"), judged->digest);
    return std::make_unique<AnswersStrategy>(folder, judged);
  };
  return entry;
}

}  // namespace ccd::plugin
