#include "datasets/query_file.hpp"

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/input_file.hpp"
#include "datasets/rational.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>

namespace ccd::datasets {
namespace {

constexpr std::size_t kRowsPerQuery = 8;

bool ends_with(const std::string& text, std::string_view suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::vector<std::string_view> split_columns(std::string_view line) {
  std::vector<std::string_view> columns;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = line.find(',', begin);
    std::string_view column = line.substr(begin, comma == std::string_view::npos ? std::string_view::npos : comma - begin);
    while (!column.empty() && (column.front() == ' ' || column.front() == '\t')) column.remove_prefix(1);
    while (!column.empty() && (column.back() == ' ' || column.back() == '\t')) column.remove_suffix(1);
    columns.push_back(column);
    if (comma == std::string_view::npos) break;
    begin = comma + 1;
  }
  return columns;
}

struct Row {
  Query::RationalPoint point;
  std::optional<bool> truth;
  std::size_t line;
};

}  // namespace

std::string_view to_string(QueryKind kind) { return kind == QueryKind::vertex_face ? "vertex-face" : "edge-edge"; }

bool QueryFile::has_truth() const {
  return std::all_of(queries.begin(), queries.end(), [](const Query& q) { return q.truth.has_value(); });
}

std::size_t QueryFile::labelled() const {
  return static_cast<std::size_t>(std::count_if(queries.begin(), queries.end(), [](const Query& q) { return q.truth.has_value(); }));
}

std::size_t QueryFile::positives() const {
  return static_cast<std::size_t>(std::count_if(queries.begin(), queries.end(), [](const Query& q) { return q.truth.value_or(false); }));
}

std::size_t QueryFile::not_exactly_double() const {
  return static_cast<std::size_t>(std::count_if(queries.begin(), queries.end(), [](const Query& q) { return !q.exactly_double; }));
}

std::optional<QueryKind> classify_query_path(const std::filesystem::path& path) {
  const std::string name = path.filename().string();
  if (ends_with(name, "vf.csv")) return QueryKind::vertex_face;
  if (ends_with(name, "ee.csv")) return QueryKind::edge_edge;
  for (const auto& part : path.parent_path()) {
    if (part == "vertex-face") return QueryKind::vertex_face;
    if (part == "edge-edge") return QueryKind::edge_edge;
  }
  return std::nullopt;
}

std::vector<std::filesystem::path> discover_query_files(const std::vector<std::filesystem::path>& inputs) {
  std::vector<std::filesystem::path> files;
  for (const std::filesystem::path& input : inputs) {
    if (!std::filesystem::exists(input)) throw InputError(input, {}, "no such file or directory");
    if (!std::filesystem::is_directory(input)) {
      files.push_back(input);
      continue;
    }
    std::vector<std::filesystem::path> found;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(input)) {
      if (entry.is_regular_file() && entry.path().extension() == ".csv") found.push_back(entry.path());
    }
    std::sort(found.begin(), found.end());
    files.insert(files.end(), found.begin(), found.end());
  }
  return files;
}

std::optional<std::filesystem::path> truth_file_for(const std::filesystem::path& csv) {
  if (csv.parent_path().filename() != "queries") return std::nullopt;
  return csv.parent_path().parent_path() / "mma_bool" / (csv.stem().string() + "_mma_bool.json");
}

std::vector<bool> read_truth_file(const std::filesystem::path& path) {
  const nlohmann::json document = read_json_file(path, "truth file");
  if (!document.is_array()) throw InputError(path, {}, "a truth file must be a JSON array of booleans");
  std::vector<bool> truth;
  truth.reserve(document.size());
  for (std::size_t i = 0; i < document.size(); ++i) {
    if (!document[i].is_boolean()) throw InputError(path, "entry " + std::to_string(i), "not a boolean");
    truth.push_back(document[i].get<bool>());
  }
  return truth;
}

namespace {

/// The thickness a file's first line says its labels are for. @throws InputError for any other comment line, or
/// this one anywhere but first.
double labels_thickness_of(const std::filesystem::path& path, const std::string& line, std::size_t line_number, bool not_first) {
  const std::string header = kLabelsThicknessLine;
  if (line.rfind(header, 0) != 0 || not_first) {
    throw InputError(path, line_at(line_number), "the only comment a query file may hold is its first line, '" + header + "D'");
  }
  const std::optional<double> thickness = parse_double(line.substr(header.size()));
  if (!thickness || !std::isfinite(*thickness) || *thickness < 0) {
    throw InputError(path, line_at(line_number), "'" + line.substr(header.size()) + "' is not a thickness (a finite number >= 0)");
  }
  return *thickness;
}

/// The queries of a file's rows, 8 rows each (the count checked by the caller): one truth per query, coordinates
/// rounded to doubles. @throws InputError for a truth that changes within a query or a value beyond double's range.
void assemble_queries(const std::filesystem::path& path, std::vector<Row>& rows, QueryFile& file) {
  file.queries.resize(rows.size() / kRowsPerQuery);
  for (std::size_t q = 0; q < file.queries.size(); ++q) {
    Query& query = file.queries[q];
    query.first_line = rows[q * kRowsPerQuery].line;
    query.truth = rows[q * kRowsPerQuery].truth;
    for (std::size_t r = 0; r < kRowsPerQuery; ++r) {
      Row& row = rows[q * kRowsPerQuery + r];
      if (row.truth != query.truth) {
        throw InputError(path, line_at(row.line), "truth changes within query " + std::to_string(q) + " (it must repeat on all 8 rows)");
      }
      for (int k = 0; k < 3; ++k) {
        const RoundedRational rounded = round_to_double(row.point[k]);
        if (!std::isfinite(rounded.value)) {
          throw InputError(path, line_at(row.line), "coordinate beyond the range of double");
        }
        query.rounded[r][k] = rounded.value;
        query.exactly_double = query.exactly_double && rounded.exact;
      }
      query.exact[r] = std::move(row.point);
    }
  }
}

}  // namespace

