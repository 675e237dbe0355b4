#pragma once
/// @file
/// The one table writer of the command line and the reports: fixed-width text for a terminal, Markdown for a page.

#include <iosfwd>
#include <string>
#include <vector>

namespace ccd::harness {

class Table {
 public:
  enum class Align { left, right };
  struct Column {
    std::string header;
    Align align = Align::left;
  };

  explicit Table(std::vector<Column> columns);
  /// Appends a row. @throws std::logic_error when it has not one cell per column.
  void add_row(std::vector<std::string> cells);
  /// Adds a column at the right (every row so far gets `fill`).
  void add_column(Column column, const std::string& fill = "");
  std::size_t rows() const { return rows_.size(); }
  const std::vector<std::string>& row(std::size_t i) const { return rows_.at(i); }
  /// Replaces row `i`. @throws std::logic_error when it has not one cell per column.
  void set_row(std::size_t i, std::vector<std::string> cells);

  /// Text: every column as wide as its widest cell, two spaces apart; a left-aligned last column is not padded.
  void print(std::ostream& out) const;
  /// Markdown: `| a | b |` with `---:` under right-aligned columns.
  void print_markdown(std::ostream& out) const;

 private:
  std::vector<Column> columns_;
  std::vector<std::vector<std::string>> rows_;
};

/// `value` with `digits` digits after the point ("12.346").
std::string fixed(double value, int digits);
/// `value` with `significant` significant digits, as an ostream prints it ("0.000123", "1.2e-07").
std::string significant(double value, int significant);

}  // namespace ccd::harness
