#pragma once
/// @file
/// The rational CSV query format (docs/DATA.md; docs/DESIGN.md §7): 8 rows per query, 3 exact rationals
/// per row as numerator,denominator pairs, an optional 7th column of truth (1 = the primitives touch for some
/// t in [0, 1] at zero thickness), or the truth in mma_bool/NAME_mma_bool.json beside queries/NAME.csv. A file whose
/// labels are for another thickness (the misses of a run at δ, a comparison's newly missed pairs) says so on its
/// first line: `# labels at thickness D` (D the shortest decimal that reads back as the double δ).

#include "core/vec.hpp"

#include <gmpxx.h>

#include <array>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

namespace ccd::datasets {

enum class QueryKind { vertex_face, edge_edge };

/// "vertex-face" or "edge-edge".
std::string_view to_string(QueryKind kind);

/// One query, rows in the data's own order:
///   vertex-face: v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1
///   edge-edge:   ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1
struct Query {
  using RationalPoint = std::array<mpq_class, 3>;
  /// The coordinates exactly as written (canonical rationals).
  std::array<RationalPoint, 8> exact;
  /// The doubles nearest to them.
  std::array<Vec3, 8> rounded;
  /// Whether every coordinate equals its double (false: only `exact` is the query).
  bool exactly_double = true;
  /// Ground truth when the file or its truth file has it.
  std::optional<bool> truth;
  /// 1-based line of the query's first row.
  std::size_t first_line = 0;
};

struct QueryFile {
  std::filesystem::path path;
  QueryKind kind = QueryKind::vertex_face;
  std::vector<Query> queries;
  /// The mma_bool file the truth came from; nullopt when it came from the 7th column or there is none.
  std::optional<std::filesystem::path> truth_file;
  /// The thickness its labels are for, when its first line says one (`# labels at thickness D`); else 0.
  double labels_thickness = 0;

  /// Whether every query has a truth label.
  bool has_truth() const;
  /// How many queries have a truth label.
  std::size_t labelled() const;
  /// Queries whose truth is "collide".
  std::size_t positives() const;
  /// Queries with at least one coordinate that is not exactly a double.
  std::size_t not_exactly_double() const;
};

/// docs/DESIGN.md §7: under a `vertex-face` folder or named `*vf.csv` is VF; under `edge-edge` or `*ee.csv` is EE.
std::optional<QueryKind> classify_query_path(const std::filesystem::path& path);

/// Files named on the command line are taken as they are; directories are searched recursively for `.csv`
/// files only. The result is sorted within each directory and keeps the order of `inputs`.
/// @throws InputError for a path that does not exist.
std::vector<std::filesystem::path> discover_query_files(const std::vector<std::filesystem::path>& inputs);

/// For `.../queries/NAME.csv`, the truth file `.../mma_bool/NAME_mma_bool.json`; nullopt for other paths.
std::optional<std::filesystem::path> truth_file_for(const std::filesystem::path& csv);

/// The first line of a file whose labels are for thickness δ > 0.
inline constexpr const char* kLabelsThicknessLine = "# labels at thickness ";

/// Reads a query file and its truth. `kind` overrides the path rule.
/// @throws InputError (file, line, reason) for: a row whose column count is not 6 or 7 or differs from the
///         first row's, a non-integer, a zero denominator, a row count that is not a multiple of 8, a truth
///         value that is not 0/1 or changes within a query, a truth file whose length differs from the query
///         count, a value beyond the double range, and a path whose kind cannot be told.
QueryFile read_query_file(const std::filesystem::path& path, std::optional<QueryKind> kind = std::nullopt);

/// A JSON array of booleans (an mma_bool file). @throws InputError when malformed.
std::vector<bool> read_truth_file(const std::filesystem::path& path);

/// The query whose rows are these doubles (each exactly a rational), without truth.
Query query_of_doubles(const std::array<Vec3, 8>& rows);

/// Writes queries as the 7-column format (truth on every query) or the 6-column one (on none), atomically; labels for
/// a thickness `labels_thickness` > 0 are said so on the first line. @throws std::invalid_argument for mixed labels.
void write_query_file(const std::filesystem::path& path, const std::vector<Query>& queries, double labels_thickness = 0);

}  // namespace ccd::datasets