QueryFile read_query_file(const std::filesystem::path& path, std::optional<QueryKind> kind) {
  if (!kind) kind = classify_query_path(path);
  if (!kind) {
    throw InputError(path, {},
                     "cannot tell vertex-face from edge-edge: put the file under a 'vertex-face' or "
                     "'edge-edge' folder, or name it *vf.csv or *ee.csv");
  }
  std::ifstream in = open_input_file(path, "query file");

  QueryFile file;
  bool saw_header = false;
  std::vector<Row> rows;
  std::size_t columns_expected = 0;
  std::string line;
  for (std::size_t line_number = 1; std::getline(in, line); ++line_number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (line.front() == '#') {
      file.labels_thickness = labels_thickness_of(path, line, line_number, !rows.empty() || saw_header);
      saw_header = true;
      continue;
    }
    const auto columns = split_columns(line);
    if (columns_expected == 0) {
      if (columns.size() != 6 && columns.size() != 7) {
        throw InputError(path, line_at(line_number),
                         "expected 6 or 7 columns (x, y, z as numerator,denominator [, truth]), found " + std::to_string(columns.size()));
      }
      columns_expected = columns.size();
    } else if (columns.size() != columns_expected) {
      throw InputError(path, line_at(line_number),
                       "expected " + std::to_string(columns_expected) + " columns like the first row, found " + std::to_string(columns.size()));
    }
    Row row;
    row.line = line_number;
    for (int k = 0; k < 3; ++k) {
      const auto numerator = parse_integer(columns[2 * k]);
      const auto denominator = parse_integer(columns[2 * k + 1]);
      if (!numerator || !denominator) {
        throw InputError(path, line_at(line_number),
                         "column " + std::to_string(numerator ? 2 * k + 2 : 2 * k + 1) + ": not an integer: '" +
                             std::string(numerator ? columns[2 * k + 1] : columns[2 * k]) + "'");
      }
      if (*denominator == 0) {
        throw InputError(path, line_at(line_number), "column " + std::to_string(2 * k + 2) + ": zero denominator");
      }
      row.point[k] = mpq_class(*numerator, *denominator);
      row.point[k].canonicalize();
    }
    if (columns_expected == 7) {
      if (columns[6] != "0" && columns[6] != "1") {
        throw InputError(path, line_at(line_number), "column 7 (truth) must be 0 or 1, found '" + std::string(columns[6]) + "'");
      }
      row.truth = columns[6] == "1";
    }
    rows.push_back(std::move(row));
  }
  if (rows.size() % kRowsPerQuery != 0) {
    throw InputError(path, line_at(rows.empty() ? 1 : rows.back().line),
                     std::to_string(rows.size()) + " rows is not a multiple of 8 (8 rows per query)");
  }

  if (saw_header && file.labels_thickness > 0 && columns_expected != 7) {
    throw InputError(path, "line 1", "says what thickness its labels are for, but it has no labels (no 7th column)");
  }
  file.path = path;
  file.kind = *kind;
  assemble_queries(path, rows, file);
  if (columns_expected != 7) {
    const auto truth_path = truth_file_for(path);
    if (truth_path && std::filesystem::exists(*truth_path)) {
      const std::vector<bool> truth = read_truth_file(*truth_path);
      if (truth.size() != file.queries.size()) {
        throw InputError(
            *truth_path, {},
            "has " + std::to_string(truth.size()) + " entries but " + path.string() + " has " + std::to_string(file.queries.size()) + " queries");
      }
      for (std::size_t q = 0; q < truth.size(); ++q) file.queries[q].truth = truth[q];
      file.truth_file = *truth_path;
    }
  }
  return file;
}

void write_query_file(const std::filesystem::path& path, const std::vector<Query>& queries, double labels_thickness) {
  AtomicFile file(path, std::ios::out);
  std::ofstream& out = file.stream();
  // Labelled (7 columns) or not (6): a file is one or the other.
  const bool labelled = !queries.empty() && queries.front().truth.has_value();
  if (labelled && labels_thickness > 0) {
    char text[64];
    out << kLabelsThicknessLine << std::string_view(text, std::to_chars(text, text + sizeof text, labels_thickness).ptr - text) << '\n';
  }
  for (const Query& query : queries) {
    if (query.truth.has_value() != labelled) throw std::invalid_argument("write_query_file: every query needs a truth label, or none does");
    for (const Query::RationalPoint& point : query.exact) {
      for (int k = 0; k < 3; ++k) out << point[k].get_num().get_str() << ',' << point[k].get_den().get_str() << (k < 2 || labelled ? "," : "");
      if (labelled) out << (*query.truth ? 1 : 0);
      out << '\n';
    }
  }
  file.commit();
}

Query query_of_doubles(const std::array<Vec3, 8>& rows) {
  Query query;
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) query.exact[i][k] = mpq_class(rows[i][k]);  // exact: every double is a rational
  }
  query.rounded = rows;
  return query;
}

}  // namespace ccd::datasets
