#pragma once
/// @file wavelet_synthesis.hpp
/// WaveletWave blocks of MPEG-I Haptics (ISO/IEC 23090-31) back to samples:
/// each effect's `wavelet_stream` is base64 text of a bit stream coded with an
/// adaptive binary arithmetic coder (10-bit registers, seven contexts), which
/// carries a SPIHT bit-plane coding (Said & Pearlman, IEEE TCSVT 6(3), 1996,
/// here on the 1-D dyadic tree: node y's children 2y and 2y+1) of the block's
/// quantised wavelet coefficients, inverted with the CDF 9/7 wavelet (the
/// JPEG 2000 irreversible filters, ISO/IEC 15444-1 Annex F) over
/// log2(length / 4) levels with whole-sample symmetric extension. The bit
/// layout follows the MPEG reference software's decoder. Setup-side code.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace hapticfield::material {

/// Longest WaveletWave block decoded [samples] (the reference Encoder's are 1024).
inline constexpr std::size_t max_wavelet_block = std::size_t{1} << 16;

namespace detail {

/// base64 text to bits, most significant of each 6-bit digit first (the reference's reading: any
/// character outside A-Z a-z 0-9 + is read as '/').
[[nodiscard]] inline std::vector<std::uint8_t> base64_bits(std::string_view text) {
  std::vector<std::uint8_t> bits;
  bits.reserve(text.size() * 6);
  for (const char c : text) {
    int v = 63;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    for (int b = 5; b >= 0; --b)
      bits.push_back(static_cast<std::uint8_t>((v >> b) & 1));
  }
  return bits;
}

/// Adaptive binary arithmetic decoder: 10-bit range, per-context counts of zeros (start 8 of 16).
class BinaryArithmeticDecoder {
 public:
  explicit BinaryArithmeticDecoder(const std::vector<std::uint8_t>& bits) : bits_(bits) {
    for (int i = 0; i < 10; ++i)
      code_ = (code_ << 1) | next_bit();
  }
  [[nodiscard]] int decode(std::size_t context) {
    const double p0 = std::round(static_cast<double>(zeros_[context]) / static_cast<double>(totals_[context]) * full);
    int split = static_cast<int>(static_cast<double>(high_ - low_) * p0) / full;
    if (split == 0) split = 1;
    if (split == high_ - low_) split = high_ - low_ - 1;
    int symbol = 0;
    if (code_ - low_ < split) {
      high_ = low_ + split;
    } else {
      symbol = 1;
      low_ += split;
    }
    for (;;) {  // renormalise: emit-free scaling as the encoder's (E1, E2, E3 cases)
      int offset = 0;
      if (high_ <= half)
        offset = 0;
      else if (low_ >= half)
        offset = half;
      else if (low_ >= quarter && high_ <= 3 * quarter)
        offset = quarter;
      else
        break;
      low_ = (low_ - offset) << 1;
      high_ = (high_ - offset) << 1;
      code_ = ((code_ - offset) << 1) | next_bit();
    }
    if (symbol == 0) ++zeros_[context];
    ++totals_[context];
    return symbol;
  }

 private:
  static constexpr int full = 1024, half = 512, quarter = 256;
  int next_bit() noexcept { return at_ < bits_.size() ? bits_[at_++] : 0; }
  const std::vector<std::uint8_t>& bits_;
  std::size_t at_{0};
  int code_{0}, low_{0}, high_{full};
  std::array<int, 7> zeros_{8, 8, 8, 8, 8, 8, 8};
  std::array<int, 7> totals_{16, 16, 16, 16, 16, 16, 16};
};

[[nodiscard]] inline int floor_log2(std::size_t n) noexcept {
  int k = -1;
  while (n != 0)
    n >>= 1, ++k;
  return k;
}

/// CDF 9/7 synthesis of one level: the first len coefficients (low half, high half) to len samples in place.
inline void inverse_cdf97_level(std::vector<double>& x, std::size_t len) {
  // analysis low-pass taps 0..4 and high-pass taps 0..3 (JPEG 2000 irreversible 9/7, sqrt(2) normalised)
  constexpr double l0 = 0.852698679009404, l1 = 0.377402855612654, l2 = -0.110624404418423, l3 = -0.023849465019380,
                   l4 = 0.037828455506995;
  constexpr double h0 = -0.788485616405665, h1 = 0.418092273222212, h2 = 0.040689417609559, h3 = -0.064538882628938;
  // synthesis filters: the analysis filters modulated by (-1)^n, centred
  constexpr std::array<double, 9> from_high{-l4, l3, -l2, l1, -l0, l1, -l2, l3, -l4};
  constexpr std::array<double, 7> from_low{h3, -h2, h1, -h0, h1, -h2, h3};
  std::vector<double> up_low(len, 0.0), up_high(len, 0.0);
  for (std::size_t j = 0; j < len; j += 2) {
    up_low[j] = x[j / 2];
    if (j + 1 < len) up_high[j + 1] = x[j / 2 + len / 2];
  }
  const auto n = static_cast<std::ptrdiff_t>(len);
  const auto at = [n](const std::vector<double>& v, std::ptrdiff_t m) {  // whole-sample symmetric extension
    if (n == 1) return v[0];
    while (m < 0 || m >= n)
      m = m < 0 ? -m : 2 * (n - 1) - m;
    return v[static_cast<std::size_t>(m)];
  };
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    double y = 0.0;
    for (std::ptrdiff_t k = 0; k < 9; ++k)
      y += from_high[static_cast<std::size_t>(k)] * at(up_high, i + 4 - k);
    for (std::ptrdiff_t k = 0; k < 7; ++k)
      y += from_low[static_cast<std::size_t>(k)] * at(up_low, i + 3 - k);
    x[static_cast<std::size_t>(i)] = y;
  }
}

}  // namespace detail

