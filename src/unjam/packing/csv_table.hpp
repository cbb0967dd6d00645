#pragma once
// Numeric CSV tables (particles.csv, contacts.csv, probes.csv, bounds.csv).
//
// Reading: the first non-blank line is the header; columns are looked up by name, so their
// order is free and unknown columns are ignored. Fields are separated by commas, surrounding
// spaces and a trailing '\r' are dropped, blank lines are skipped; there is no quoting (the
// tables hold numbers only). A leading UTF-8 byte order mark is skipped, and CR-only line
// ends are read as line ends. Every error names the file, the line and the column.
//
// Writing: doubles in the shortest form that reloads bit for bit (std::to_chars, at most 17
// significant digits; -0.0 is written "-0"), integers exactly.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace unjam {

class CsvTable {
 public:
  // Parses `text`; `name` (usually the file's path) prefixes every error message.
  // Throws unjam::Error on an empty file, an empty or duplicated column name, or a row whose
  // field count differs from the header's ("<name> line 12: expected 7 fields, found 4").
  static CsvTable parse(std::string text, std::string name);

  // Reads and parses a file; throws unjam::Error if it cannot be read.
  static CsvTable read(const std::filesystem::path& path);

  const std::string& name() const { return name_; }
  const std::vector<std::string>& header() const { return header_; }
  std::size_t rows() const { return line_of_row_.size(); }

  // The index of a column, or nullopt if the header lacks it.
  std::optional<std::size_t> find_column(std::string_view column) const;
  // The index of a column; throws "<name>: missing column '<column>'".
  std::size_t column(std::string_view column) const;

  // Line number (1-based, in the file) of a data row (0-based).
  std::size_t line(std::size_t row) const { return line_of_row_[row]; }

  std::string_view field(std::size_t row, std::size_t col) const;
  // A finite double; throws "<name> line L, column 'c': '<text>' is not a finite number".
  double number(std::size_t row, std::size_t col) const;
  // An integer (also accepts an integral decimal such as "3.0"); throws like number().
  std::int64_t integer(std::size_t row, std::size_t col) const;

  // "<name> line L: " + message, for checks made by the caller on a row.
  [[noreturn]] void fail(std::size_t row, const std::string& message) const;

 private:
  struct Span {
    std::size_t begin, end;  // byte offsets into text_
  };
  [[noreturn]] void fail_field(std::size_t row, std::size_t col, const std::string& why) const;

  std::string name_;
  std::string text_;
  std::vector<std::string> header_;
  std::vector<Span> fields_;                 // row-major, header_.size() per row
  std::vector<std::size_t> line_of_row_;
};

// Appends `value` in the shortest form that reloads bit for bit (std::to_chars).
void append_number(std::string& out, double value);
void append_number(std::string& out, std::int64_t value);

// Builds a CSV text row by row: cell(...) for each column, then end_row().
class CsvWriter {
 public:
  explicit CsvWriter(const std::vector<std::string>& columns);

  CsvWriter& cell(double value);
  CsvWriter& cell(std::int64_t value);
  CsvWriter& cell(int value) { return cell(static_cast<std::int64_t>(value)); }
  CsvWriter& cell(std::string_view value);
  // Ends the row; throws std::logic_error if it does not have one cell per column.
  void end_row();

  const std::string& str() const { return text_; }

 private:
  void separator();

  std::string text_;
  std::size_t columns_;
  std::size_t in_row_ = 0;
};

}  // namespace unjam
