#pragma once
// The CSV files of every stage, read and written the same way: history.csv (post-processing),
// load and ground-motion tables (time_s, value), the atlas (breccia-plan), the atlas's rows.
#include <filesystem>
#include <string>
#include <vector>

namespace breccia {

// Fields of one line, comma-separated; a field may be double-quoted ("" inside a quoted
// field stands for one quote). With max_fields > 0 the last field takes the rest of the
// line, commas included (free text written unquoted, as the atlas's error_measure). Each
// field is trimmed of spaces and of a carriage return or newline at its end.
std::vector<std::string> split_csv_line(const std::string& line, size_t max_fields = 0);

// Text for one field of a CSV written without quoting: commas become ';', quotes and
// newlines spaces, so the field cannot split its row.
std::string csv_plain_field(std::string text);

// A CSV of numbers under a header of column names.
struct CsvColumns {
  std::vector<std::string> names;            // empty when the header was optional and absent
  std::vector<std::vector<double>> columns;  // one per header column (or per field of row 1)
  std::vector<int> line;                     // the file's line number of each row
};

struct CsvReadOptions {
  bool header_optional = false;  // a first row of numbers is data (load tables may omit the header)
  bool comments = false;         // lines starting with '#' are skipped
  bool finite = false;           // nan and inf refused (input tables; a run's own history.csv may hold
                                 // them once it became unstable, and is still read)
  std::string expected;          // what the file should be, for error messages
};

// Blank lines are skipped. Every row holds a decimal number in each column (cells beyond the
// header's are ignored; hexadecimal is not a number here); otherwise InputError naming the
// file, the line and the column.
CsvColumns read_csv_columns(const std::filesystem::path& path, const CsvReadOptions& options);

}  // namespace breccia
