#pragma once
/// @file cli.hpp
/// The command-line parser every example tool shares.
///
/// A tool's main() is one call:
///
///   int main(int argc, char** argv) {
///     return cli::main("my_tool", usage, argc, argv, [](cli::Parser& p) {
///       Args a;
///       cli::Input image("IMAGE");  // the one positional argument, if any
///       while (p.next()) {
///         if (p.is("--trials")) a.trials = static_cast<int>(p.integer(1, 100000));
///         else p.input_or_unknown(image);  // or p.unknown() with no input
///       }
///       a.image = image.required();  // "no IMAGE given"
///       p.finish();       // checks the output paths before any work
///       return run(a);
///     });
///   }
///
/// Options several tools share live beside it: mask_options.hpp (--mask,
/// --size, --border), servo_options.hpp (--realtime, --clock),
/// device_option.hpp (--device, --list-devices) and view/view_options.hpp
/// (--view, --distance).
///
/// Exit status: 0 success (and --help / -h, usage on stdout), 2 a usage error
/// (unknown or missing flag, a value that is not a whole number in range),
/// 1 bad input (files, pictures, devices, anything that fails later). Every
/// error is one line on stderr: "TOOL: message".

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <unistd.h>

#include "hapticfield/core/error.hpp"

namespace hapticfield::cli {

/// The command line itself is wrong: exit status 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Exit statuses of every tool.
inline constexpr int exit_ok = 0;
inline constexpr int exit_bad_input = 1;
inline constexpr int exit_usage = 2;

/// A closed or open interval for a real-valued flag.
struct Interval {
  double lo{0.0};
  double hi{0.0};
  bool lo_open{false};
  bool hi_open{false};

  [[nodiscard]] bool contains(double v) const noexcept {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  [[nodiscard]] std::string text() const;
};

/// [lo, hi]
[[nodiscard]] inline Interval closed(double lo, double hi) {
  return {lo, hi, false, false};
}
/// (lo, hi)
[[nodiscard]] inline Interval open(double lo, double hi) {
  return {lo, hi, true, true};
}
/// (lo, hi]
[[nodiscard]] inline Interval open_closed(double lo, double hi) {
  return {lo, hi, true, false};
}

namespace detail {

/// %g with up to 6 significant digits: 1e+06 is written 1e6.
inline std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  std::string s = buf;
  const auto e = s.find("e+");
  if (e != std::string::npos) {
    std::size_t digits = e + 2;
    while (digits + 1 < s.size() && s[digits] == '0')
      ++digits;
    s = s.substr(0, e + 1) + s.substr(digits);
  }
  return s;
}

/// The text shown for a user's token: quoted, control characters as '?',
/// at most 40 characters.
inline std::string quoted(std::string_view text) {
  std::string s = "'";
  for (std::size_t i = 0; i < text.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    s.push_back(c < 0x20 || c == 0x7f ? '?' : static_cast<char>(c));
  }
  if (text.size() > 40) s += "...";
  return s + "'";
}

/// Makes a message fit on one line.
inline std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' '))
    text.pop_back();
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text.empty() ? std::string("unknown error") : text;
}

}  // namespace detail

inline std::string Interval::text() const {
  std::string s(1, lo_open ? '(' : '[');
  s.append(detail::number_text(lo)).append(", ").append(detail::number_text(hi));
  s.push_back(hi_open ? ')' : ']');
  return s;
}

/// Parses a whole token as a finite real number.
/// @throws UsageError naming `what` for empty text, leading spaces, trailing
///         characters, NaN, Inf or a value that overflows.
[[nodiscard]] inline double parse_real(const std::string& text, const std::string& what) {
  if (text.empty()) throw UsageError(what + " expects a number, got an empty value");
  if (text.front() == ' ' || text.front() == '\t' || text.front() == '\n')
    throw UsageError(what + " expects a number, got " + detail::quoted(text));
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) throw UsageError(what + " expects a number, got " + detail::quoted(text));
  if (!std::isfinite(v) || (errno == ERANGE && std::abs(v) > 1.0))
    throw UsageError(what + " must be a finite number, got " + detail::quoted(text));
  return v;
}

