#pragma once
/// @file integral_kernel.hpp
/// O(1)-per-pixel kernels for masks whose weights are linear in the column
/// (Prewitt) or a sign (block emboss), from integral images of the inverted
/// image and of its first moments (Crow 1984 summed-area tables):
///
///   Prewitt  Fx = sum P (c - x) = M1x(box) - (x - x0) M0(box)
///   emboss   Fx = M0(right half) - M0(left half)
///
/// with M0 the plain sum and M1x the sum of P (c - x0). Four table reads per
/// box whatever the mask size.
///
/// The tables hold integers, so the sums are exact: gray levels are written
/// as Q = round(P D) with D = 1 (8-bit gray), 100 (the paper's weights on
/// 8-bit colour: 0.3, 0.59, 0.11), 1000 (BT.601), found by checking that
/// every P D is an integer; any other picture uses D = 2^24 (a 3e-10 of
/// full scale quantisation). The tables wrap modulo 2^32 or 2^64; a box
/// combination of four cells is then its exact sum modulo the same, and as
/// the true force |M1x - (x - x0) M0| <= D 255 m h (h + 1) (h = m / 2) fits
/// in a signed word, the wrapped result is the exact force. 32-bit cells
/// (12 bytes for the three tables) are used when that bound is below 2^31:
/// 8-bit gray at every m, the paper's colour weights up to m = 65, BT.601 up
/// to m = 17; 64-bit cells (24 bytes) otherwise. Large tables ask Linux for
/// transparent huge pages, so random queries do not miss the TLB.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <glm/vec2.hpp>

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/direct_kernel.hpp"
#include "hapticfield/kernels/mask.hpp"

namespace hapticfield {

/// True when MaskKind has an O(1) integral-image kernel.
[[nodiscard]] constexpr bool has_integral_kernel(MaskKind kind) noexcept {
  return kind == MaskKind::prewitt || kind == MaskKind::emboss;
}

namespace detail {

/// A fixed-size array of trivially copyable T, aligned to 2 MiB when large
/// and advised for transparent huge pages on Linux (setup only).
template <class T>
requires std::is_trivially_copyable_v<T>
class LargeArray {
 public:
  LargeArray() = default;
  explicit LargeArray(std::size_t n) : size_(n) {
    if (n == 0) return;
    constexpr std::size_t huge = std::size_t{2} << 20;  // [bytes]
    const std::size_t bytes = n * sizeof(T);
    const std::size_t align = bytes >= huge ? huge : alignof(std::max_align_t);
    const std::size_t rounded = (bytes + align - 1) / align * align;
    data_ = static_cast<T*>(std::aligned_alloc(align, rounded));
    if (!data_) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (align == huge) (void)madvise(data_, rounded, MADV_HUGEPAGE);  // a hint; failure is harmless
#endif
  }
  LargeArray(const LargeArray& other) : LargeArray(other.size_) {
    if (size_) std::memcpy(data_, other.data_, size_ * sizeof(T));
  }
  LargeArray(LargeArray&& other) noexcept : data_(other.data_), size_(other.size_) {
    other.data_ = nullptr;
    other.size_ = 0;
  }
  LargeArray& operator=(LargeArray other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
    return *this;
  }
  ~LargeArray() {
    std::free(data_);
  }

