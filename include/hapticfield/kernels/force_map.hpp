#pragma once
/// @file force_map.hpp
/// Force maps: the normalised force at every pixel centre as two float
/// planes, from any kernel, plus an O(1)-per-pixel Prewitt map built from
/// running sums that matches the per-pixel kernels to float rounding.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <thread>
#include <type_traits>
#include <vector>

#include <glm/vec2.hpp>

#include "hapticfield/core/always_inline.hpp"
#include "hapticfield/core/restrict.hpp"
#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/direct_kernel.hpp"
#include "hapticfield/kernels/image_force.hpp"
#include "hapticfield/kernels/integral_kernel.hpp"
#include "hapticfield/kernels/mask.hpp"

#if (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
#define HAPTICFIELD_X86_DISPATCH 1
#include <immintrin.h>
// AVX-512F code whose double arithmetic must round as the other routes do:
// GCC would fuse a multiply and an add into one FMA there (AVX-512F has
// them), so contraction is off; clang fuses only within one expression.
#if defined(__clang__)
#define HAPTICFIELD_AVX512_EXACT __attribute__((target("avx512f")))
#define HAPTICFIELD_AVX512_EXACT_WIDE __attribute__((target("avx512f")))
#else
#define HAPTICFIELD_AVX512_EXACT __attribute__((target("avx512f"), optimize("fp-contract=off")))
#define HAPTICFIELD_AVX512_EXACT_WIDE \
  __attribute__((target("avx512f,prefer-vector-width=512"), optimize("fp-contract=off")))
#endif
#else
#define HAPTICFIELD_X86_DISPATCH 0
#endif

namespace hapticfield {

/// fx and fy at every pixel centre, row-major, normalised (1 = a black/white
/// edge), x right and y down.
struct ForceMap {
  int width = 0;
  int height = 0;
  std::vector<float> fx;
  std::vector<float> fy;

  [[nodiscard]] std::size_t index(int x, int y) const noexcept {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
  }
  /// Largest force magnitude in the map.
  [[nodiscard]] double max_magnitude() const noexcept {
    double m = 0.0;
    for (std::size_t i = 0; i < fx.size(); ++i)
      m = std::max(m, std::hypot(double(fx[i]), double(fy[i])));
    return m;
  }
};

/// The map of anything with at_pixel(x, y), width() and height() (an
/// ImageForce or a TangibleImage): one kernel evaluation per pixel.
template <class Source>
[[nodiscard]] ForceMap force_map(const Source& source) {
  ForceMap map{source.width(), source.height(), {}, {}};
  map.fx.assign(static_cast<std::size_t>(map.width) * map.height, 0.0f);
  map.fy.assign(map.fx.size(), 0.0f);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const glm::dvec2 f = source.at_pixel(x, y);
      map.fx[map.index(x, y)] = static_cast<float>(f.x);
      map.fy[map.index(x, y)] = static_cast<float>(f.y);
    }
  }
  return map;
}

namespace detail {

/// Instruction sets the integer route is compiled for, chosen at run time.
enum class MapSimd { baseline, avx2, avx512 };

/// Arithmetic of the map's running sums. double: the gray levels as they
/// are. std::uint32_t: gray levels as exact integers Q = P D (see
/// integral_kernel.hpp), summed modulo 2^32; the final force is exact as
/// long as its true value fits 31 bits, which prewitt_force_map() checks.
template <class T>
struct MapArithmetic;

template <>
struct MapArithmetic<double> {
  [[nodiscard]] static double value(double p, double, std::uint64_t&) noexcept { return p; }
  [[nodiscard]] static double weight(int i) noexcept { return static_cast<double>(i); }
  [[nodiscard]] static float out(double v, double scale) noexcept { return static_cast<float>(v * scale); }
};

template <>
struct MapArithmetic<std::uint32_t> {
  /// Q = round(p d), by the 1.5 * 2^52 trick (adding it leaves the rounded
  /// integer in the low mantissa bits): no branch and no out-of-range cast,
  /// so the conversion loop vectorises. bad gets non-zero bits when p d is
  /// not an integer to 2^-21 (rounding p d 2^20 then disagrees with 2^20 Q),
  /// lies outside [0, 255 d], or is NaN.
  [[nodiscard]] static std::uint32_t value(double p, double d, std::uint64_t& bad) noexcept {
    constexpr double magic = 6755399441055744.0;  // 1.5 * 2^52
    const auto bits = std::bit_cast<std::uint64_t>(magic);
    const double q = p * d;
    // unsigned: any bit pattern (NaN, huge values) wraps instead of overflowing
    const std::uint64_t k = std::bit_cast<std::uint64_t>(q + magic) - bits;
    const std::uint64_t k20 = std::bit_cast<std::uint64_t>(q * 1048576.0 + magic) - bits;
    bad |=
        (k20 - (k << 20)) | (k >> 31) | static_cast<std::uint64_t>(k > static_cast<std::uint64_t>(gray_full_scale * d));
    return static_cast<std::uint32_t>(k);
  }
  [[nodiscard]] static std::uint32_t weight(int i) noexcept { return static_cast<std::uint32_t>(i); }
  [[nodiscard]] static float out(std::uint32_t v, double scale) noexcept {
    return static_cast<float>(static_cast<double>(static_cast<std::int32_t>(v)) * scale);
  }
};

#if HAPTICFIELD_X86_DISPATCH
/// Q = round((255 - p) d) for n contiguous levels, eight at a time; returns
/// non-zero when one is not an integer to integer_tolerance or lies outside
/// [0, 255 d] (NaN included). The conversion is exact for integers whatever
/// the rounding mode. The checks are folded into two running maxima (the
/// distance to the integer, and Q as unsigned: a negative or out-of-range Q,
/// NaN included, converts to a value above 255 d), tested once at the end.
__attribute__((target("avx2"))) inline std::uint64_t convert_levels_avx2(
    const double* HAPTICFIELD_RESTRICT p, int n, double d, std::uint32_t* HAPTICFIELD_RESTRICT out) noexcept {
  const __m256d vd = _mm256_set1_pd(d);
  const __m256d top = _mm256_set1_pd(gray_full_scale * d);
  const __m256d sign = _mm256_set1_pd(-0.0);
  __m256d worst_off = _mm256_setzero_pd();
  __m256i worst_q = _mm256_setzero_si256();
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    const __m256d q0 = _mm256_sub_pd(top, _mm256_mul_pd(_mm256_loadu_pd(p + i), vd));
    const __m256d q1 = _mm256_sub_pd(top, _mm256_mul_pd(_mm256_loadu_pd(p + i + 4), vd));
    const __m128i k0 = _mm256_cvtpd_epi32(q0);
    const __m128i k1 = _mm256_cvtpd_epi32(q1);
    // max_pd returns its second operand when the first is NaN; a NaN level
    // is caught by the range test instead.
    worst_off = _mm256_max_pd(_mm256_andnot_pd(sign, _mm256_sub_pd(q0, _mm256_cvtepi32_pd(k0))), worst_off);
    worst_off = _mm256_max_pd(_mm256_andnot_pd(sign, _mm256_sub_pd(q1, _mm256_cvtepi32_pd(k1))), worst_off);
    const __m256i k = _mm256_inserti128_si256(_mm256_castsi128_si256(k0), k1, 1);
    worst_q = _mm256_max_epu32(worst_q, k);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), k);
  }
  alignas(32) double offs[4];
  alignas(32) std::uint32_t qs[8];
  _mm256_store_pd(offs, worst_off);
  _mm256_store_si256(reinterpret_cast<__m256i*>(qs), worst_q);
  const auto highest = static_cast<std::uint32_t>(gray_full_scale * d);
  std::uint64_t bad = 0;
  for (const double o : offs)
    bad |= static_cast<std::uint64_t>(!(o <= integer_tolerance));
  for (const std::uint32_t q : qs)
    bad |= static_cast<std::uint64_t>(q > highest);
  std::uint64_t rest = 0;
  for (; i < n; ++i)
    out[i] = MapArithmetic<std::uint32_t>::value(gray_full_scale - p[i], d, rest);
  return bad | rest;
}