/// Parses a whole token as a base-10 integer in [lo, hi].
/// @throws UsageError naming `what`.
[[nodiscard]] inline long long parse_integer(const std::string& text, const std::string& what, long long lo,
                                             long long hi) {
  const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
  const std::size_t sign = !text.empty() && (text[0] == '-' || text[0] == '+') ? 1 : 0;
  const bool digits_only = text.size() > sign && text.find_first_not_of("0123456789", sign) == std::string::npos;
  if (!digits_only) throw UsageError(what + " expects an integer in " + range + ", got " + detail::quoted(text));
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno == ERANGE || v < lo || v > hi)
    throw UsageError(what + " must be in " + range + ", got " + detail::quoted(text));
  return v;
}

/// Parses "x,y" (no spaces around the comma needed, none allowed inside a
/// number); each part a finite number in `range`.
[[nodiscard]] inline std::pair<double, double> parse_pair(const std::string& text, const std::string& what,
                                                          Interval range) {
  const auto comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos)
    throw UsageError(what + " expects x,y, got " + detail::quoted(text));
  const auto trim = [](std::string s) {
    const auto a = s.find_first_not_of(" \t");
    const auto b = s.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
  };
  const double x = parse_real(trim(text.substr(0, comma)), what);
  const double y = parse_real(trim(text.substr(comma + 1)), what);
  if (!range.contains(x) || !range.contains(y))
    throw UsageError(what + " values must be in " + range.text() + ", got " + detail::quoted(text));
  return {x, y};
}

/// Checks that a file can be created or replaced at `path`: its parent
/// folder exists and is writable, and `path` is not a folder.
/// @throws FileError naming `what` and the path.
inline void check_output_file(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  const std::string head = what + ": cannot write " + detail::quoted(path) + ": ";
  if (path.empty()) throw FileError(what + ": empty path");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw FileError(head + "it is a folder");
  fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) parent = ".";
  if (!fs::exists(parent, ec)) throw FileError(head + "folder " + detail::quoted(parent.string()) + " does not exist");
  if (!fs::is_directory(parent, ec)) throw FileError(head + detail::quoted(parent.string()) + " is not a folder");
  if (::access(parent.c_str(), W_OK | X_OK) != 0)
    throw FileError(head + "folder " + detail::quoted(parent.string()) + " is not writable");
  if (fs::exists(path, ec) && ::access(path.c_str(), W_OK) != 0) throw FileError(head + "permission denied");
}

/// Checks that `path` is a writable folder, or can be created: the nearest
/// existing ancestor is a writable folder.
/// @throws FileError naming `what` and the path.
inline void check_output_dir(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  const std::string head = what + ": cannot write into " + detail::quoted(path) + ": ";
  if (path.empty()) throw FileError(what + ": empty path");
  std::error_code ec;
  fs::path p = fs::path(path);
  if (fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec)) throw FileError(head + "it is not a folder");
    if (::access(p.c_str(), W_OK | X_OK) != 0) throw FileError(head + "permission denied");
    return;
  }
  fs::path ancestor = p.parent_path();
  while (!ancestor.empty() && !fs::exists(ancestor, ec))
    ancestor = ancestor.parent_path();
  if (ancestor.empty()) ancestor = ".";
  if (!fs::is_directory(ancestor, ec)) throw FileError(head + detail::quoted(ancestor.string()) + " is not a folder");
  if (::access(ancestor.c_str(), W_OK | X_OK) != 0)
    throw FileError(head + "folder " + detail::quoted(ancestor.string()) + " is not writable");
}

/// A tool's one positional argument, its input (a file), named in messages
/// as the usage names it ("IMAGE"). Parser::input_or_unknown() fills it.
class Input {
 public:
  explicit Input(std::string name) : name_(std::move(name)) {}

  /// The name in messages ("IMAGE").
  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  /// An input was given (it may be "").
  [[nodiscard]] bool given() const noexcept { return given_; }
  /// The input given; empty when none was.
  [[nodiscard]] const std::string& value() const noexcept { return value_; }

  /// The input, which the tool cannot do without.
  /// @throws UsageError "no IMAGE given".
  [[nodiscard]] const std::string& required() const {
    if (!given_) throw UsageError("no " + name_ + " given");
    return value_;
  }