/// One WaveletWave block of `length` samples (a power of two in [16, max_wavelet_block]: the eight tree roots
/// need their children) from its base64 stream; an empty vector for another length.
[[nodiscard]] inline std::vector<double> decode_wavelet_block(std::string_view base64, std::size_t length) {
  if (length < 16 || length > max_wavelet_block || (length & (length - 1)) != 0) return {};
  const std::vector<std::uint8_t> bits = detail::base64_bits(base64);
  detail::BinaryArithmeticDecoder coder(bits);
  const auto read_bits = [&](int count) {  // least significant first
    int v = 0;
    for (int i = 0; i < count; ++i)
      v |= coder.decode(0) << i;
    return v;
  };
  const int planes = read_bits(4);
  const int wide = coder.decode(0);
  const int peak_code = read_bits(7);
  const double peak = wide != 0 ? peak_code / 8.0 + 1.0 : peak_code / 128.0;

  // SPIHT on the dyadic tree: roots 0..7, the last four of them with descendants
  const int log_length = detail::floor_log2(length);
  const std::size_t roots = std::size_t{2} << (log_length - (log_length - 2));
  std::vector<int> c(length, 0);
  std::vector<std::size_t> lip, lsp;
  struct SetEntry {
    std::size_t node;
    bool grandchildren;  // type B: the set of the node's grandchildren and below; type A: all descendants
  };
  std::vector<SetEntry> lis;
  for (std::size_t i = 0; i < roots; ++i)
    lip.push_back(i);
  for (std::size_t i = roots / 2; i < roots; ++i)
    lis.push_back({i, false});
  const auto significant = [&](std::size_t k, int threshold) {
    lsp.push_back(k);
    c[k] = coder.decode(1) == 1 ? threshold : -threshold;
  };
  for (int n = planes; n >= 0; --n) {
    const int threshold = 1 << n;
    const std::size_t refined = lsp.size();
    std::vector<std::size_t> still;
    for (const std::size_t k : lip) {
      if (coder.decode(2) == 1)
        significant(k, threshold);
      else
        still.push_back(k);
    }
    lip.swap(still);
    std::vector<SetEntry> kept;
    for (std::size_t i = 0; i < lis.size(); ++i) {  // entries appended below are visited in this pass too
      const SetEntry e = lis[i];
      if (!e.grandchildren) {
        if (coder.decode(3) == 0) {
          kept.push_back(e);
          continue;
        }
        for (const std::size_t child : {2 * e.node, 2 * e.node + 1}) {
          if (coder.decode(4) == 1)
            significant(child, threshold);
          else
            lip.push_back(child);
        }
        if (4 * e.node + 3 < length) lis.push_back({e.node, true});
      } else {
        if (coder.decode(5) == 0) {
          kept.push_back(e);
          continue;
        }
        lis.push_back({2 * e.node, false});
        lis.push_back({2 * e.node + 1, false});
      }
    }
    lis.swap(kept);
    for (std::size_t i = 0; i < refined; ++i)
      if (coder.decode(6) == 1) c[lsp[i]] += (c[lsp[i]] > 0 ? 1 : -1) * threshold;
  }

  const double step = peak / std::ldexp(1.0, planes);
  std::vector<double> x(length);
  for (std::size_t i = 0; i < length; ++i)
    x[i] = c[i] * step;
  const int levels = log_length - 2;
  for (int level = levels - 1; level >= 0; --level)
    detail::inverse_cdf97_level(x, length >> level);
  return x;
}

}  // namespace hapticfield::material