/// All-lanes masks for the AVX-512 intrinsics: the masked forms name no
/// undefined register, which GCC 12 would warn about.
inline constexpr __mmask8 all8 = 0xFF;
inline constexpr __mmask16 all16 = 0xFFFF;

/// convert_levels_avx2() sixteen levels at a time (AVX-512F: eight doubles
/// to eight int32 in one instruction); the rest through the AVX2 version.
HAPTICFIELD_AVX512_EXACT inline std::uint64_t convert_levels_avx512(const double* HAPTICFIELD_RESTRICT p, int n,
                                                                    double d,
                                                                    std::uint32_t* HAPTICFIELD_RESTRICT out) noexcept {
  const __m512d vd = _mm512_set1_pd(d);
  const __m512d top = _mm512_set1_pd(gray_full_scale * d);
  __m512d worst_off = _mm512_setzero_pd();
  __m512i worst_q = _mm512_setzero_si512();
  int i = 0;
  for (; i + 16 <= n; i += 16) {
    const __m512d q0 = _mm512_sub_pd(top, _mm512_mul_pd(_mm512_loadu_pd(p + i), vd));
    const __m512d q1 = _mm512_sub_pd(top, _mm512_mul_pd(_mm512_loadu_pd(p + i + 8), vd));
    const __m256i k0 = _mm512_maskz_cvtpd_epi32(all8, q0);
    const __m256i k1 = _mm512_maskz_cvtpd_epi32(all8, q1);
    // as in convert_levels_avx2: a NaN distance leaves the maximum alone
    worst_off =
        _mm512_maskz_max_pd(all8, _mm512_abs_pd(_mm512_sub_pd(q0, _mm512_maskz_cvtepi32_pd(all8, k0))), worst_off);
    worst_off =
        _mm512_maskz_max_pd(all8, _mm512_abs_pd(_mm512_sub_pd(q1, _mm512_maskz_cvtepi32_pd(all8, k1))), worst_off);
    const __m512i k = _mm512_maskz_inserti64x4(all8, _mm512_castsi256_si512(k0), k1, 1);
    worst_q = _mm512_maskz_max_epu32(all16, worst_q, k);
    _mm512_storeu_si512(out + i, k);
  }
  alignas(64) double offs[8];
  alignas(64) std::uint32_t qs[16];
  _mm512_store_pd(offs, worst_off);
  _mm512_store_si512(qs, worst_q);
  const auto highest = static_cast<std::uint32_t>(gray_full_scale * d);
  std::uint64_t bad = 0;
  for (const double o : offs)
    bad |= static_cast<std::uint64_t>(!(o <= integer_tolerance));
  for (const std::uint32_t q : qs)
    bad |= static_cast<std::uint64_t>(q > highest);
  return bad | convert_levels_avx2(p + i, n - i, d, out + i);
}
#endif

/// Inverted picture row `row`, columns c_first .. c_first + n - 1, extended
/// past the picture's sides by the border policy, into out[q * stride], in
/// the arithmetic T (scale d for integers). Returns non-zero when a scaled
/// value was not an integer (always 0 for double).
template <class T, MapSimd Simd = MapSimd::baseline>
HAPTICFIELD_ALWAYS_INLINE inline std::uint64_t inverted_padded_row(const GrayImage& gray, int row, int c_first, int n,
                                                                   Border border, T* HAPTICFIELD_RESTRICT out,
                                                                   int stride, double d) {
  using A = MapArithmetic<T>;
  std::uint64_t worst = 0;
  const double* src = gray.row(row);
  const int w = gray.width();
  const int interior_begin = std::clamp(-c_first, 0, n);
  const int interior_end = std::clamp(w - c_first, interior_begin, n);
  for (int q = 0; q < interior_begin; ++q)
    out[q * stride] = A::value(gray_full_scale - src[border_index(c_first + q, w, border)], d, worst);
  bool done = false;
#if HAPTICFIELD_X86_DISPATCH
  if constexpr (Simd != MapSimd::baseline && std::is_same_v<T, std::uint32_t>) {
    if (stride == 1) {
      const int count = interior_end - interior_begin;
      if constexpr (Simd == MapSimd::avx512)
        worst |= convert_levels_avx512(src + c_first + interior_begin, count, d, out + interior_begin);
      else
        worst |= convert_levels_avx2(src + c_first + interior_begin, count, d, out + interior_begin);
      done = true;
    }
  }
#endif
  if (done) {
  } else if (stride == 1) {  // contiguous: vectorises
    const double* HAPTICFIELD_RESTRICT in = src + c_first;
    for (int q = interior_begin; q < interior_end; ++q)
      out[q] = A::value(gray_full_scale - in[q], d, worst);
  } else {
    for (int q = interior_begin; q < interior_end; ++q)
      out[q * stride] = A::value(gray_full_scale - src[c_first + q], d, worst);
  }
  for (int q = interior_end; q < n; ++q)
    out[q * stride] = A::value(gray_full_scale - src[border_index(c_first + q, w, border)], d, worst);
  return worst;
}

