#pragma once
/// @file xml.hpp
/// A small, bounds-checked XML reader for data files such as the HaTT
/// modelSet schema: elements, text, attributes (read and kept), comments,
/// processing instructions, DOCTYPE and CDATA, the five predefined entities
/// and numeric character references. Setup code only: it allocates and
/// throws std::invalid_argument with the byte offset of the problem.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hapticfield::texture::detail {
/// Concatenates strings by appending (avoids a g++ 12 -Wrestrict false
/// positive on `"literal" + std::string(...)`).
template <class... Parts>
[[nodiscard]] std::string cat(const Parts&... parts) {
  std::string s;
  (s.append(std::string_view(parts)), ...);
  return s;
}
}  // namespace hapticfield::texture::detail

namespace hapticfield::texture::xml {

struct Node {
  std::string name;                                          ///< element name
  std::vector<std::pair<std::string, std::string>> attributes;  ///< in document order
  std::string text;                                          ///< concatenated character data
  std::vector<Node> children;                                ///< child elements in order

  /// First child element with this name, or nullptr.
  [[nodiscard]] const Node* child(std::string_view n) const noexcept {
    for (const auto& c : children)
      if (c.name == n) return &c;
    return nullptr;
  }
  /// All child elements with this name.
  [[nodiscard]] std::vector<const Node*> children_named(std::string_view n) const {
    std::vector<const Node*> out;
    for (const auto& c : children)
      if (c.name == n) out.push_back(&c);
    return out;
  }
};

namespace detail {

inline constexpr std::size_t max_depth = 64;

class Parser {
 public:
  Parser(std::string_view text, std::string_view source) : s_(text), source_(source) {}

