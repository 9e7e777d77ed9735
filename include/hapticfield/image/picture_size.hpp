#pragma once
/// @file picture_size.hpp
/// The width and height of a picture read from its file header alone, so a
/// loader can refuse a picture too large for memory before decoding it (a
/// 2 MB PNG can declare 20000 x 20000 px). OpenCV 4.6 has no header-only
/// query, so the headers are parsed here: PNG (IHDR), JPEG (the SOFn
/// segment), BMP (the DIB header), TIFF (the first IFD, classic TIFF) and
/// the Netpbm family (PBM, PGM, PPM, PAM). Reads at most a few header bytes
/// per segment; never the pixel data.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

#include "hapticfield/core/error.hpp"

namespace hapticfield {

/// A picture's size as its header declares it [px].
struct PictureSize {
  std::uint64_t width = 0;
  std::uint64_t height = 0;
  const char* format = "";  ///< "PNG", "JPEG", "BMP", "TIFF" or "Netpbm"
  [[nodiscard]] std::uint64_t pixels() const noexcept { return width * height; }
};

namespace detail {

/// A small reader over a FILE* that knows how to fail.
class HeaderReader {
 public:
  explicit HeaderReader(const std::string& path) : file_(std::fopen(path.c_str(), "rb")) {}
  ~HeaderReader() {
    if (file_) std::fclose(file_);
  }
  HeaderReader(const HeaderReader&) = delete;
  HeaderReader& operator=(const HeaderReader&) = delete;

  [[nodiscard]] bool ok() const noexcept { return file_ != nullptr; }
  bool read(unsigned char* out, std::size_t n) noexcept { return std::fread(out, 1, n, file_) == n; }
  bool seek(long offset) noexcept { return offset >= 0 && std::fseek(file_, offset, SEEK_SET) == 0; }
  bool skip(long n) noexcept { return n >= 0 && std::fseek(file_, n, SEEK_CUR) == 0; }
  int get() noexcept { return std::fgetc(file_); }

 private:
  std::FILE* file_;
};

[[nodiscard]] inline std::uint32_t be32(const unsigned char* p) noexcept {
  return std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | p[3];
}
[[nodiscard]] inline std::uint32_t be16(const unsigned char* p) noexcept {
  return std::uint32_t(p[0]) << 8 | p[1];
}
[[nodiscard]] inline std::uint32_t le32(const unsigned char* p) noexcept {
  return std::uint32_t(p[3]) << 24 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[1]) << 8 | p[0];
}
[[nodiscard]] inline std::uint32_t le16(const unsigned char* p) noexcept {
  return std::uint32_t(p[1]) << 8 | p[0];
}

/// JPEG: walk the marker segments up to the first start-of-frame.
[[nodiscard]] inline std::optional<PictureSize> jpeg_size(HeaderReader& in) {
  for (int segments = 0; segments < 1024; ++segments) {
    int c = in.get();
    if (c != 0xFF) return std::nullopt;
    while (c == 0xFF)
      c = in.get();  // fill bytes
    if (c < 0) return std::nullopt;
    const int marker = c;
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (marker == 0xD9 || marker == 0xDA) return std::nullopt;           // image end / scan before a frame
    unsigned char len[2];
    if (!in.read(len, 2)) return std::nullopt;
    const long length = static_cast<long>(be16(len));
    if (length < 2) return std::nullopt;
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      unsigned char f[5];  // precision, height, width
      if (length < 7 || !in.read(f, 5)) return std::nullopt;
      return PictureSize{be16(f + 3), be16(f + 1), "JPEG"};
    }
    if (!in.skip(length - 2)) return std::nullopt;
  }
  return std::nullopt;
}

/// Classic TIFF: tags 256 (ImageWidth) and 257 (ImageLength) of the first IFD.
[[nodiscard]] inline std::optional<PictureSize> tiff_size(HeaderReader& in, bool little) {
  const auto u16 = [little](const unsigned char* p) { return little ? le16(p) : be16(p); };
  const auto u32 = [little](const unsigned char* p) { return little ? le32(p) : be32(p); };
  unsigned char b[4];
  if (!in.seek(4) || !in.read(b, 4)) return std::nullopt;
  const std::uint32_t ifd = u32(b);
  if (ifd > 0x7fffffffu || !in.seek(static_cast<long>(ifd)) || !in.read(b, 2)) return std::nullopt;
  const std::uint32_t entries = u16(b);
  std::uint64_t width = 0;
  std::uint64_t height = 0;
  for (std::uint32_t i = 0; i < entries; ++i) {
    unsigned char e[12];
    if (!in.read(e, 12)) return std::nullopt;
    const std::uint32_t tag = u16(e);
    const std::uint32_t type = u16(e + 2);
    if (tag != 256 && tag != 257) continue;
    std::uint64_t value = 0;
    if (type == 3)
      value = u16(e + 8);  // SHORT
    else if (type == 4)
      value = u32(e + 8);  // LONG
    else
      return std::nullopt;
    (tag == 256 ? width : height) = value;
  }
  if (width == 0 || height == 0) return std::nullopt;
  return PictureSize{width, height, "TIFF"};
}

