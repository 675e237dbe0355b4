#include "harness/queries/answer_files.hpp"

#include "core/error.hpp"
#include "datasets/content_hash.hpp"
#include "strategies/narrowphase/spec.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>

namespace ccd::harness {
namespace {

/// A line longer than this is no answer (file,index,hit,toi,method with a long path and method name is a few hundred
/// bytes): a file whose line 1 passes it is refused there, not read whole first.
constexpr std::size_t kLongestAnswerLine = 1 << 16;

/// One CSV line's fields. Answer files hold no quoted fields: paths and method names with ',' are refused.
std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = line.find(',', begin);
    fields.push_back(line.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin));
    if (comma == std::string::npos) return fields;
    begin = comma + 1;
  }
}

/// Whether `path` ends with the components of `tail` ("vertex-face/x.csv" ends "data/vertex-face/x.csv").
bool ends_with_components(const std::filesystem::path& path, const std::filesystem::path& tail) {
  auto p = path.lexically_normal();
  auto t = tail.lexically_normal();
  std::vector<std::filesystem::path> a(p.begin(), p.end()), b(t.begin(), t.end());
  if (b.empty() || b.size() > a.size()) return false;
  return std::equal(b.rbegin(), b.rend(), a.rbegin());
}

}  // namespace

std::string answer_number(double value) {
  char text[64];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
}

namespace {

/// One answer line's fields, by the header's columns. @throws InputError (the line) for a bad field.
AnswerLine parse_answer_line(const std::vector<std::string>& fields, const std::map<std::string, std::size_t>& column,
                             const std::filesystem::path& path, const std::string& where) {
  if (fields.size() != column.size()) {
    throw InputError(path, where, std::to_string(fields.size()) + " fields, but the header names " + std::to_string(column.size()));
  }
  AnswerLine answer;
  answer.file = fields[column.at("file")];
  if (answer.file.empty()) throw InputError(path, where, "no file");
  const std::string& index = fields[column.at("index")];
  const auto [at, error] = std::from_chars(index.data(), index.data() + index.size(), answer.index);
  if (error != std::errc() || at != index.data() + index.size() || index.empty())
    throw InputError(path, where, "index '" + index + "' is not a whole number");
  const std::string& hit = fields[column.at("hit")];
  if (hit == "1") {
    answer.hit = 1;
  } else if (hit == "0") {
    answer.hit = 0;
  } else if (hit == "error") {
    answer.hit = -1;
  } else {
    throw InputError(path, where, "hit '" + hit + "' is none of 1, 0, error");
  }
  if (column.count("toi") && !fields[column.at("toi")].empty()) {
    const std::string& toi = fields[column.at("toi")];
    const auto [end_of, bad] = std::from_chars(toi.data(), toi.data() + toi.size(), answer.toi);
    if (bad != std::errc() || end_of != toi.data() + toi.size() || !(answer.toi >= 0.0 && answer.toi <= 1.0)) {
      throw InputError(path, where, "toi '" + toi + "' is not a number in [0, 1]");
    }
  }
  if (column.count("method")) answer.method = fields[column.at("method")];
  return answer;
}

/// The header's columns. @throws InputError (the line) for a column named twice or a required one missing.
std::map<std::string, std::size_t> parse_answer_header(const std::vector<std::string>& fields, const std::filesystem::path& path,
                                                       const std::string& where) {
  std::map<std::string, std::size_t> column;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    if (!column.emplace(fields[k], k).second) throw InputError(path, where, "column '" + fields[k] + "' is named twice");
  }
  for (const char* required : {"file", "index", "hit"}) {
    if (!column.count(required)) {
      throw InputError(path, where,
                       std::string("the header names no '") + required + "' column (an answer file starts with a header: file,index,hit,toi)");
    }
  }
  return column;
}

/// The method a table is of: the one asked for (by its whole name or its head, "cubic64" for "cubic64:eta=1e-06"),
/// or the only one; the other methods' lines are dropped.
void pick_answer_method(AnswerTable& table, const std::set<std::string>& methods, const std::string& method) {
  auto head = [](const std::string& name) { return name.substr(0, name.find(':')); };
  std::string listed;
  for (const std::string& m : methods) listed += (listed.empty() ? "" : ", ") + (m.empty() ? std::string("(none)") : m);
  if (method.empty()) {
    if (methods.size() > 1)
      throw InputError(table.path, {}, "holds the answers of several methods (" + listed + "): pick one with answers:FILE:method=NAME");
    table.method = methods.empty() ? "" : *methods.begin();
    return;
  }
  std::vector<std::string> matching;
  for (const std::string& m : methods) {
    if (m == method) matching = {m};
  }
  if (matching.empty()) {
    for (const std::string& m : methods) {
      if (head(m) == method) matching.push_back(m);
    }
  }
  if (matching.size() != 1) {
    throw InputError(table.path, {}, "method=" + method + " names " + (matching.empty() ? "none" : "several") + " of its methods (" + listed + ")");
  }
  table.method = matching.front();
  std::erase_if(table.lines, [&](const AnswerLine& line) { return line.method != table.method; });
}

}  // namespace