  [[nodiscard]] T* data() noexcept {
    return data_;
  }
  [[nodiscard]] const T* data() const noexcept {
    return data_;
  }
  [[nodiscard]] std::size_t size() const noexcept {
    return size_;
  }
  T& operator[](std::size_t i) noexcept {
    return data_[i];
  }
  const T& operator[](std::size_t i) const noexcept {
    return data_[i];
  }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

/// Distance of q from the nearest integer, for q in [0, 2^31) (anything
/// else gives a large value); cheap enough to vectorise.
[[nodiscard]] inline double off_integer(double q) noexcept {
  if (!(q >= 0.0 && q < 2147483647.0)) return 1.0;
  return std::abs(q - static_cast<double>(static_cast<std::int32_t>(q + 0.5)));
}

/// Largest off_integer(p d) over the first n values of p.
[[nodiscard]] inline double max_off_integer(const double* p, std::size_t n, double d) noexcept {
  double worst = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    worst = std::max(worst, off_integer(p[i] * d));
  return worst;
}

/// Tolerance of the integer test [levels x D]: double gray levels from
/// integer channels carry rounding of about 1e-13.
inline constexpr double integer_tolerance = 1e-6;

/// The smallest D in {1, 100, 1000} for which every P D is an integer (to
/// integer_tolerance), else 2^24: the fixed-point scale of the integral
/// tables.
[[nodiscard]] inline double fixed_point_scale(const GrayImage& image) noexcept {
  const std::vector<double>& p = image.pixels();
  // Levels outside [0, 255] (which GrayImage does not promise to exclude)
  // would void the force bound of the narrow route: take the wide one.
  for (const double v : p)
    if (!(v >= 0.0 && v <= gray_full_scale)) return 16777216.0;
  // Blocks of 1024 keep the inner loop vectorised and stop early on a
  // picture that is not integer at this D (most frames of a video).
  constexpr std::size_t block = 1024;
  for (const double d : {1.0, 100.0, 1000.0}) {
    bool fits = true;
    for (std::size_t i = 0; fits && i < p.size(); i += block)
      fits = max_off_integer(p.data() + i, std::min(block, p.size() - i), d) <= integer_tolerance;
    if (fits) return d;
  }
  return 16777216.0;  // 2^24
}

/// The D of fixed_point_scale() judged from a few rows only (0 when none
/// fits): a guess for code that checks every value as it converts it.
[[nodiscard]] inline double guess_fixed_point_scale(const GrayImage& image) noexcept {
  for (const double d : {1.0, 100.0, 1000.0}) {
    bool fits = true;
    for (const int y : {0, image.height() / 3, image.height() / 2, image.height() - 1})
      fits = fits && max_off_integer(image.row(y), static_cast<std::size_t>(image.width()), d) <= integer_tolerance;
    if (fits) return d;
  }
  return 0.0;
}

}  // namespace detail

class IntegralKernel {
 public:
  /// @param inverted  the inverted image 255 - Y
  /// @param kind      MaskKind::prewitt or MaskKind::emboss
  /// @param size      odd mask size 3..129 [px]
  /// @throws std::invalid_argument for another kind, a bad size, or an image
  ///         that is empty or smaller than the mask.
  IntegralKernel(const GrayImage& inverted, MaskKind kind, int size, Border border)
      : kind_(kind), size_(size), border_(border), width_(inverted.width()), height_(inverted.height()) {
    if (!has_integral_kernel(kind))
      throw std::invalid_argument(std::string("IntegralKernel: no O(1) kernel for mask ") + to_string(kind) +
                                  " (prewitt and emboss only)");
    validate_mask_size(kind, size);
    validate_image_for_mask(inverted, size);
    const double d = detail::fixed_point_scale(inverted);
    scale_ = 1.0 / (Mask<>::make(kind, size).step_response() * d);
    pad_ = size;
    stride_ = width_ + 2 * pad_ + 1;
    x0_ = (width_ + 2 * pad_) / 2;
    y0_ = (height_ + 2 * pad_) / 2;
    const int h = size / 2;
    const double bound = d * gray_full_scale * size * h * (h + 1.0);  // largest |force| before scaling
    wide_ = !(bound < 2147483648.0);
    if (wide_)
      build(inverted, d, wide_table_);
    else
      build(inverted, d, narrow_table_);
  }

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] int mask_size() const noexcept { return size_; }
  [[nodiscard]] int anchor() const noexcept { return size_ / 2; }
  [[nodiscard]] Border border() const noexcept { return border_; }
  [[nodiscard]] MaskKind kind() const noexcept { return kind_; }
  /// Bytes per table cell (one per padded pixel): 12 or 24.
  [[nodiscard]] std::size_t bytes_per_cell() const noexcept {
    return wide_ ? sizeof(Cell<std::uint64_t>) : sizeof(Cell<std::uint32_t>);
  }
  /// Memory held by the tables [bytes].
  [[nodiscard]] std::size_t table_bytes() const noexcept {
    return wide_ ? wide_table_.size() * sizeof(Cell<std::uint64_t>)
                 : narrow_table_.size() * sizeof(Cell<std::uint32_t>);
  }

  /// Normalised force at the centre of pixel (x, y); same contract as
  /// DirectKernel::at_pixel().
  [[nodiscard]] glm::dvec2 at_pixel(int x, int y) const noexcept {
    return wide_ ? at_pixel_in(wide_table_, x, y) : at_pixel_in(narrow_table_, x, y);
  }

 private:
  /// The three tables side by side, so one cache line serves all of them.
  /// Unsigned: sums wrap modulo 2^bits (see the file comment).
  template <class U>
  struct Cell {
    U sum;       ///< sum of Q
    U moment_x;  ///< sum of Q (c - x0)
    U moment_y;  ///< sum of Q (r - y0)
  };