/// Fills every pixel of the map outside [x0, x1] x [y0, y1] with the force
/// of the nearest pixel inside, faded linearly to zero over fade_px of
/// Euclidean distance: what ImageForce::at_pixel() gives there.
inline void extend_outside(ForceMap& map, int x0, int x1, int y0, int y1, double fade_px) {
  for (int y = 0; y < map.height; ++y) {
    float* fx = &map.fx[map.index(0, y)];
    float* fy = &map.fy[map.index(0, y)];
    const int py = std::clamp(y, y0, y1);
    const float* sx = &map.fx[map.index(0, py)];
    const float* sy = &map.fy[map.index(0, py)];
    const bool whole = y < y0 || y > y1;
    for (int x = 0; x < map.width; ++x) {
      if (!whole && x >= x0 && x <= x1) {
        x = x1;  // skip the interior
        continue;
      }
      const int px = std::clamp(x, x0, x1);
      const double d = std::hypot(double(x - px), double(y - py));  // [px]
      const double g = d < fade_px ? 1.0 - d / fade_px : 0.0;
      fx[x] = static_cast<float>(g * sx[px]);
      fy[x] = static_cast<float>(g * sy[px]);
    }
  }
}

}  // namespace detail

namespace detail {

/// One step down the columns: row `in` enters the window, row `out` leaves.
/// box = sum of H0, ramp = sum of i H0(y + i) (fy), moment = sum of H1
/// (fx); with fx, fy given, also writes the row scaled by `scale`. A function
/// of its own so the compiler sees the restrict-qualified parameters and
/// vectorises the loop.
template <class T>
HAPTICFIELD_ALWAYS_INLINE inline void slide_columns(T* HAPTICFIELD_RESTRICT box, T* HAPTICFIELD_RESTRICT ramp,
                                                    T* HAPTICFIELD_RESTRICT moment, const T* HAPTICFIELD_RESTRICT in0,
                                                    const T* HAPTICFIELD_RESTRICT out0,
                                                    const T* HAPTICFIELD_RESTRICT in1,
                                                    const T* HAPTICFIELD_RESTRICT out1, int n, T h,
                                                    float* HAPTICFIELD_RESTRICT fx, float* HAPTICFIELD_RESTRICT fy,
                                                    double scale) noexcept {
  using A = MapArithmetic<T>;
  const T h1 = h + T(1);
  if (fx == nullptr) {
    for (int x = 0; x < n; ++x) {
      const T b = box[x] + (in0[x] - out0[x]);
      box[x] = b;
      ramp[x] += h * out0[x] + h1 * in0[x] - b;
      moment[x] += in1[x] - out1[x];
    }
    return;
  }
  for (int x = 0; x < n; ++x) {
    const T b = box[x] + (in0[x] - out0[x]);
    const T r = ramp[x] + (h * out0[x] + h1 * in0[x] - b);
    const T m = moment[x] + (in1[x] - out1[x]);
    box[x] = b;
    ramp[x] = r;
    moment[x] = m;
    fx[x] = A::out(m, scale);
    fy[x] = A::out(r, scale);
  }
}

/// Output rows y_first .. y_last of the Prewitt map; the output region is
/// [lo, x_hi] x [lo, y_hi]. See prewitt_force_map().
template <class T>
HAPTICFIELD_ALWAYS_INLINE inline bool prewitt_band_in(const GrayImage& gray, int h, Border border, double fade_px,
                                                      double scale, double d, int lo, int x_hi, int y_hi, int y_first,
                                                      int y_last, ForceMap& map) {
  using A = MapArithmetic<T>;
  const int height = gray.height();
  const int n_out = x_hi - lo + 1;
  const int n_in = n_out + 2 * h;
  const int r_last = y_last + h;

  // Ring of horizontal results: rows y - h - 1 .. y + h + 3 are alive at once.
  constexpr int batch = 32 / static_cast<int>(sizeof(T));  // one 256-bit vector of rows
  const int ring = 2 * h + 2 + batch;
  std::vector<T> h0(static_cast<std::size_t>(ring) * n_out);
  std::vector<T> h1(h0.size());
  const auto h0_row = [&](int r) HAPTICFIELD_ALWAYS_INLINE {
    return &h0[static_cast<std::size_t>((r + ring * 4) % ring) * n_out];
  };
  const auto h1_row = [&](int r) HAPTICFIELD_ALWAYS_INLINE {
    return &h1[static_cast<std::size_t>((r + ring * 4) % ring) * n_out];
  };

  // Horizontal pass for rows r .. r + k - 1 (k <= batch). The rows are
  // interleaved (column q of row b at q * batch + b) so the running sums of
  // the batch advance together in vector registers.
  std::vector<T> rows(static_cast<std::size_t>(batch) * n_in, T(0));
  const auto horizontal = [&](int r, int k) HAPTICFIELD_ALWAYS_INLINE {
    for (int b = 0; b < k; ++b)
      (void)detail::inverted_padded_row<T>(gray, detail::border_index(r + b, height, border), lo - h, n_in, border,
                                           &rows[b], batch, d);
    T s[batch] = {};
    T m1[batch] = {};
    for (int q = 0; q <= 2 * h; ++q)
      for (int b = 0; b < batch; ++b) {
        s[b] += rows[q * batch + b];
        m1[b] += A::weight(q - h) * rows[q * batch + b];
      }
    T* o0[batch] = {};
    T* o1[batch] = {};
    for (int b = 0; b < k; ++b) {
      o0[b] = h0_row(r + b);
      o1[b] = h1_row(r + b);
      o0[b][0] = s[b];
      o1[b][0] = m1[b];
    }
    const T hh = A::weight(h);
    const T hh1 = A::weight(h + 1);
    for (int i = 1; i < n_out; ++i) {
      const T* leaving = &rows[static_cast<std::size_t>(i - 1) * batch];
      const T* entering = &rows[static_cast<std::size_t>(i + 2 * h) * batch];
      for (int b = 0; b < batch; ++b) {
        s[b] += entering[b] - leaving[b];
        m1[b] += hh * leaving[b] + hh1 * entering[b] - s[b];  // sum of j P(x + j), from x - 1
      }
      for (int b = 0; b < k; ++b) {
        o0[b][i] = s[b];
        o1[b][i] = m1[b];
      }
    }
  };
  int computed = y_first - h;  // next row without a horizontal result
  const auto ensure = [&](int r) HAPTICFIELD_ALWAYS_INLINE {
    while (computed <= r) {
      const int k = std::min(batch, r_last - computed + 1);
      horizontal(computed, k);
      computed += k;
    }
  };

  // Vertical pass. box = sum of H0 over the window, ramp = sum of i H0(y + i)
  // (fy), moment = sum of H1(y + i) (fx).
  std::vector<T> box(static_cast<std::size_t>(n_out), T(0));
  std::vector<T> ramp(static_cast<std::size_t>(n_out), T(0));
  std::vector<T> moment(static_cast<std::size_t>(n_out), T(0));
  ensure(y_first + h);
  for (int i = -h; i <= h; ++i) {
    const T* a = h0_row(y_first + i);
    const T* b = h1_row(y_first + i);
    const T wi = A::weight(i);
    for (int x = 0; x < n_out; ++x) {
      box[x] += a[x];
      ramp[x] += wi * a[x];
      moment[x] += b[x];
    }
  }
  const T hh = A::weight(h);
  for (int y = y_first; y <= y_last; ++y) {
    float* fx = &map.fx[map.index(lo, y)];
    float* fy = &map.fy[map.index(lo, y)];
    T* bx = box.data();
    T* rp = ramp.data();
    T* mo = moment.data();
    const bool fade = border == Border::fade;
    if (y > y_first) {  // slide the window down: row y - 1 - h leaves, row y + h enters
      ensure(y + h);
      slide_columns(bx, rp, mo, h0_row(y + h), h0_row(y - 1 - h), h1_row(y + h), h1_row(y - 1 - h), n_out, hh,
                    fade ? nullptr : fx, fade ? nullptr : fy, scale);
      if (!fade) continue;  // the row is written
    }
    if (fade) {
      const double row_inside = std::min(y - lo, y_hi - y);
      for (int x = 0; x < n_out; ++x) {
        const double inside = std::min(row_inside, static_cast<double>(std::min(x, n_out - 1 - x)));
        const double g = scale * std::clamp(inside / fade_px, 0.0, 1.0);
        fx[x] = A::out(mo[x], g);
        fy[x] = A::out(rp[x], g);
      }
    } else {
      for (int x = 0; x < n_out; ++x) {
        fx[x] = A::out(mo[x], scale);
        fy[x] = A::out(rp[x], scale);
      }
    }
  }
  return true;
}

/// Prefix sums of one row for the integer route: c0[t + 1] = sum of b[0..t],
/// d0[t + 1] = sum of s b[s], c1[t + 1] = sum of r[0..t] (modulo 2^32).
HAPTICFIELD_ALWAYS_INLINE inline void prefix_sums_scalar(const std::uint32_t* HAPTICFIELD_RESTRICT b,
                                                         const std::uint32_t* HAPTICFIELD_RESTRICT r, std::size_t n,
                                                         std::uint32_t* HAPTICFIELD_RESTRICT c0,
                                                         std::uint32_t* HAPTICFIELD_RESTRICT d0,
                                                         std::uint32_t* HAPTICFIELD_RESTRICT c1, std::size_t from = 0,
                                                         std::uint32_t s0 = 0, std::uint32_t sd = 0,
                                                         std::uint32_t s1 = 0) noexcept {
  for (std::size_t t = from; t < n; ++t) {
    s0 += b[t];
    sd += static_cast<std::uint32_t>(t) * b[t];
    s1 += r[t];
    c0[t + 1] = s0;
    d0[t + 1] = sd;
    c1[t + 1] = s1;
  }
}

#if HAPTICFIELD_X86_DISPATCH
/// Inclusive prefix sum of eight uint32 lanes, plus carry.
__attribute__((target("avx2"), always_inline)) inline __m256i scan8(__m256i x, __m256i carry) noexcept {
  x = _mm256_add_epi32(x, _mm256_slli_si256(x, 4));
  x = _mm256_add_epi32(x, _mm256_slli_si256(x, 8));
  const __m256i low_total = _mm256_shuffle_epi32(x, 0xFF);                         // element 3 of each half
  x = _mm256_add_epi32(x, _mm256_permute2x128_si256(low_total, low_total, 0x08));  // into the upper half only
  return _mm256_add_epi32(x, carry);
}

/// The same with AVX2: an in-register scan of eight sums at a time (two
/// shifted adds per 128-bit half, then the lower half's total carried into
/// the upper half and the running total into both).
__attribute__((target("avx2"))) inline void prefix_sums_avx2(const std::uint32_t* HAPTICFIELD_RESTRICT b,
                                                             const std::uint32_t* HAPTICFIELD_RESTRICT r, std::size_t n,
                                                             std::uint32_t* HAPTICFIELD_RESTRICT c0,
                                                             std::uint32_t* HAPTICFIELD_RESTRICT d0,
                                                             std::uint32_t* HAPTICFIELD_RESTRICT c1) noexcept {
  const __m256i last = _mm256_set1_epi32(7);
  __m256i k0 = _mm256_setzero_si256();
  __m256i kd = _mm256_setzero_si256();
  __m256i k1 = _mm256_setzero_si256();
  __m256i index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i eight = _mm256_set1_epi32(8);
  std::size_t t = 0;
  for (; t + 8 <= n; t += 8) {
    const __m256i vb = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + t));
    const __m256i vr = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(r + t));
    const __m256i s0 = scan8(vb, k0);
    const __m256i sd = scan8(_mm256_mullo_epi32(vb, index), kd);
    const __m256i s1 = scan8(vr, k1);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(c0 + t + 1), s0);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(d0 + t + 1), sd);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(c1 + t + 1), s1);
    k0 = _mm256_permutevar8x32_epi32(s0, last);
    kd = _mm256_permutevar8x32_epi32(sd, last);
    k1 = _mm256_permutevar8x32_epi32(s1, last);
    index = _mm256_add_epi32(index, eight);
  }
  prefix_sums_scalar(b, r, n, c0, d0, c1, t, c0[t], d0[t], c1[t]);
}

