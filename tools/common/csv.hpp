#pragma once
/// @file csv.hpp
/// The one reader for the numeric CSV files the example tools take
/// (tangible_image --probes x,y; picture_normals --probes x,y,vx,vy).
///
/// Each row is N comma-separated numbers; spaces and tabs around a number are
/// ignored, blank lines and lines starting with '#' are skipped, and the first
/// other line may be a header (not numeric). Lines may end in CR LF. Lines
/// are bounded in length and the file in rows, so any input ends quickly in
/// rows or in a FileError naming the file and the line.

#include <array>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "hapticfield/core/error.hpp"

namespace hapticfield::cli {

struct CsvConfig {
  std::string columns{"x,y"};        ///< the column names, for messages ("x,y,vx,vy")
  std::string what{"probes"};        ///< what the file holds, for messages
  std::size_t max_line_bytes{4096};  ///< longest line [bytes]
  std::size_t max_rows{1'000'000};   ///< most rows
  bool finite_only{false};           ///< reject NaN / Inf values
  bool allow_empty{false};           ///< a file with no rows is fine
};

namespace detail {

/// Parses one trimmed cell as a number; false when it is not one.
inline bool csv_number(std::string_view cell, double& out) {
  while (!cell.empty() && (cell.front() == ' ' || cell.front() == '\t'))
    cell.remove_prefix(1);
  while (!cell.empty() && (cell.back() == ' ' || cell.back() == '\t'))
    cell.remove_suffix(1);
  if (cell.empty() || cell.size() > 512) return false;
  char buf[514];
  cell.copy(buf, cell.size());
  buf[cell.size()] = '\0';
  char* end = nullptr;
  out = std::strtod(buf, &end);
  return end == buf + cell.size();
}

/// A line shown in a message: at most 40 characters, control characters as '?'.
inline std::string csv_excerpt(std::string_view line) {
  std::string s;
  for (std::size_t i = 0; i < line.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(line[i]);
    s.push_back(c < 0x20 || c == 0x7f ? '?' : static_cast<char>(c));
  }
  if (line.size() > 40) s += "...";
  return s;
}

}  // namespace detail

/// Parses the text of a CSV file named `name` into rows of N numbers.
/// @throws FileError "NAME:LINE: expected 'x,y', got '...'", "NAME:LINE: line
///         longer than 4096 bytes", "NAME: more than 1000000 rows",
///         "NAME: no x,y rows".
template <std::size_t N>
requires(N >= 1)
    [[nodiscard]] std::vector<std::array<double, N>> parse_csv(std::string_view text, const std::string& name,
                                                               const CsvConfig& config = {}) {
  std::vector<std::array<double, N>> rows;
  std::size_t number = 0;
  bool header_seen = false;
  while (!text.empty()) {
    ++number;
    const std::size_t newline = text.find('\n');
    std::string_view line = text.substr(0, newline);
    text.remove_prefix(newline == std::string_view::npos ? text.size() : newline + 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.size() > config.max_line_bytes)
      throw FileError(name + ":" + std::to_string(number) + ": line longer than " +
                      std::to_string(config.max_line_bytes) + " bytes");
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || line[first] == '#') continue;

    std::array<double, N> row{};
    std::size_t cells = 0;
    bool numeric = true;
    std::string_view rest = line;
    while (true) {
      const std::size_t comma = rest.find(',');
      const std::string_view cell = rest.substr(0, comma);
      if (cells < N) numeric = detail::csv_number(cell, row[cells]) && numeric;
      ++cells;
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (!numeric && rows.empty() && !header_seen) {  // the header line
      header_seen = true;
      continue;
    }
    header_seen = true;
    if (!numeric || cells != N)
      throw FileError(name + ":" + std::to_string(number) + ": expected '" + config.columns + "', got '" +
                      detail::csv_excerpt(line) + "'");
    if (config.finite_only)
      for (double v : row)
        if (!std::isfinite(v))
          throw FileError(name + ":" + std::to_string(number) + ": values must be finite, got '" +
                          detail::csv_excerpt(line) + "'");
    if (rows.size() >= config.max_rows)
      throw FileError(name + ": more than " + std::to_string(config.max_rows) + " rows");
    rows.push_back(row);
  }
  if (rows.empty() && !config.allow_empty) throw FileError(name + ": no " + config.columns + " rows");
  return rows;
}

/// Reads a CSV file (see parse_csv) through read_file(), at most
/// max_rows * max_line_bytes bytes.
/// @throws FileError "cannot open probes file 'p': no such file", ... and as parse_csv().
template <std::size_t N>
requires(N >= 1)
    [[nodiscard]] std::vector<std::array<double, N>> read_csv(const std::string& path, const CsvConfig& config = {}) {
  std::string text;
  try {
    text = read_file(path, static_cast<std::uintmax_t>(config.max_rows + 1) * (config.max_line_bytes + 2));
  } catch (const FileError& e) {
    // "cannot open 'p': reason" becomes "cannot open probes file 'p': reason"
    std::string message = e.what();
    const std::string plain = "cannot open '" + path + "'";
    if (message.rfind(plain, 0) == 0)
      message = "cannot open " + config.what + " file '" + path + "'" + message.substr(plain.size());
    throw FileError(message);
  }
  return parse_csv<N>(text, path, config);
}

}  // namespace hapticfield::cli