  /// Takes `token` as the input.
  /// @throws UsageError "more than one IMAGE given ('a.png', 'b.png')".
  void take(const std::string& token) {
    if (given_)
      throw UsageError("more than one " + name_ + " given (" + detail::quoted(value_) + ", " + detail::quoted(token) +
                       ")");
    value_ = token;
    given_ = true;
  }

 private:
  std::string name_;
  std::string value_;
  bool given_{false};
};

/// Walks the arguments one token at a time.
class Parser {
 public:
  Parser(int argc, char** argv) : args_(argv + 1, argv + argc) {}

  /// Moves to the next token; false when there are none left.
  bool next() {
    if (at_ + 1 >= static_cast<long>(args_.size())) {
      at_ = static_cast<long>(args_.size());
      return false;
    }
    ++at_;
    return true;
  }

  /// The current token.
  [[nodiscard]] const std::string& token() const { return args_.at(static_cast<std::size_t>(at_)); }
  /// The current token is this flag.
  [[nodiscard]] bool is(std::string_view flag) const { return token() == flag; }
  /// The current token is not a flag ("-" alone counts as a value).
  [[nodiscard]] bool positional() const { return token().size() < 2 || token()[0] != '-'; }

  /// The current flag's value.
  /// @throws UsageError "--flag needs a value".
  const std::string& value() {
    flag_ = token();
    if (at_ + 1 >= static_cast<long>(args_.size())) throw UsageError(flag_ + " needs a value");
    return args_[static_cast<std::size_t>(++at_)];
  }

  /// The value as an integer in [lo, hi].
  long long integer(long long lo, long long hi) {
    const std::string& v = value();
    return parse_integer(v, flag_, lo, hi);
  }

  /// The value as a finite real number in `range`.
  double real(Interval range) {
    const std::string& v = value();
    const double x = parse_real(v, flag_);
    if (!range.contains(x)) throw UsageError(flag_ + " must be in " + range.text() + ", got " + detail::quoted(v));
    return x;
  }

  /// The value as "x,y", each in `range`.
  std::pair<double, double> pair(Interval range) {
    const std::string& v = value();
    return parse_pair(v, flag_, range);
  }

  /// The value in millions of pixels, in (0, 1e6], as a count of pixels: a
  /// tool's --max-mpx, the largest picture or frame it decodes.
  std::uint64_t megapixels() { return static_cast<std::uint64_t>(real(open_closed(0.0, 1e6)) * 1e6); }

  /// The value as a whole number of `unit` in `range`, written as a real
  /// number ("44100", "4.41e4"): a WAV header or a sound card holds a whole
  /// rate, so 8000.5 Hz is refused rather than silently rounded.
  double whole(Interval range, std::string_view unit) {
    const double x = real(range);
    if (x != std::floor(x))
      throw UsageError(flag_ + " must be a whole number of " + std::string(unit) + ", got " + detail::quoted(token()));
    return x;
  }

  /// The value as one of the named choices; `noun` names them in the
  /// message ("--mask: unknown mask 'x' (one of prewitt, sobel)").
  template <class T>
  T choice(std::string_view noun, std::initializer_list<std::pair<std::string_view, T>> choices) {
    const std::string& v = value();
    std::string names;
    for (const auto& [name, result] : choices) {
      if (v == name) return result;
      names += (names.empty() ? "" : ", ") + std::string(name);
    }
    throw UsageError(flag_ + ": unknown " + std::string(noun) + " " + detail::quoted(v) + " (one of " + names + ")");
  }

  /// The value as one of `values`, each spelled as to_string(value) spells
  /// it (the library's masks and borders: mask_kinds, border_kinds).
  template <class T, std::size_t N>
  T named(std::string_view noun, const std::array<T, N>& values) {
    const std::string& v = value();
    std::string names;
    for (const T& t : values) {
      if (v == to_string(t)) return t;
      names += (names.empty() ? "" : ", ") + std::string(to_string(t));
    }
    throw UsageError(flag_ + ": unknown " + std::string(noun) + " " + detail::quoted(v) + " (one of " + names + ")");
  }

  /// The value as a path to a file that the tool writes; checked by finish().
  std::string output_file() {
    const std::string path = value();
    outputs_.push_back({flag_, path, false});
    return path;
  }