/// Inclusive prefix sum of sixteen uint32 lanes, plus carry: four shifts by
/// 1, 2, 4 and 8 lanes across the whole register.
__attribute__((target("avx512f"), always_inline)) inline __m512i scan16(__m512i x, __m512i carry) noexcept {
  const __m512i zero = _mm512_setzero_si512();
  x = _mm512_add_epi32(x, _mm512_maskz_alignr_epi32(all16, x, zero, 15));
  x = _mm512_add_epi32(x, _mm512_maskz_alignr_epi32(all16, x, zero, 14));
  x = _mm512_add_epi32(x, _mm512_maskz_alignr_epi32(all16, x, zero, 12));
  x = _mm512_add_epi32(x, _mm512_maskz_alignr_epi32(all16, x, zero, 8));
  return _mm512_add_epi32(x, carry);
}

/// prefix_sums_avx2() sixteen sums at a time.
__attribute__((target("avx512f"))) inline void prefix_sums_avx512(const std::uint32_t* HAPTICFIELD_RESTRICT b,
                                                                  const std::uint32_t* HAPTICFIELD_RESTRICT r,
                                                                  std::size_t n, std::uint32_t* HAPTICFIELD_RESTRICT c0,
                                                                  std::uint32_t* HAPTICFIELD_RESTRICT d0,
                                                                  std::uint32_t* HAPTICFIELD_RESTRICT c1) noexcept {
  const __m512i last = _mm512_set1_epi32(15);
  __m512i k0 = _mm512_setzero_si512();
  __m512i kd = _mm512_setzero_si512();
  __m512i k1 = _mm512_setzero_si512();
  __m512i index = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512i sixteen = _mm512_set1_epi32(16);
  std::size_t t = 0;
  for (; t + 16 <= n; t += 16) {
    const __m512i vb = _mm512_loadu_si512(b + t);
    const __m512i vr = _mm512_loadu_si512(r + t);
    const __m512i s0 = scan16(vb, k0);
    const __m512i sd = scan16(_mm512_mullo_epi32(vb, index), kd);
    const __m512i s1 = scan16(vr, k1);
    _mm512_storeu_si512(c0 + t + 1, s0);
    _mm512_storeu_si512(d0 + t + 1, sd);
    _mm512_storeu_si512(c1 + t + 1, s1);
    k0 = _mm512_maskz_permutexvar_epi32(all16, last, s0);
    kd = _mm512_maskz_permutexvar_epi32(all16, last, sd);
    k1 = _mm512_maskz_permutexvar_epi32(all16, last, s1);
    index = _mm512_add_epi32(index, sixteen);
  }
  prefix_sums_scalar(b, r, n, c0, d0, c1, t, c0[t], d0[t], c1[t]);
}
#endif