  template <class U>
  void build(const GrayImage& inverted, double d, detail::LargeArray<Cell<U>>& table) {
    using S = std::make_signed_t<U>;
    const int pw = width_ + 2 * pad_;
    const int ph = height_ + 2 * pad_;
    table = detail::LargeArray<Cell<U>>(static_cast<std::size_t>(stride_) * static_cast<std::size_t>(ph + 1));
    std::memset(table.data(), 0, static_cast<std::size_t>(stride_) * sizeof(Cell<U>));  // row 0
    const bool fill = !needs_full_mask(border_);  // suspend / fade read no pixel beyond the picture
    // One padded row of Q, built from the picture through the border policy:
    // the picture's own columns straight from the row, the pads through
    // border_index (suspend and fade leave them zero).
    std::vector<S> q(static_cast<std::size_t>(pw));
    const auto quantised = [d](double level) noexcept {
      const double v = level * d;
      // Exact rounding, half away from zero as llround; the common case
      // (v >= 0) without the library call. v - trunc(v) is exact.
      if (!(v >= 0.0)) return static_cast<S>(std::llround(v));
      const S whole = static_cast<S>(v);
      return v - static_cast<double>(whole) >= 0.5 ? static_cast<S>(whole + 1) : whole;
    };
    for (int r = 0; r < ph; ++r) {
      const int sy = r - pad_;
      const bool row_inside = sy >= 0 && sy < height_;
      std::fill(q.begin(), q.end(), S{0});
      if (row_inside || fill) {
        const double* src = inverted.row(detail::border_index(sy, height_, border_));
        S* inside = q.data() + pad_;
        for (int x = 0; x < width_; ++x)
          inside[x] = quantised(src[x]);
        if (fill)
          for (int c = 0; c < pad_; ++c) {
            q[static_cast<std::size_t>(c)] = quantised(src[detail::border_index(c - pad_, width_, border_)]);
            const int right = pad_ + width_ + c;
            q[static_cast<std::size_t>(right)] = quantised(src[detail::border_index(width_ + c, width_, border_)]);
          }
      }
      Cell<U>* above = table.data() + static_cast<std::size_t>(r) * stride_;
      Cell<U>* here = above + stride_;
      here[0] = Cell<U>{0, 0, 0};
      U row_sum = 0;
      U row_mx = 0;
      const U dy = static_cast<U>(static_cast<S>(r - y0_));
      for (int c = 0; c < pw; ++c) {
        const U v = static_cast<U>(q[static_cast<std::size_t>(c)]);
        row_sum += v;
        row_mx += v * static_cast<U>(static_cast<S>(c - x0_));
        const Cell<U>& up = above[c + 1];
        here[c + 1] = Cell<U>{static_cast<U>(up.sum + row_sum), static_cast<U>(up.moment_x + row_mx),
                              static_cast<U>(up.moment_y + row_sum * dy)};
      }
    }
  }

  template <class U>
  [[nodiscard]] glm::dvec2 at_pixel_in(const detail::LargeArray<Cell<U>>& table, int x, int y) const noexcept {
    using S = std::make_signed_t<U>;
    const int a = size_ / 2;
    const int cx = x + pad_;
    const int cy = y + pad_;
    const int c0 = cx - a;
    const int c1 = c0 + size_;  // exclusive
    const int r0 = cy - a;
    const int r1 = r0 + size_;  // exclusive
    if (kind_ == MaskKind::prewitt) {
      const Cell<U> b = box(table, r0, r1, c0, c1);
      const auto fx = static_cast<S>(static_cast<U>(b.moment_x - static_cast<U>(static_cast<S>(cx - x0_)) * b.sum));
      const auto fy = static_cast<S>(static_cast<U>(b.moment_y - static_cast<U>(static_cast<S>(cy - y0_)) * b.sum));
      return glm::dvec2{static_cast<double>(fx) * scale_, static_cast<double>(fy) * scale_};
    }
    const auto fx = static_cast<S>(static_cast<U>(box(table, r0, r1, cx + 1, c1).sum - box(table, r0, r1, c0, cx).sum));
    const auto fy = static_cast<S>(static_cast<U>(box(table, cy + 1, r1, c0, c1).sum - box(table, r0, cy, c0, c1).sum));
    return glm::dvec2{static_cast<double>(fx) * scale_, static_cast<double>(fy) * scale_};
  }

  /// Sums over padded rows [r0, r1) and columns [c0, c1), modulo 2^bits.
  template <class U>
  [[nodiscard]] Cell<U> box(const detail::LargeArray<Cell<U>>& table, int r0, int r1, int c0, int c1) const noexcept {
    const std::size_t s = static_cast<std::size_t>(stride_);
    const Cell<U>& a = table[r1 * s + c1];
    const Cell<U>& b = table[r0 * s + c1];
    const Cell<U>& c = table[r1 * s + c0];
    const Cell<U>& d = table[r0 * s + c0];
    return Cell<U>{static_cast<U>(a.sum - b.sum - c.sum + d.sum),
                   static_cast<U>(a.moment_x - b.moment_x - c.moment_x + d.moment_x),
                   static_cast<U>(a.moment_y - b.moment_y - c.moment_y + d.moment_y)};
  }

  MaskKind kind_;
  int size_;
  Border border_;
  int width_;
  int height_;
  int pad_ = 0;
  int stride_ = 0;
  int x0_ = 0;
  int y0_ = 0;
  double scale_ = 1.0;
  bool wide_ = false;
  detail::LargeArray<Cell<std::uint32_t>> narrow_table_;
  detail::LargeArray<Cell<std::uint64_t>> wide_table_;
};

}  // namespace hapticfield
