// `answers:DIR` (plugin_strategy.hpp): a folder of per-step answer files judged as a strategy, for CCD code that
// cannot be loaded into ccdbench (a CUDA program, a Python prototype, a run on another machine).
//
// DIR/LABEL/step_0000.csv, step_0001.csv, ... for a scene labelled LABEL in results (the suite's scene name, or a
// scene file's folder). Each line is one colliding pair (README "Answer files"):
//   vf,VERTEX,FACE[,TOI]
//   ee,A0,A1,B0,B1[,TOI]
// with the scene's global vertex and face ids (0-based) and an optional TOI in [0, 1]; '#' starts a comment line.
// An empty file is a step with no contact. The folder is read once per process, when its entry is made; every file of
// the scene is parsed and checked in init, before any step:
// a malformed line, an index out of range, a pair that cannot collide, a pair given twice or a line cut short is
// refused as FILE:line N: REASON, a missing scene folder as FOLDER: REASON; a step past the last file is refused
// (FILE: missing) when the run reaches it.
#include "ccd/config.hpp"
#include "core/error.hpp"
#include "strategies/plugin/contact_check.hpp"
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

/// A folder of answers as read once (docs/DESIGN.md §10 "Identity"): every regular file's bytes by its path relative
/// to the folder (folders linked into it followed), and the digest of exactly those bytes. Its steps are judged from
/// these bytes, never from a second read, so that a file rewritten during the run cannot put one answer's digest on
/// another's verdict. The whole folder is held in memory for the process (answers are text, a few bytes a pair).
struct FolderSnapshot {
  std::map<std::string, std::string> files;
  std::string digest;
};

std::shared_ptr<const FolderSnapshot> read_folder(const std::filesystem::path& folder) {
  auto snapshot = std::make_shared<FolderSnapshot>();
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder, std::filesystem::directory_options::follow_directory_symlink)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  // Each name and each file's bytes with its length before it: no two folders give the same stream (a file's bytes
  // may hold anything, a name's end included).
  std::string stream;
  auto append = [&](const std::string& part) {
    const std::uint64_t size = part.size();
    stream.append(reinterpret_cast<const char*>(&size), sizeof size);
    stream += part;
  };
  for (const std::filesystem::path& file : files) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file, {}, "cannot be read");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string name = std::filesystem::relative(file, folder).generic_string();
    append(name);
    append(bytes);
    snapshot->files.emplace(name, std::move(bytes));
  }
  snapshot->digest = bytes_digest(stream);
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
                           ", one file per step; README \"Answer files\")");
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