/// One output row of the integer route: for x in [0, n_out), the window
/// t in [x, x + 2h] of the prefix sums gives box = dc0, fx = dd0 - (x + h) box,
/// fy = dc1, each an exact int32 scaled to float with one rounding.
HAPTICFIELD_ALWAYS_INLINE inline void integer_output_scalar(const std::uint32_t* HAPTICFIELD_RESTRICT c0,
                                                            const std::uint32_t* HAPTICFIELD_RESTRICT d0,
                                                            const std::uint32_t* HAPTICFIELD_RESTRICT c1, int h,
                                                            int from, int n_out, double scale,
                                                            float* HAPTICFIELD_RESTRICT fx,
                                                            float* HAPTICFIELD_RESTRICT fy) noexcept {
  using U = std::uint32_t;
  const int width = 2 * h + 1;
  for (int x = from; x < n_out; ++x) {
    const U box = c0[x + width] - c0[x];
    const U mx = (d0[x + width] - d0[x]) - static_cast<U>(x + h) * box;  // sum of (t - centre) V0(t)
    const U my = c1[x + width] - c1[x];
    fx[x] = MapArithmetic<U>::out(mx, scale);
    fy[x] = MapArithmetic<U>::out(my, scale);
  }
}

#if HAPTICFIELD_X86_DISPATCH
/// Eight uint32 from memory, unaligned.
__attribute__((target("avx2"), always_inline)) inline __m256i load8(const std::uint32_t* p) noexcept {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

/// Eight exact int32 forces to float, through double (one rounding).
__attribute__((target("avx2"), always_inline)) inline __m256 scale8(__m256i v, __m256d scale) noexcept {
  const __m128 lo = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_cvtepi32_pd(_mm256_castsi256_si128(v)), scale));
  const __m128 hi = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_cvtepi32_pd(_mm256_extracti128_si256(v, 1)), scale));
  return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}

