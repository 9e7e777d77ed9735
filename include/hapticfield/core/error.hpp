#pragma once
/// @file error.hpp
/// The library's error family and the one place files are opened for reading.
///
///   std::invalid_argument   a bad parameter passed in code (sizes, limits, gains)
///   hapticfield::Error      a run-time failure: pictures, model and calibration
///                           files, devices, the servo loop
///     FileError             a file that is missing, not a regular file,
///                           unreadable, too large or malformed; what() names it
///
/// Every component that opens a file goes through read_file()/check_file(),
/// so the same missing file gives the same FileError wherever it is opened.

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace hapticfield {

/// Base of every run-time failure the library reports.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file cannot be used: missing, not a regular file, unreadable, larger
/// than allowed or malformed. The message names the file.
class FileError : public Error {
 public:
  using Error::Error;
};

/// Largest text file (model, calibration, CSV) read by default [bytes].
inline constexpr std::uintmax_t default_max_file_bytes = std::uintmax_t{64} << 20;

/// Checks that path names a readable regular file of at most max_bytes and
/// returns its size [bytes].
/// @throws FileError "cannot open 'p': no such file" / "not a regular file" /
///         "permission denied" / "larger than N bytes".
inline std::uintmax_t check_file(const std::string& path, std::uintmax_t max_bytes = default_max_file_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (path.empty() || !fs::exists(st)) throw FileError("cannot open '" + path + "': no such file");
  if (!fs::is_regular_file(st)) throw FileError("cannot open '" + path + "': not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw FileError("cannot open '" + path + "': " + ec.message());
  if (size > max_bytes)
    throw FileError("cannot open '" + path + "': " + std::to_string(size) + " bytes, larger than the limit of " +
                    std::to_string(max_bytes) + " bytes");
  if (FILE* f = std::fopen(path.c_str(), "rb")) {
    std::fclose(f);
  } else {
    throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  }
  return size;
}

/// Reads a whole file of at most max_bytes into a string.
/// @throws FileError as check_file(), or when reading fails midway.
[[nodiscard]] inline std::string read_file(const std::string& path, std::uintmax_t max_bytes = default_max_file_bytes) {
  const std::uintmax_t size = check_file(path, max_bytes);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  std::string text(static_cast<std::size_t>(size), '\0');
  const std::size_t got = size ? std::fread(text.data(), 1, text.size(), f) : 0;
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed || got != text.size()) throw FileError("cannot read '" + path + "': read failed");
  return text;
}

}  // namespace hapticfield
