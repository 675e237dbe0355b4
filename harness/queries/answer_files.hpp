#pragma once
/// @file
/// Query answer files (docs/audit.md "Answer files"): per-query answers of CCD code that cannot be loaded into ccdbench,
/// scored like a built-in method (`queries --answers FILE`), and the answers `queries --write-answers FILE` writes
/// (each method's, with the exact label and TOI) in the same format.
///
/// A CSV with a header line naming its columns, in any order: `file`, `index` and `hit` are required; `toi` and
/// `method` are optional; other columns (label, exact_toi, ...) are read past.
/// - file: a query file among the inputs, as `queries` names it or by a unique end of its path
///   ("vertex-face/x.csv");
/// - index: the query's 0-based place in that file;
/// - hit: 1 (collides), 0 (apart), or `error` (no answer: counted apart, as a miss);
/// - toi: the time of impact in [0, 1], or empty;
/// - method: which method's answer the line is, when the file holds several (`answers:FILE:method=NAME` picks one).
/// Every query of every input file needs exactly one answer; a line cut short, a value that is not one of these, an
/// answer for a query that is not among the inputs, or a query without an answer is refused as FILE:line N: REASON.

#include "datasets/query_file.hpp"

#include <cstddef>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace ccd::harness {

struct AnswerLine {
  std::string file;
  std::size_t index = 0;
  /// 0 apart, 1 collides, -1 error.
  int hit = 0;
  double toi = std::numeric_limits<double>::quiet_NaN();
  std::string method;
  std::size_t line = 0;
};

/// The lines of one answer file, for one method.
struct AnswerTable {
  std::filesystem::path path;
  /// The digest of the bytes read (and scored).
  std::string digest;
  /// The method chosen (`method=`), or the file's one method, or "" when it has no method column.
  std::string method;
  std::vector<AnswerLine> lines;
  /// After bind_answers: for each input file's path as `queries` names it, the line of each query.
  std::map<std::string, std::vector<const AnswerLine*>> by_file;
};

/// Reads `path` and keeps the lines of `method` ("" : the file must hold one method, or none named).
/// @throws InputError (the file, line N, reason).
AnswerTable read_answer_table(const std::filesystem::path& path, const std::string& method);

/// Matches every line to a query of `files` and checks that each query has exactly one answer.
/// @throws InputError (the answer file, line N or the query without an answer, reason).
void bind_answers(AnswerTable& table, const std::vector<datasets::QueryFile>& files);

/// Whether a method spec names an answer file (`answers:FILE[:method=NAME]`).
bool names_answers(const std::string& spec);

/// A double as the answer files write it: the shortest text that reads back as the same double.
std::string answer_number(double value);

}  // namespace ccd::harness