/// integer_output_scalar() eight pixels at a time. Where the rows allow,
/// the planes are written with non-temporal stores: the map is larger than
/// the caches and is not read back here, so this saves reading every
/// output line before writing it. The caller issues the store fence.
__attribute__((target("avx2"))) inline void integer_output_avx2(const std::uint32_t* HAPTICFIELD_RESTRICT c0,
                                                                const std::uint32_t* HAPTICFIELD_RESTRICT d0,
                                                                const std::uint32_t* HAPTICFIELD_RESTRICT c1, int h,
                                                                int n_out, double scale, float* HAPTICFIELD_RESTRICT fx,
                                                                float* HAPTICFIELD_RESTRICT fy,
                                                                const double* next = nullptr, int n_next = 0) noexcept {
  const int width = 2 * h + 1;
  // Head: up to the first x where both rows are 32-byte aligned (they are
  // equally misaligned when the planes were allocated alike).
  int x = 0;
  const bool same_phase = ((reinterpret_cast<std::uintptr_t>(fx) ^ reinterpret_cast<std::uintptr_t>(fy)) & 31u) == 0;
  if (same_phase)
    while (x < n_out && (reinterpret_cast<std::uintptr_t>(fx + x) & 31u) != 0)
      ++x;
  else
    x = n_out;  // unusual layout: scalar throughout
  integer_output_scalar(c0, d0, c1, h, 0, x, scale, fx, fy);
  const __m256d vs = _mm256_set1_pd(scale);
  __m256i centre = _mm256_add_epi32(_mm256_set1_epi32(x + h), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  const __m256i eight = _mm256_set1_epi32(8);
  for (; x + 8 <= n_out; x += 8) {
    const __m256i box = _mm256_sub_epi32(load8(c0 + x + width), load8(c0 + x));
    const __m256i mx =
        _mm256_sub_epi32(_mm256_sub_epi32(load8(d0 + x + width), load8(d0 + x)), _mm256_mullo_epi32(centre, box));
    const __m256i my = _mm256_sub_epi32(load8(c1 + x + width), load8(c1 + x));
    _mm256_stream_ps(fx + x, scale8(mx, vs));
    _mm256_stream_ps(fy + x, scale8(my, vs));
    if (x < n_next) _mm_prefetch(reinterpret_cast<const char*>(next + x), _MM_HINT_T0);
    centre = _mm256_add_epi32(centre, eight);
  }
  integer_output_scalar(c0, d0, c1, h, x, n_out, scale, fx, fy);
}

/// Sixteen exact int32 forces to float, through double (one rounding).
__attribute__((target("avx512f"), always_inline)) inline __m512 scale16(__m512i v, __m512d scale) noexcept {
  const __m256 lo = _mm512_maskz_cvtpd_ps(
      all8, _mm512_mul_pd(_mm512_maskz_cvtepi32_pd(all8, _mm512_maskz_extracti64x4_epi64(all8, v, 0)), scale));
  const __m256 hi = _mm512_maskz_cvtpd_ps(
      all8, _mm512_mul_pd(_mm512_maskz_cvtepi32_pd(all8, _mm512_maskz_extracti64x4_epi64(all8, v, 1)), scale));
  return _mm512_castpd_ps(
      _mm512_maskz_insertf64x4(all8, _mm512_castpd256_pd512(_mm256_castps_pd(lo)), _mm256_castps_pd(hi), 1));
}

#endif

#if HAPTICFIELD_X86_DISPATCH
/// One output row of the integer route straight from the column sums, with
/// no prefix tables: along the row the window's box B, first moment R (fx)
/// and the box F of V1 (fy) change by
///   B(x) - B(x-1) = V0(x+2h) - V0(x-1),
///   R(x) - R(x-1) = h V0(x-1) + (h+1) V0(x+2h) - B(x),
///   F(x) - F(x-1) = V1(x+2h) - V1(x-1),
/// so B, R and F are running sums of those differences, sixteen at a time
/// by scan16(). Same integers (modulo 2^32) as the prefix tables, hence the
/// same planes. Non-temporal 64-byte stores where fx and fy are equally
/// aligned (ordinary ones otherwise); meanwhile it prefetches `next`
/// (n_next levels: the picture row the band converts next), one cache line
/// per 8 levels.
///
/// Given q_in and q_out, the column sums are first slid down one row on the
/// way (q_in enters, q_out leaves, as in prewitt_band_integer()), `ahead`
/// columns before the row pass reads them: each column is read and written
/// twice while it is in the first-level cache, and the stores have left
/// the store buffer before the (unaligned) loads that read them back.
__attribute__((target("avx512f"))) inline void integer_row_avx512(
    std::uint32_t* v0, std::uint32_t* v1, int h, int n_out, double scale, float* HAPTICFIELD_RESTRICT fx,
    float* HAPTICFIELD_RESTRICT fy, const double* next, int n_next,
    const std::uint32_t* HAPTICFIELD_RESTRICT q_in = nullptr,
    const std::uint32_t* HAPTICFIELD_RESTRICT q_out = nullptr) noexcept {
  using U = std::uint32_t;
  using A = MapArithmetic<U>;
  const int span = 2 * h;
  const int n = n_out + span;  // columns of the column sums
  const U hh = static_cast<U>(h);
  constexpr int ahead = 128;
  int slid = q_in == nullptr ? n : 0;  // columns [0, slid) are slid
  const auto slide_to = [&](int end) HAPTICFIELD_ALWAYS_INLINE {
    end = std::min(end, n);
    for (int t = slid; t < end; ++t) {
      const U box = v0[t] + (q_in[t] - q_out[t]);
      v0[t] = box;
      v1[t] += hh * (q_out[t] + q_in[t]) + q_in[t] - box;
    }
    slid = std::max(slid, end);
  };
  slide_to(span + 16 + ahead);
  U b = 0;
  U r = 0;
  U f = 0;
  for (int j = 0; j <= span; ++j) {
    b += v0[j];
    r += static_cast<U>(j - h) * v0[j];
    f += v1[j];
  }
  fx[0] = A::out(r, scale);
  fy[0] = A::out(f, scale);
  const auto step = [&](int x) HAPTICFIELD_ALWAYS_INLINE {
    const U in = v0[x + span];
    const U out = v0[x - 1];
    b += in - out;
    r += hh * (out + in) + in - b;
    f += v1[x + span] - v1[x - 1];
    fx[x] = A::out(r, scale);
    fy[x] = A::out(f, scale);
  };
  int x = 1;
  const bool same_phase = ((reinterpret_cast<std::uintptr_t>(fx) ^ reinterpret_cast<std::uintptr_t>(fy)) & 63u) == 0;
  if (same_phase)
    for (; x < n_out && (reinterpret_cast<std::uintptr_t>(fx + x) & 63u) != 0; ++x)
      step(x);
  const __m512i last = _mm512_set1_epi32(15);
  const __m512i vh = _mm512_set1_epi32(h);
  const __m512d vs = _mm512_set1_pd(scale);
  __m512i kb = _mm512_set1_epi32(static_cast<int>(b));
  __m512i kr = _mm512_set1_epi32(static_cast<int>(r));
  __m512i kf = _mm512_set1_epi32(static_cast<int>(f));
  const int vector_end = x + (n_out - x) / 16 * 16;
  slide_to(x + span + ahead);
  for (; x < vector_end; x += 16) {
    if (slid < n) {  // slide columns [x + span + ahead, + 16)
      const int t = slid;
      if (t + 16 <= n) {
        const __m512i qi = _mm512_loadu_si512(q_in + t);
        const __m512i qo = _mm512_loadu_si512(q_out + t);
        const __m512i box = _mm512_add_epi32(_mm512_loadu_si512(v0 + t), _mm512_sub_epi32(qi, qo));
        _mm512_storeu_si512(v0 + t, box);
        _mm512_storeu_si512(
            v1 + t, _mm512_add_epi32(
                        _mm512_loadu_si512(v1 + t),
                        _mm512_sub_epi32(_mm512_add_epi32(_mm512_mullo_epi32(vh, _mm512_add_epi32(qo, qi)), qi), box)));
        slid = t + 16;
      } else {
        slide_to(n);
      }
    }
    const __m512i in0 = _mm512_loadu_si512(v0 + x + span);
    const __m512i out0 = _mm512_loadu_si512(v0 + x - 1);
    const __m512i in1 = _mm512_loadu_si512(v1 + x + span);
    const __m512i out1 = _mm512_loadu_si512(v1 + x - 1);
    const __m512i vb = scan16(_mm512_sub_epi32(in0, out0), kb);
    const __m512i dr = _mm512_sub_epi32(_mm512_add_epi32(_mm512_mullo_epi32(vh, _mm512_add_epi32(out0, in0)), in0), vb);
    const __m512i vr = scan16(dr, kr);
    const __m512i vf = scan16(_mm512_sub_epi32(in1, out1), kf);
    if (same_phase) {
      _mm512_stream_ps(fx + x, scale16(vr, vs));
      _mm512_stream_ps(fy + x, scale16(vf, vs));
    } else {  // unusual layout: the planes cannot both be 64-byte aligned
      _mm512_storeu_ps(fx + x, scale16(vr, vs));
      _mm512_storeu_ps(fy + x, scale16(vf, vs));
    }
    if (x < n_next) {
      _mm_prefetch(reinterpret_cast<const char*>(next + x), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(next + x + 8), _MM_HINT_T0);
    }
    kb = _mm512_maskz_permutexvar_epi32(all16, last, vb);
    kr = _mm512_maskz_permutexvar_epi32(all16, last, vr);
    kf = _mm512_maskz_permutexvar_epi32(all16, last, vf);
  }
  if (x < n_out && x > 1) {  // the running sums from the last vector
    alignas(64) U lanes[16];
    _mm512_store_si512(lanes, kb);
    b = lanes[0];
    _mm512_store_si512(lanes, kr);
    r = lanes[0];
    _mm512_store_si512(lanes, kf);
    f = lanes[0];
  }
  slide_to(n);
  for (; x < n_out; ++x)
    step(x);
}
#endif

/// The integer route for one band: vertical first, then prefix sums along
/// the row. Down the columns, V0 = sum of Q over the window's rows (running,
/// vectorised across the row) and V1 = sum of i Q(y + i) (a running ramp).
/// Along the row, prefix sums C0, D0 (of t V0(t)) and C1 give, for a window
/// [x - h, x + h], box = dC0, fx = dD0 - x box and fy = dC1: one dependent
/// add per table and element, the rest vectorised. All modulo 2^32 (see
/// MapArithmetic<std::uint32_t>). Returns false when a gray level was not
/// an integer in the fixed point d.
template <MapSimd Simd>
HAPTICFIELD_ALWAYS_INLINE inline bool prewitt_band_integer(const GrayImage& gray, int h, Border border, double fade_px,
                                                           double scale, double d, int lo, int x_hi, int y_hi,
                                                           int y_first, int y_last, ForceMap& map) {
  using U = std::uint32_t;
  using A = MapArithmetic<U>;
  const int height = gray.height();
  const int n_out = x_hi - lo + 1;
  const int n_in = n_out + 2 * h;
  const std::size_t n = static_cast<std::size_t>(n_in);
  const int ring = 2 * h + 2;  // rows y - h - 1 .. y + h
  std::vector<U> q(static_cast<std::size_t>(ring) * n);
  const auto q_row = [&](int r) HAPTICFIELD_ALWAYS_INLINE {
    return &q[static_cast<std::size_t>(((r % ring) + ring) % ring) * n];
  };
  std::uint64_t bad = 0;  // non-zero once a scaled gray level was not an integer
  const auto convert = [&](int r) HAPTICFIELD_ALWAYS_INLINE {
    bad |= inverted_padded_row<U, Simd>(gray, border_index(r, height, border), lo - h, n_in, border, q_row(r), 1, d);
  };
  std::vector<U> v0(n, 0u);
  std::vector<U> v1(n, 0u);
  for (int i = -h; i <= h; ++i) {
    convert(y_first + i);
    const U* HAPTICFIELD_RESTRICT row = q_row(y_first + i);
    U* HAPTICFIELD_RESTRICT b = v0.data();
    U* HAPTICFIELD_RESTRICT r = v1.data();
    const U wi = A::weight(i);
    for (std::size_t t = 0; t < n; ++t) {
      b[t] += row[t];
      r[t] += wi * row[t];
    }
  }
  std::vector<U> c0(n + 1, 0u);
  std::vector<U> d0(n + 1, 0u);
  std::vector<U> c1(n + 1, 0u);
  const U hh = A::weight(h);
  const int width = 2 * h + 1;
  for (int y = y_first; y <= y_last; ++y) {
    // AVX-512 slides the column sums inside the row pass
    const bool slide_in_row = Simd == MapSimd::avx512 && border != Border::fade;
    if (y > y_first) convert(y + h);  // row y - 1 - h leaves the window, row y + h enters
    if (y > y_first && !slide_in_row) {
      const U* HAPTICFIELD_RESTRICT in = q_row(y + h);
      const U* HAPTICFIELD_RESTRICT out = q_row(y - 1 - h);
      U* HAPTICFIELD_RESTRICT b = v0.data();
      U* HAPTICFIELD_RESTRICT r = v1.data();
      for (std::size_t t = 0; t < n; ++t) {
        const U box = b[t] + (in[t] - out[t]);
        b[t] = box;
        r[t] += hh * (out[t] + in[t]) + in[t] - box;  // h out + (h + 1) in - box, one multiply
      }
    }
#if HAPTICFIELD_X86_DISPATCH
    if constexpr (Simd == MapSimd::avx512) {
      if (border != Border::fade) {  // straight from the column sums
        integer_row_avx512(v0.data(), v1.data(), h, n_out, scale, &map.fx[map.index(lo, y)], &map.fy[map.index(lo, y)],
                           y < y_last ? gray.row(border_index(y + 1 + h, height, border)) : nullptr,
                           y < y_last ? gray.width() : 0, y > y_first ? q_row(y + h) : nullptr,
                           y > y_first ? q_row(y - 1 - h) : nullptr);
        continue;
      }
      prefix_sums_avx512(v0.data(), v1.data(), n, c0.data(), d0.data(), c1.data());
    } else if constexpr (Simd == MapSimd::avx2)
      prefix_sums_avx2(v0.data(), v1.data(), n, c0.data(), d0.data(), c1.data());
    else
      prefix_sums_scalar(v0.data(), v1.data(), n, c0.data(), d0.data(), c1.data());
#else
    prefix_sums_scalar(v0.data(), v1.data(), n, c0.data(), d0.data(), c1.data());
#endif
    float* HAPTICFIELD_RESTRICT fx = &map.fx[map.index(lo, y)];
    float* HAPTICFIELD_RESTRICT fy = &map.fy[map.index(lo, y)];
    const U* HAPTICFIELD_RESTRICT pc0 = c0.data();
    const U* HAPTICFIELD_RESTRICT pd0 = d0.data();
    const U* HAPTICFIELD_RESTRICT pc1 = c1.data();
    if (border != Border::fade) {
#if HAPTICFIELD_X86_DISPATCH
      const double* next = y < y_last ? gray.row(border_index(y + 1 + h, height, border)) : nullptr;
      const int n_next = y < y_last ? gray.width() : 0;
      if constexpr (Simd != MapSimd::baseline)  // AVX-512 rows seldom come here (see above)
        integer_output_avx2(pc0, pd0, pc1, h, n_out, scale, fx, fy, next, n_next);
      else
        integer_output_scalar(pc0, pd0, pc1, h, 0, n_out, scale, fx, fy);
#else
      integer_output_scalar(pc0, pd0, pc1, h, 0, n_out, scale, fx, fy);
#endif
    } else {
      const double row_inside = std::min(y - lo, y_hi - y);
      for (int x = 0; x < n_out; ++x) {
        const U box = pc0[x + width] - pc0[x];
        const U mx = (pd0[x + width] - pd0[x]) - static_cast<U>(x + h) * box;
        const U my = pc1[x + width] - pc1[x];
        const double inside = std::min(row_inside, static_cast<double>(std::min(x, n_out - 1 - x)));
        const double g = scale * std::clamp(inside / fade_px, 0.0, 1.0);
        fx[x] = A::out(mx, g);
        fy[x] = A::out(my, g);
      }
    }
  }
#if HAPTICFIELD_X86_DISPATCH
  if constexpr (Simd != MapSimd::baseline) _mm_sfence();  // the non-temporal stores are visible before the band returns
#endif
  return bad == 0;
}

/// Arguments of one band of the Prewitt map.
struct PrewittBand {
  const GrayImage* gray;
  int h;
  Border border;
  double fade_px;
  double scale;  ///< [1 / (gray level D)] to the normalised force
  double d;      ///< fixed-point scale of integer arithmetic; 0 for double
  int lo, x_hi, y_hi, y_first, y_last;
  ForceMap* map;
};

/// Returns false when the integer arithmetic met a non-integer level.
template <MapSimd Simd>
HAPTICFIELD_ALWAYS_INLINE inline bool prewitt_band_any(const PrewittBand& a) {
  if (a.d > 0.0)
    return prewitt_band_integer<Simd>(*a.gray, a.h, a.border, a.fade_px, a.scale, a.d, a.lo, a.x_hi, a.y_hi, a.y_first,
                                      a.y_last, *a.map);
  return prewitt_band_in<double>(*a.gray, a.h, a.border, a.fade_px, a.scale, 1.0, a.lo, a.x_hi, a.y_hi, a.y_first,
                                 a.y_last, *a.map);
}

/// The band for baseline x86-64 (or any other target).
inline bool prewitt_band_baseline(const PrewittBand& a) {
  return prewitt_band_any<MapSimd::baseline>(a);
}

#if HAPTICFIELD_X86_DISPATCH
/// The same code compiled for AVX2 (8 integer or 4 double lanes), chosen at
/// run time when the CPU has it.
__attribute__((target("avx2"))) inline bool prewitt_band_avx2(const PrewittBand& a) {
  return prewitt_band_any<MapSimd::avx2>(a);
}

/// The integer route again for AVX-512F (16 lanes, 512-bit loops in the
/// compiler's own vectorisation too), with no multiply-add contraction
/// (see HAPTICFIELD_AVX512_EXACT).
/// The double route stays on AVX2, whose planes it reproduces to the bit.
HAPTICFIELD_AVX512_EXACT_WIDE inline bool prewitt_band_avx512(const PrewittBand& a) {
  return prewitt_band_integer<MapSimd::avx512>(*a.gray, a.h, a.border, a.fade_px, a.scale, a.d, a.lo, a.x_hi, a.y_hi,
                                               a.y_first, a.y_last, *a.map);
}
#endif

/// True when the CPU runs prewitt_band_avx2().
[[nodiscard]] inline bool has_avx2() noexcept {
#if HAPTICFIELD_X86_DISPATCH
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

/// True when the CPU runs prewitt_band_avx512().
[[nodiscard]] inline bool has_avx512() noexcept {
#if HAPTICFIELD_X86_DISPATCH
  return __builtin_cpu_supports("avx512f");
#else
  return false;
#endif
}

/// The widest route the CPU runs (tests pick one to compare the routes).
[[nodiscard]] inline MapSimd best_map_simd() noexcept {
  if (has_avx512()) return MapSimd::avx512;
  if (has_avx2()) return MapSimd::avx2;
  return MapSimd::baseline;
}

inline bool prewitt_band(const PrewittBand& a, MapSimd simd) {
#if HAPTICFIELD_X86_DISPATCH
  if (simd == MapSimd::avx512 && a.d > 0.0 && has_avx512()) return prewitt_band_avx512(a);
  if (simd != MapSimd::baseline && has_avx2()) return prewitt_band_avx2(a);
#else
  (void)simd;
#endif
  return prewitt_band_baseline(a);
}

}  // namespace detail

namespace detail {

/// prewitt_force_map() on the instruction set `simd` (or the widest below
/// it that the CPU runs); every route gives the same planes.
inline void prewitt_force_map_on(MapSimd simd, const GrayImage& gray, int size, Border border, ForceMap& map,
                                 double fade_px, int threads) {
  validate_mask_size(MaskKind::prewitt, size);
  validate_image_for_mask(gray, size);
  if (!std::isfinite(fade_px) || fade_px <= 0.0)
    throw std::invalid_argument("prewitt_force_map: fade width must be finite and positive [px]");
  if (threads < 1) throw std::invalid_argument("prewitt_force_map: threads must be at least 1");
  const int h = size / 2;
  const int width = gray.width();
  const int height = gray.height();
  const double scale = 1.0 / Mask<>::prewitt(size).step_response();
  // Exact 32-bit integer sums when the picture's levels are integers in a
  // small fixed point (see integral_kernel.hpp) and the force fits 31 bits.
  // Each band checks every level as it converts it; if one is not an
  // integer after all, the map is computed again in double.
  const double guess = detail::guess_fixed_point_scale(gray);
  const bool integer = guess > 0.0 && guess * gray_full_scale * size * h * (h + 1.0) < 2147483648.0;

  map.width = width;
  map.height = height;
  map.fx.resize(static_cast<std::size_t>(width) * height);
  map.fy.resize(map.fx.size());

  // Output pixels [lo, x_hi] x [lo, y_hi]; they read rows and columns h beyond.
  const bool full_mask = needs_full_mask(border);
  const int lo = full_mask ? h : 0;
  const int x_hi = full_mask ? width - 1 - h : width - 1;
  const int y_hi = full_mask ? height - 1 - h : height - 1;

  constexpr int min_band_rows = 64;
  const int rows = y_hi - lo + 1;
  const int bands = std::max(1, std::min(threads, rows / min_band_rows));
  const auto run = [&](double d) {
    std::vector<std::thread> workers;
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(bands));
    std::vector<char> exact(static_cast<std::size_t>(bands), 1);
    for (int band = bands - 1; band >= 0; --band) {
      const int first = lo + static_cast<int>(static_cast<long>(rows) * band / bands);
      const int last = lo + static_cast<int>(static_cast<long>(rows) * (band + 1) / bands) - 1;
      auto work = [&, band, first, last] {
        try {
          exact[static_cast<std::size_t>(band)] = detail::prewitt_band(
              {&gray, h, border, fade_px, d > 0.0 ? scale / d : scale, d, lo, x_hi, y_hi, first, last, &map}, simd);
        } catch (...) {
          errors[static_cast<std::size_t>(band)] = std::current_exception();
        }
      };
      if (band == 0)
        work();
      else
        workers.emplace_back(work);
    }
    for (std::thread& w : workers)
      w.join();
    for (const std::exception_ptr& e : errors)
      if (e) std::rethrow_exception(e);
    return std::all_of(exact.begin(), exact.end(), [](char ok) { return ok != 0; });
  };
  if (!run(integer ? guess : 0.0)) (void)run(0.0);
  if (full_mask) detail::extend_outside(map, lo, x_hi, lo, y_hi, fade_px);
}
}  // namespace detail