  /// The value as a folder that the tool writes into (created if needed);
  /// checked by finish().
  std::string output_dir() {
    const std::string path = value();
    outputs_.push_back({flag_, path, true});
    return path;
  }

  /// Registers a default output folder that finish() checks too.
  void default_output_dir(const std::string& flag, const std::string& path) { outputs_.push_back({flag, path, true}); }

  /// @throws UsageError for the current token: an unknown option, or an
  ///         unexpected value.
  [[noreturn]] void unknown() const {
    if (positional()) throw UsageError("unexpected argument " + detail::quoted(token()));
    throw UsageError("unknown option " + detail::quoted(token()));
  }

  /// The current token is none of the tool's flags: a value is the tool's
  /// input, a flag an unknown option.
  /// @throws UsageError "unknown option '--x'" or "more than one IMAGE given
  ///         ('a.png', 'b.png')".
  void input_or_unknown(Input& input) const {
    if (!positional()) unknown();
    input.take(token());
  }

  /// Checks every output path given (before any work is done).
  /// @throws FileError naming the flag.
  void finish() const {
    for (const Output& o : outputs_) {
      if (o.dir)
        check_output_dir(o.path, o.flag);
      else
        check_output_file(o.path, o.flag);
    }
  }

 private:
  struct Output {
    std::string flag;
    std::string path;
    bool dir{false};
  };
  std::vector<std::string> args_;
  long at_{-1};
  std::string flag_;
  std::vector<Output> outputs_;
};

/// Runs f() with stderr sent to /dev/null: decoders (libpng, libjpeg) print
/// their own complaints there before OpenCV reports the failure, which the
/// tool then reports once. Returns f()'s result; rethrows its exception.
template <class F>
decltype(auto) quiet_stderr(F&& f) {
  std::fflush(stderr);
  const int saved = ::dup(STDERR_FILENO);
  std::FILE* null = std::fopen("/dev/null", "w");
  if (saved >= 0 && null) ::dup2(::fileno(null), STDERR_FILENO);
  struct Restore {
    int saved;
    std::FILE* null;
    ~Restore() {
      std::fflush(stderr);
      if (saved >= 0) {
        ::dup2(saved, STDERR_FILENO);
        ::close(saved);
      }
      if (null) std::fclose(null);
    }
  } restore{saved, null};
  return f();
}

/// The library's size limits end their message with "(raise max_pixels to
/// allow it)"; a tool's user sets the limit with a flag, so the message names
/// that flag instead: "(raise --max-mpx to allow it)". Other messages pass
/// unchanged.
[[nodiscard]] inline std::string name_limit_flag(std::string message, std::string_view flag) {
  const std::string library_hint = "(raise max_pixels to allow it)";
  const auto at = message.find(library_hint);
  if (at != std::string::npos)
    message.replace(at, library_hint.size(), "(raise " + std::string(flag) + " to allow it)");
  return message;
}

/// True when stdout is a terminal: live status lines redraw themselves with
/// '\r' only there; a file or a pipe gets whole lines.
[[nodiscard]] inline bool stdout_is_terminal() {
  return ::isatty(STDOUT_FILENO) == 1;
}

/// Prints "tool: message" as one line on stderr.
inline void report(const char* tool, const std::string& message) {
  std::fflush(stdout);
  std::fprintf(stderr, "%s: %s\n", tool, detail::one_line(message).c_str());
}

/// Runs a tool: --help / -h anywhere print `usage` on stdout (exit 0);
/// otherwise body(parser) runs and its errors become one stderr line and
/// exit 2 (UsageError) or 1 (anything else).
template <class Body>
int main(const char* tool, const char* usage, int argc, char** argv, Body&& body) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(usage, stdout);
      return exit_ok;
    }
  }
  try {
    Parser parser(argc, argv);
    return body(parser);
  } catch (const UsageError& e) {
    report(tool, std::string(e.what()) + " (--help shows the usage)");
    return exit_usage;
  } catch (const std::exception& e) {
    report(tool, e.what());
    return exit_bad_input;
  } catch (...) {
    report(tool, "unknown error");
    return exit_bad_input;
  }
}

}  // namespace hapticfield::cli
