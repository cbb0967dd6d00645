#include "unjam/packing/csv_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"

namespace unjam {

namespace {

// "'text'", for error messages.
std::string quoted(std::string_view text) {
  std::string q;
  q.reserve(text.size() + 2);
  q += '\'';
  q += text;
  q += '\'';
  return q;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// Parses the whole of `s` as a double; a leading '+' is accepted.
std::optional<double> parse_double(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) return std::nullopt;
  return v;
}

}  // namespace

CsvTable CsvTable::parse(std::string text, std::string name) {
  CsvTable t;
  t.name_ = std::move(name);
  t.text_ = std::move(text);
  // A UTF-8 byte order mark (spreadsheet exports) is not part of the first column's name, and
  // a file with CR-only line ends (classic Mac) has its lines split at them.
  if (t.text_.rfind("\xEF\xBB\xBF", 0) == 0) t.text_.erase(0, 3);
  if (t.text_.find('\n') == std::string::npos) std::replace(t.text_.begin(), t.text_.end(), '\r', '\n');
  const std::string& s = t.text_;
  std::vector<Span> row;
  std::size_t pos = 0, line = 0;
  bool have_header = false;
  while (pos < s.size()) {
    ++line;
    std::size_t eol = s.find('\n', pos);
    if (eol == std::string::npos) eol = s.size();
    // Split [pos, eol) at commas, trimming spaces around each field.
    row.clear();
    std::size_t begin = pos;
    while (true) {
      std::size_t end = begin;
      while (end < eol && s[end] != ',') ++end;
      std::size_t b = begin, e = end;
      while (b < e && is_space(s[b])) ++b;
      while (e > b && is_space(s[e - 1])) --e;
      row.push_back({b, e});
      if (end == eol) break;
      begin = end + 1;
    }
    pos = eol + 1;
    if (row.size() == 1 && row[0].begin == row[0].end) continue;  // blank line
    if (!have_header) {
      for (const Span& f : row) {
        std::string col = s.substr(f.begin, f.end - f.begin);
        if (col.empty())
          throw Error(t.name_ + " line " + std::to_string(line) + ": empty column name in the header");
        if (t.find_column(col))
          throw Error(t.name_ + " line " + std::to_string(line) + ": column '" + col +
                      "' appears twice in the header");
        t.header_.push_back(std::move(col));
      }
      have_header = true;
      continue;
    }
    if (row.size() != t.header_.size())
      throw Error(t.name_ + " line " + std::to_string(line) + ": expected " +
                  std::to_string(t.header_.size()) + " fields, found " + std::to_string(row.size()) +
                  " (truncated file?)");
    t.fields_.insert(t.fields_.end(), row.begin(), row.end());
    t.line_of_row_.push_back(line);
  }
  if (!have_header) throw Error(t.name_ + ": empty file (expected a header line)");
  return t;
}

CsvTable CsvTable::read(const std::filesystem::path& path) {
  return parse(read_file(path), path.string());
}

std::optional<std::size_t> CsvTable::find_column(std::string_view column) const {
  for (std::size_t c = 0; c < header_.size(); ++c)
    if (header_[c] == column) return c;
  return std::nullopt;
}

std::size_t CsvTable::column(std::string_view column) const {
  if (const auto c = find_column(column)) return *c;
  throw Error(name_ + ": missing column '" + std::string(column) + "'");
}

std::string_view CsvTable::field(std::size_t row, std::size_t col) const {
  const Span& f = fields_[row * header_.size() + col];
  return std::string_view(text_).substr(f.begin, f.end - f.begin);
}

double CsvTable::number(std::size_t row, std::size_t col) const {
  const std::string_view s = field(row, col);
  if (s.empty()) fail_field(row, col, "empty field");
  const auto v = parse_double(s);
  if (!v || !std::isfinite(*v)) fail_field(row, col, quoted(s) + " is not a finite number");
  return *v;
}

std::int64_t CsvTable::integer(std::size_t row, std::size_t col) const {
  std::string_view s = field(row, col);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  std::int64_t i = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), i);
  if (ec == std::errc() && ptr == s.data() + s.size() && !s.empty()) return i;
  // An integral decimal, as written by tools that store every column as floating point.
  const auto v = parse_double(s);
  if (v && std::isfinite(*v) && *v == std::trunc(*v) && std::abs(*v) < 9.0e15)
    return static_cast<std::int64_t>(*v);
  fail_field(row, col, quoted(field(row, col)) + " is not an integer");
}

void CsvTable::fail(std::size_t row, const std::string& message) const {
  throw Error(name_ + " line " + std::to_string(line(row)) + ": " + message);
}

void CsvTable::fail_field(std::size_t row, std::size_t col, const std::string& why) const {
  throw Error(name_ + " line " + std::to_string(line(row)) + ", column '" + header_[col] + "': " + why);
}

CsvWriter::CsvWriter(const std::vector<std::string>& columns) : columns_(columns.size()) {
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (c > 0) text_ += ',';
    text_ += columns[c];
  }
  text_ += '\n';
}

void CsvWriter::separator() {
  if (in_row_++ > 0) text_ += ',';
}

void append_number(std::string& out, double value) {
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, value);  // shortest round trip
  if (ec != std::errc()) throw std::logic_error("append_number: to_chars failed");
  out.append(buf, ptr);
}

void append_number(std::string& out, std::int64_t value) {
  char buf[24];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, value);
  if (ec != std::errc()) throw std::logic_error("append_number: to_chars failed");
  out.append(buf, ptr);
}

CsvWriter& CsvWriter::cell(double value) {
  separator();
  append_number(text_, value);
  return *this;
}

CsvWriter& CsvWriter::cell(std::int64_t value) {
  separator();
  append_number(text_, value);
  return *this;
}

CsvWriter& CsvWriter::cell(std::string_view value) {
  separator();
  text_ += value;
  return *this;
}

void CsvWriter::end_row() {
  if (in_row_ != columns_)
    throw std::logic_error("CsvWriter: row has " + std::to_string(in_row_) + " cells, expected " +
                           std::to_string(columns_));
  text_ += '\n';
  in_row_ = 0;
}

}  // namespace unjam