/// The Prewitt map of a gray picture in O(1) per pixel whatever the mask
/// size, written into `map` (its buffers are reused when already large
/// enough). Along each border-extended row, running sums give the row's box
/// sum H0 and first moment H1 under the mask, four rows at a time so their
/// dependency chains run side by side; down the columns, running sums of H1
/// give fx and a running ramp over H0 gives fy, vectorised across the row.
/// Rows live in a small ring buffer, so memory traffic stays near one read
/// of the picture and one write of the map. `threads` > 1 splits the rows
/// into bands computed in parallel (setup work, never a servo tick). The
/// widest route the CPU runs is taken (baseline, AVX2, AVX-512F for exact
/// integers); all give the same planes. Equals
/// force_map() of TangibleImage{prewitt, size, border} to float rounding,
/// the edge fades of ImageForce included.
/// @throws std::invalid_argument as TangibleImage, or for threads < 1.
inline void prewitt_force_map(const GrayImage& gray, int size, Border border, ForceMap& map,
                              double fade_px = default_fade_px, int threads = 1) {
  detail::prewitt_force_map_on(detail::best_map_simd(), gray, size, border, map, fade_px, threads);
}

/// The Prewitt map in a new ForceMap; see the overload that writes into one.
[[nodiscard]] inline ForceMap prewitt_force_map(const GrayImage& gray, int size, Border border,
                                                double fade_px = default_fade_px, int threads = 1) {
  ForceMap map;
  prewitt_force_map(gray, size, border, map, fade_px, threads);
  return map;
}

}  // namespace hapticfield