AnswerTable read_answer_table(const std::filesystem::path& path, const std::string& method) {
  // A folder, a FIFO or a device is no answer file: refused before anything is read from it.
  std::error_code status_error;
  const std::filesystem::file_status status = std::filesystem::status(path, status_error);
  if (status_error || !std::filesystem::exists(status)) throw InputError(path, {}, "no such file");
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError(path, {}, std::filesystem::is_directory(status) ? "is a folder: an answer file (CSV) is expected" : "is not a regular file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, {}, "cannot be read");
  AnswerTable table;
  table.path = path;
  // Read line by line, each line digested as it is read: the digest is of the bytes scored, from this one read (a
  // file rewritten while it is read cannot put one file's digest on another's verdict), and a file that is not an
  // answer file is refused at its first bad line, without holding the rest.
  datasets::ContentHash digest;
  std::map<std::string, std::size_t> column;
  std::set<std::string> methods;
  std::size_t line_number = 0;
  for (std::string line; in.peek() != std::char_traits<char>::eof();) {
    ++line_number;
    const std::string where = "line " + std::to_string(line_number);
    line.clear();
    for (int c; (c = in.get()) != std::char_traits<char>::eof() && c != '\n';) {
      line.push_back(static_cast<char>(c));
      if (line.size() > kLongestAnswerLine)
        throw InputError(path, where, "longer than " + std::to_string(kLongestAnswerLine) + " bytes: not an answer file");
    }
    const bool ended = !in.eof();
    digest.bytes(line.data(), line.size());
    if (ended) digest.bytes("\n", 1);
    if (!ended) throw InputError(path, where, "the file ends inside this line (cut short?): every line ends with a newline");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string> fields = fields_of(line);
    if (column.empty()) {
      column = parse_answer_header(fields, path, where);
      continue;
    }
    AnswerLine answer = parse_answer_line(fields, column, path, where);
    answer.line = line_number;
    methods.insert(answer.method);
    table.lines.push_back(std::move(answer));
  }
  if (in.bad()) throw InputError(path, {}, "cannot be read");
  table.digest = digest.hex();
  if (column.empty()) throw InputError(path, {}, "empty: an answer file starts with a header (file,index,hit,toi)");
  pick_answer_method(table, methods, method);
  return table;
}

void bind_answers(AnswerTable& table, const std::vector<datasets::QueryFile>& files) {
  table.by_file.clear();
  for (const datasets::QueryFile& file : files) table.by_file[file.path.string()].assign(file.queries.size(), nullptr);
  std::map<std::string, const datasets::QueryFile*> resolved;  // an answer's file name -> the input it names
  for (const AnswerLine& line : table.lines) {
    const std::string where = "line " + std::to_string(line.line);
    auto it = resolved.find(line.file);
    if (it == resolved.end()) {
      const datasets::QueryFile* match = nullptr;
      for (const datasets::QueryFile& file : files) {
        if (file.path.string() == line.file) match = &file;
      }
      if (match == nullptr) {
        for (const datasets::QueryFile& file : files) {
          if (!ends_with_components(file.path, line.file)) continue;
          if (match != nullptr)
            throw InputError(table.path, where, "file '" + line.file + "' names several of the query files: give more of its path");
          match = &file;
        }
      }
      if (match == nullptr) throw InputError(table.path, where, "file '" + line.file + "' is none of the query files scored");
      it = resolved.emplace(line.file, match).first;
    }
    std::vector<const AnswerLine*>& slots = table.by_file.at(it->second->path.string());
    if (line.index >= slots.size()) {
      throw InputError(table.path, where,
                       "index " + std::to_string(line.index) + " is past the end of " + it->second->path.string() + " (" +
                           std::to_string(slots.size()) + " queries, indices from 0)");
    }
    if (slots[line.index] != nullptr) {
      throw InputError(table.path, where,
                       "query " + std::to_string(line.index) + " of " + it->second->path.string() + " is answered twice (line " +
                           std::to_string(slots[line.index]->line) + " too)");
    }
    slots[line.index] = &line;
  }
  for (const datasets::QueryFile& file : files) {
    const std::vector<const AnswerLine*>& slots = table.by_file.at(file.path.string());
    const auto missing = std::find(slots.begin(), slots.end(), nullptr);
    if (missing != slots.end()) {
      const std::size_t count = static_cast<std::size_t>(std::count(slots.begin(), slots.end(), nullptr));
      throw InputError(table.path, {},
                       "no answer for query " + std::to_string(missing - slots.begin()) + " of " + file.path.string() + " (" + std::to_string(count) +
                           " of its " + std::to_string(slots.size()) + " queries have none: cut short, or answers to other files?)");
    }
  }
}

bool names_answers(const std::string& spec) { return spec.rfind(std::string(narrowphase::kAnswersHead) + ":", 0) == 0; }

}  // namespace ccd::harness
