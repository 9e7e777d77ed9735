#pragma once
/// @file sequence_pattern.hpp
/// SequencePattern: the printf pattern of an image sequence
/// ("frames/%04d.png"), parsed and formatted by our own code, never by
/// printf: one conversion %d, %Nd or %0Nd (N at most 9), "%%" for a literal
/// '%', the number in the file name (not in a folder's name).

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>

#include "hapticfield/core/error.hpp"

namespace hapticfield {

/// Widest frame number a sequence pattern may ask for (%09d).
inline constexpr int max_sequence_digits = 9;

/// A sequence pattern that is not one %d conversion (a FileError naming it).
class SequencePatternError : public FileError {
 public:
  using FileError::FileError;
};

class SequencePattern {
 public:
  /// @throws SequencePatternError for no conversion or more than one, a
  ///         conversion other than d, a width above 9, or a number outside
  ///         the file name.
  explicit SequencePattern(const std::string& pattern) : pattern_(pattern) {
    bool found = false;
    for (std::size_t i = 0; i < pattern.size(); ++i) {
      if (pattern[i] != '%') {
        (found ? suffix_ : prefix_).push_back(pattern[i]);
        continue;
      }
      if (i + 1 < pattern.size() && pattern[i + 1] == '%') {  // a literal '%'
        (found ? suffix_ : prefix_).push_back('%');
        ++i;
        continue;
      }
      if (found) fail("more than one frame number (one %d, or %% for a literal %)");
      found = true;
      std::size_t j = i + 1;
      if (j < pattern.size() && pattern[j] == '0') {
        zero_ = true;
        ++j;
      }
      std::size_t digits = 0;
      while (j < pattern.size() && pattern[j] >= '0' && pattern[j] <= '9') {
        if (++digits > 2) fail("the frame number's width must be at most " + std::to_string(max_sequence_digits));
        width_ = width_ * 10 + (pattern[j] - '0');
        ++j;
      }
      if (j >= pattern.size() || pattern[j] != 'd')
        fail("the frame number must be %d, %Nd or %0Nd (N at most " + std::to_string(max_sequence_digits) + ")");
      if (width_ > max_sequence_digits)
        fail("the frame number's width must be at most " + std::to_string(max_sequence_digits) + " (%0" +
             std::to_string(max_sequence_digits) + "d)");
      i = j;
    }
    if (!found) fail("no frame number (%d, %Nd or %0Nd)");
    if (suffix_.find('/') != std::string::npos) fail("the frame number must be in the file name, not in a folder's");
    const std::size_t slash = prefix_.rfind('/');
    folder_ = slash == std::string::npos ? std::string(".") : prefix_.substr(0, slash == 0 ? 1 : slash);
    file_prefix_ = slash == std::string::npos ? prefix_ : prefix_.substr(slash + 1);
  }

  /// The file of frame number `number` (>= 0).
  [[nodiscard]] std::string path(long number) const { return prefix_ + digits(number) + suffix_; }

  /// The frame number of a file name (no folder) this pattern makes, if any.
  [[nodiscard]] std::optional<long> number_of(const std::string& file) const {
    if (file.size() <= file_prefix_.size() + suffix_.size()) return std::nullopt;
    if (file.compare(0, file_prefix_.size(), file_prefix_) != 0) return std::nullopt;
    if (file.compare(file.size() - suffix_.size(), suffix_.size(), suffix_) != 0) return std::nullopt;
    const std::string middle = file.substr(file_prefix_.size(), file.size() - file_prefix_.size() - suffix_.size());
    const std::size_t first = middle.find_first_not_of(' ');
    if (first == std::string::npos || middle.size() - first > 10) return std::nullopt;
    long number = 0;
    for (std::size_t i = first; i < middle.size(); ++i) {
      if (middle[i] < '0' || middle[i] > '9') return std::nullopt;
      number = number * 10 + (middle[i] - '0');
    }
    if (digits(number) != middle) return std::nullopt;  // e.g. "7" for %04d, or "0007" for %d
    return number;
  }

  /// The folder the files are in.
  [[nodiscard]] const std::string& folder() const noexcept { return folder_; }
  [[nodiscard]] const std::string& text() const noexcept { return pattern_; }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw SequencePatternError("cannot open image sequence '" + pattern_ + "': " + why);
  }

  [[nodiscard]] std::string digits(long number) const {
    std::string d = std::to_string(number);
    if (static_cast<int>(d.size()) < width_)
      d.insert(0, static_cast<std::size_t>(width_) - d.size(), zero_ ? '0' : ' ');
    return d;
  }

  std::string pattern_;
  std::string prefix_;       ///< before the number, '%%' unescaped
  std::string suffix_;       ///< after it
  std::string folder_;       ///< the prefix's folder
  std::string file_prefix_;  ///< the prefix's part in the file name
  int width_ = 0;
  bool zero_ = false;
};

}  // namespace hapticfield