/// Netpbm: "P1".."P6" then width and height as decimal text, with comments;
/// "P7" (PAM) has WIDTH and HEIGHT lines.
[[nodiscard]] inline std::optional<PictureSize> netpbm_size(HeaderReader& in, char kind) {
  // Reads the next decimal number (or word for PAM), skipping blanks and comments.
  const auto token = [&in]() -> std::string {
    std::string t;
    int c = in.get();
    while (true) {
      while (c == ' ' || c == '\t' || c == '\r' || c == '\n')
        c = in.get();
      if (c != '#') break;
      while (c >= 0 && c != '\n')
        c = in.get();
    }
    while (c >= 0 && c != ' ' && c != '\t' && c != '\r' && c != '\n' && t.size() < 32) {
      t.push_back(static_cast<char>(c));
      c = in.get();
    }
    return t;
  };
  const auto number = [](const std::string& t) -> std::optional<std::uint64_t> {
    if (t.empty() || t.size() > 18) return std::nullopt;
    std::uint64_t v = 0;
    for (char ch : t) {
      if (ch < '0' || ch > '9') return std::nullopt;
      v = v * 10 + static_cast<std::uint64_t>(ch - '0');
    }
    return v;
  };
  if (kind != '7') {
    const auto w = number(token());
    const auto h = number(token());
    if (!w || !h) return std::nullopt;
    return PictureSize{*w, *h, "Netpbm"};
  }
  std::optional<std::uint64_t> w;
  std::optional<std::uint64_t> h;
  for (int words = 0; words < 64 && !(w && h); ++words) {
    const std::string t = token();
    if (t.empty() || t == "ENDHDR") break;
    if (t == "WIDTH")
      w = number(token());
    else if (t == "HEIGHT")
      h = number(token());
  }
  if (!w || !h) return std::nullopt;
  return PictureSize{*w, *h, "Netpbm"};
}

}  // namespace detail

/// The size a picture file declares in its header, for PNG, JPEG, BMP,
/// classic TIFF and Netpbm; std::nullopt for any other format (or a header
/// this parser does not understand), which the decoder then judges.
/// @throws FileError when the file cannot be opened.
[[nodiscard]] inline std::optional<PictureSize> read_picture_size(const std::string& path) {
  detail::HeaderReader in(path);
  if (!in.ok()) throw FileError("cannot open '" + path + "'");
  std::array<unsigned char, 26> h{};
  const std::size_t got = [&] {
    std::size_t n = 0;
    for (; n < h.size(); ++n) {
      const int c = in.get();
      if (c < 0) break;
      h[n] = static_cast<unsigned char>(c);
    }
    return n;
  }();
  const unsigned char* p = h.data();
  static constexpr unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (got >= 24 && std::equal(png, png + 8, p)) {
    if (detail::be32(p + 8) != 13 || p[12] != 'I' || p[13] != 'H' || p[14] != 'D' || p[15] != 'R') return std::nullopt;
    return PictureSize{detail::be32(p + 16), detail::be32(p + 20), "PNG"};
  }
  if (got >= 3 && p[0] == 0xFF && p[1] == 0xD8 && p[2] == 0xFF) {
    if (!in.seek(2)) return std::nullopt;
    return detail::jpeg_size(in);
  }
  if (got >= 26 && p[0] == 'B' && p[1] == 'M') {
    const std::uint32_t dib = detail::le32(p + 14);
    if (dib == 12) return PictureSize{detail::le16(p + 18), detail::le16(p + 20), "BMP"};  // OS/2 core header
    const auto w = static_cast<std::int32_t>(detail::le32(p + 18));
    const auto ht = static_cast<std::int32_t>(detail::le32(p + 22));  // negative: top-down rows
    const std::int64_t hh = ht < 0 ? -std::int64_t{ht} : std::int64_t{ht};
    return PictureSize{w < 0 ? 0u : std::uint64_t(w), std::uint64_t(hh), "BMP"};
  }
  if (got >= 8 && ((p[0] == 'I' && p[1] == 'I' && p[2] == 42 && p[3] == 0) ||
                   (p[0] == 'M' && p[1] == 'M' && p[2] == 0 && p[3] == 42)))
    return detail::tiff_size(in, p[0] == 'I');
  if (got >= 3 && p[0] == 'P' && p[1] >= '1' && p[1] <= '7') {
    if (!in.seek(2)) return std::nullopt;
    return detail::netpbm_size(in, static_cast<char>(p[1]));
  }
  return std::nullopt;
}

}  // namespace hapticfield
