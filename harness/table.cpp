#include "harness/table.hpp"

#include <algorithm>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace ccd::harness {

Table::Table(std::vector<Column> columns) : columns_(std::move(columns)) {}

void Table::add_row(std::vector<std::string> cells) {
  if (cells.size() != columns_.size()) {
    throw std::logic_error("a table row of " + std::to_string(cells.size()) + " cells for " + std::to_string(columns_.size()) + " columns");
  }
  rows_.push_back(std::move(cells));
}

void Table::set_row(std::size_t i, std::vector<std::string> cells) {
  if (cells.size() != columns_.size()) throw std::logic_error("a table row of the wrong width");
  rows_.at(i) = std::move(cells);
}

void Table::add_column(Column column, const std::string& fill) {
  columns_.push_back(std::move(column));
  for (auto& row : rows_) row.push_back(fill);
}

namespace {

/// Display width: UTF-8 continuation bytes take no column (δ, †).
std::size_t width(const std::string& text) {
  return static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

}  // namespace

void Table::print(std::ostream& out) const {
  std::vector<std::size_t> widths(columns_.size());
  for (std::size_t c = 0; c < columns_.size(); ++c) {
    widths[c] = width(columns_[c].header);
    for (const auto& row : rows_) widths[c] = std::max(widths[c], width(row[c]));
  }
  auto line = [&](const auto& cell_of) {
    std::string text;
    for (std::size_t c = 0; c < columns_.size(); ++c) {
      const std::string& cell = cell_of(c);
      const std::string padding(widths[c] - width(cell), ' ');
      const bool last = c + 1 == columns_.size();
      text += columns_[c].align == Align::right ? padding + cell : cell + (last ? "" : padding);
      if (!last) text += "  ";
    }
    out << text << '\n';
  };
  line([&](std::size_t c) -> const std::string& { return columns_[c].header; });
  for (const auto& row : rows_) line([&](std::size_t c) -> const std::string& { return row[c]; });
}

void Table::print_markdown(std::ostream& out) const {
  out << '|';
  for (const Column& column : columns_) out << ' ' << column.header << " |";
  out << "\n|";
  for (const Column& column : columns_) out << (column.align == Align::right ? "---:|" : "---|");
  out << '\n';
  for (const auto& row : rows_) {
    out << '|';
    for (const std::string& cell : row) out << ' ' << cell << " |";
    out << '\n';
  }
}

std::string fixed(double value, int digits) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(digits) << value;
  return text.str();
}

std::string significant(double value, int significant) {
  std::ostringstream text;
  text << std::setprecision(significant) << value;
  return text.str();
}

}  // namespace ccd::harness
