#include "breccia/common/csv.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "breccia/common/error.hpp"

namespace breccia {
namespace {

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\n')) s.pop_back();
  size_t a = 0;
  while (a < s.size() && s[a] == ' ') ++a;
  return s.substr(a);
}

bool blank(const std::string& line) { return trim(line).empty(); }

// The decimal number a whole field holds (leading and trailing spaces allowed); false if none.
// strtod also reads hexadecimal ("0x1"), which no table of ours holds: a typo, refused.
bool parse_number(const std::string& field, double& v) {
  if (field.find_first_of("xX") != std::string::npos) return false;
  char* end = nullptr;
  v = std::strtod(field.c_str(), &end);
  if (end == field.c_str()) return false;
  while (*end == ' ' || *end == '\t') ++end;
  return *end == '\0';
}

}  // namespace

std::vector<std::string> split_csv_line(const std::string& line, size_t max_fields) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (size_t k = 0; k < line.size(); ++k) {
    const char ch = line[k];
    if (ch == '"') {
      if (quoted && k + 1 < line.size() && line[k + 1] == '"') {
        cur += '"';
        ++k;
      } else {
        quoted = !quoted;
      }
    } else if (ch == ',' && !quoted && (max_fields == 0 || out.size() + 1 < max_fields)) {
      out.push_back(trim(cur));
      cur.clear();
    } else {
      cur += ch;
    }
  }
  out.push_back(trim(cur));
  return out;
}

std::string csv_plain_field(std::string text) {
  for (char& c : text)
    if (c == ',' || c == '"' || c == '\n') c = c == ',' ? ';' : ' ';
  return text;
}

CsvColumns read_csv_columns(const std::filesystem::path& path, const CsvReadOptions& o) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string(), "", "cannot be opened", o.expected);
  CsvColumns t;
  std::string line;
  int lineno = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++lineno;
    if (blank(line) || (o.comments && line[0] == '#')) continue;
    const std::vector<std::string> f = split_csv_line(line);
    if (first) {
      first = false;
      double v;
      if (!(o.header_optional && parse_number(f[0], v))) {
        t.names = f;
        t.columns.resize(f.size());
        continue;
      }
      t.columns.resize(f.size());  // no header: the first row sets the column count
    }
    const size_t width = t.columns.size();
    if (f.size() < width)
      throw InputError(path.string(), "line " + std::to_string(lineno), std::to_string(f.size()) + " values",
                       std::to_string(width) + " (one per header column)");
    for (size_t c = 0; c < width; ++c) {
      double v;
      if (!parse_number(f[c], v) || (o.finite && !std::isfinite(v)))
        throw InputError(path.string(),
                         "line " + std::to_string(lineno) + ", column " + (t.names.empty() ? std::to_string(c + 1) : t.names[c]),
                         "'" + f[c] + "'", o.finite ? "a finite number" : "a number");
      t.columns[c].push_back(v);
    }
    t.line.push_back(lineno);
  }
  if (first) throw InputError(path.string(), "header", "empty file", o.expected.empty() ? "a CSV header line" : o.expected);
  return t;
}

}  // namespace breccia