  Node parse_document() {
    skip_misc();
    if (at_end() || peek() != '<') fail("expected the root element");
    Node root = parse_element(0);
    skip_misc();
    if (!at_end()) fail("content after the root element");
    return root;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument(texture::detail::cat("XML", source_.empty() ? "" : " '", source_, source_.empty() ? "" : "'",
                                                     ": ", what, " (at byte ", std::to_string(i_), ")"));
  }
  [[nodiscard]] bool at_end() const noexcept { return i_ >= s_.size(); }
  [[nodiscard]] char peek() const noexcept { return s_[i_]; }
  [[nodiscard]] bool starts_with(std::string_view t) const noexcept { return s_.substr(i_).starts_with(t); }
  static bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
  static bool is_name_char(char c) noexcept {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '.' || c == ':' || static_cast<unsigned char>(c) >= 0x80;
  }
  void skip_space() noexcept {
    while (!at_end() && is_space(peek())) ++i_;
  }
  void skip_until(std::string_view end, const char* what) {
    const std::size_t p = s_.find(end, i_);
    if (p == std::string_view::npos) fail(texture::detail::cat("unterminated ", what));
    i_ = p + end.size();
  }
  /// Prolog / epilog: whitespace, comments, processing instructions, DOCTYPE.
  void skip_misc() {
    for (;;) {
      skip_space();
      if (starts_with("<?")) skip_until("?>", "processing instruction");
      else if (starts_with("<!--")) skip_until("-->", "comment");
      else if (starts_with("<!DOCTYPE")) skip_until(">", "DOCTYPE");
      else return;
    }
  }
  std::string parse_name() {
    const std::size_t start = i_;
    while (!at_end() && is_name_char(peek())) ++i_;
    if (i_ == start) fail("expected a name");
    return std::string(s_.substr(start, i_ - start));
  }
  void append_decoded(std::string& out, std::string_view raw) {
    for (std::size_t k = 0; k < raw.size(); ++k) {
      if (raw[k] != '&') {
        out.push_back(raw[k]);
        continue;
      }
      const std::size_t semi = raw.find(';', k);
      if (semi == std::string_view::npos) fail("unterminated entity reference");
      const std::string_view ent = raw.substr(k + 1, semi - k - 1);
      if (ent == "amp") out.push_back('&');
      else if (ent == "lt") out.push_back('<');
      else if (ent == "gt") out.push_back('>');
      else if (ent == "quot") out.push_back('"');
      else if (ent == "apos") out.push_back('\'');
      else if (ent.size() > 1 && ent[0] == '#') {
        unsigned long code = 0;
        const bool hex = ent[1] == 'x';
        for (std::size_t m = hex ? 2 : 1; m < ent.size(); ++m) {
          const char c = ent[m];
          int d = -1;
          if (c >= '0' && c <= '9') d = c - '0';
          else if (hex && c >= 'a' && c <= 'f') d = c - 'a' + 10;
          else if (hex && c >= 'A' && c <= 'F') d = c - 'A' + 10;
          if (d < 0 || code > 0x10FFFF) fail("bad character reference");
          code = code * (hex ? 16 : 10) + static_cast<unsigned long>(d);
        }
        if (code < 0x80) out.push_back(static_cast<char>(code));
        else out.push_back('?');  // non-ASCII characters are not needed in numeric data
      } else {
        fail(texture::detail::cat("unknown entity '&", ent, ";'"));
      }
      k = semi;
    }
  }
  Node parse_element(std::size_t depth) {
    if (depth >= max_depth) fail("elements nested too deeply");
    ++i_;  // '<'
    Node node;
    node.name = parse_name();
    for (;;) {  // attributes
      skip_space();
      if (at_end()) fail(texture::detail::cat("unterminated start tag <", node.name, ">"));
      if (peek() == '/') {
        ++i_;
        if (at_end() || peek() != '>') fail("expected '>' after '/'");
        ++i_;
        return node;
      }
      if (peek() == '>') {
        ++i_;
        break;
      }
      std::string key = parse_name();
      skip_space();
      if (at_end() || peek() != '=') fail(texture::detail::cat("expected '=' after attribute ", key));
      ++i_;
      skip_space();
      if (at_end() || (peek() != '"' && peek() != '\'')) fail("expected a quoted attribute value");
      const char quote = peek();
      const std::size_t end = s_.find(quote, i_ + 1);
      if (end == std::string_view::npos) fail("unterminated attribute value");
      std::string value;
      append_decoded(value, s_.substr(i_ + 1, end - i_ - 1));
      node.attributes.emplace_back(std::move(key), std::move(value));
      i_ = end + 1;
    }
    for (;;) {  // content
      if (at_end()) fail(texture::detail::cat("missing end tag </", node.name, ">"));
      if (starts_with("</")) {
        i_ += 2;
        const std::string closing = parse_name();
        if (closing != node.name) fail(texture::detail::cat("end tag </", closing, "> does not match <", node.name, ">"));
        skip_space();
        if (at_end() || peek() != '>') fail("expected '>' in end tag");
        ++i_;
        return node;
      }
      if (starts_with("<!--")) {
        skip_until("-->", "comment");
      } else if (starts_with("<![CDATA[")) {
        const std::size_t start = i_ + 9;
        skip_until("]]>", "CDATA section");
        node.text.append(s_.substr(start, i_ - 3 - start));
      } else if (starts_with("<?")) {
        skip_until("?>", "processing instruction");
      } else if (peek() == '<') {
        node.children.push_back(parse_element(depth + 1));
      } else {
        const std::size_t start = i_;
        while (!at_end() && peek() != '<') ++i_;
        append_decoded(node.text, s_.substr(start, i_ - start));
      }
    }
  }

  std::string_view s_;
  std::string_view source_;
  std::size_t i_{0};
};

}  // namespace detail

/// Parses a whole document and returns its root element.
/// @throws std::invalid_argument for malformed XML (message has the offset).
[[nodiscard]] inline Node parse(std::string_view text, std::string_view source_name = {}) {
  return detail::Parser(text, source_name).parse_document();
}

}  // namespace hapticfield::texture::xml
