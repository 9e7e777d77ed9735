#pragma once
/// @file force_map.hpp
/// Force maps: the normalised force at every pixel centre as two float
/// planes, from any kernel, plus an O(1)-per-pixel Prewitt map built from
/// running sums that matches the per-pixel kernels to float rounding.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

#include <glm/vec2.hpp>

#include "hapticfield/core/restrict.hpp"
#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/direct_kernel.hpp"
#include "hapticfield/kernels/image_force.hpp"
#include "hapticfield/kernels/mask.hpp"

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
    for (std::size_t i = 0; i < fx.size(); ++i) m = std::max(m, std::hypot(double(fx[i]), double(fy[i])));
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

/// Inverted picture row `row`, columns c_first .. c_first + n - 1, extended
/// past the picture's sides by the border policy, into out[q * stride].
inline void inverted_padded_row(const GrayImage& gray, int row, int c_first, int n, Border border, double* out,
                                int stride) {
  const double* src = gray.row(row);
  const int w = gray.width();
  const int interior_begin = std::clamp(-c_first, 0, n);
  const int interior_end = std::clamp(w - c_first, interior_begin, n);
  for (int q = 0; q < interior_begin; ++q)
    out[q * stride] = gray_full_scale - src[border_index(c_first + q, w, border)];
  for (int q = interior_begin; q < interior_end; ++q) out[q * stride] = gray_full_scale - src[c_first + q];
  for (int q = interior_end; q < n; ++q) out[q * stride] = gray_full_scale - src[border_index(c_first + q, w, border)];
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
inline void slide_columns(double* HAPTICFIELD_RESTRICT box, double* HAPTICFIELD_RESTRICT ramp,
                          double* HAPTICFIELD_RESTRICT moment, const double* HAPTICFIELD_RESTRICT in0,
                          const double* HAPTICFIELD_RESTRICT out0, const double* HAPTICFIELD_RESTRICT in1,
                          const double* HAPTICFIELD_RESTRICT out1, int n, double h, float* HAPTICFIELD_RESTRICT fx,
                          float* HAPTICFIELD_RESTRICT fy, double scale) noexcept {
  if (fx == nullptr) {
    for (int x = 0; x < n; ++x) {
      const double b = box[x] + (in0[x] - out0[x]);
      box[x] = b;
      ramp[x] += h * out0[x] + (h + 1.0) * in0[x] - b;
      moment[x] += in1[x] - out1[x];
    }
    return;
  }
  for (int x = 0; x < n; ++x) {
    const double b = box[x] + (in0[x] - out0[x]);
    const double r = ramp[x] + (h * out0[x] + (h + 1.0) * in0[x] - b);
    const double m = moment[x] + (in1[x] - out1[x]);
    box[x] = b;
    ramp[x] = r;
    moment[x] = m;
    fx[x] = static_cast<float>(m * scale);
    fy[x] = static_cast<float>(r * scale);
  }
}

/// Output rows y_first .. y_last of the Prewitt map; the output region is
/// [lo, x_hi] x [lo, y_hi]. See prewitt_force_map().
inline void prewitt_band(const GrayImage& gray, int h, Border border, double fade_px, double scale, int lo, int x_hi,
                         int y_hi, int y_first, int y_last, ForceMap& map) {
  const int height = gray.height();
  const int n_out = x_hi - lo + 1;
  const int n_in = n_out + 2 * h;
  const int r_last = y_last + h;

  // Ring of horizontal results: rows y - h - 1 .. y + h + 3 are alive at once.
  constexpr int batch = 4;
  const int ring = 2 * h + 2 + batch;
  std::vector<double> h0(static_cast<std::size_t>(ring) * n_out);
  std::vector<double> h1(h0.size());
  const auto h0_row = [&](int r) { return &h0[static_cast<std::size_t>((r + ring * 4) % ring) * n_out]; };
  const auto h1_row = [&](int r) { return &h1[static_cast<std::size_t>((r + ring * 4) % ring) * n_out]; };

  // Horizontal pass for rows r .. r + k - 1 (k <= batch). The rows are
  // interleaved (column q of row b at q * batch + b) so the running sums of
  // the batch advance together in vector registers.
  std::vector<double> rows(static_cast<std::size_t>(batch) * n_in, 0.0);
  const auto horizontal = [&](int r, int k) {
    for (int b = 0; b < k; ++b)
      detail::inverted_padded_row(gray, detail::border_index(r + b, height, border), lo - h, n_in, border,
                                  &rows[b], batch);
    double s[batch] = {};
    double m1[batch] = {};
    for (int q = 0; q <= 2 * h; ++q)
      for (int b = 0; b < batch; ++b) {
        s[b] += rows[q * batch + b];
        m1[b] += (q - h) * rows[q * batch + b];
      }
    double* o0[batch] = {};
    double* o1[batch] = {};
    for (int b = 0; b < k; ++b) {
      o0[b] = h0_row(r + b);
      o1[b] = h1_row(r + b);
      o0[b][0] = s[b];
      o1[b][0] = m1[b];
    }
    const double hh = h;
    for (int i = 1; i < n_out; ++i) {
      const double* leaving = &rows[static_cast<std::size_t>(i - 1) * batch];
      const double* entering = &rows[static_cast<std::size_t>(i + 2 * h) * batch];
      for (int b = 0; b < batch; ++b) {
        s[b] += entering[b] - leaving[b];
        m1[b] += hh * leaving[b] + (hh + 1.0) * entering[b] - s[b];  // sum of j P(x + j), from x - 1
      }
      for (int b = 0; b < k; ++b) {
        o0[b][i] = s[b];
        o1[b][i] = m1[b];
      }
    }
  };
  int computed = y_first - h;  // next row without a horizontal result
  const auto ensure = [&](int r) {
    while (computed <= r) {
      const int k = std::min(batch, r_last - computed + 1);
      horizontal(computed, k);
      computed += k;
    }
  };

  // Vertical pass. box = sum of H0 over the window, ramp = sum of i H0(y + i)
  // (fy), moment = sum of H1(y + i) (fx).
  std::vector<double> box(static_cast<std::size_t>(n_out), 0.0);
  std::vector<double> ramp(static_cast<std::size_t>(n_out), 0.0);
  std::vector<double> moment(static_cast<std::size_t>(n_out), 0.0);
  ensure(y_first + h);
  for (int i = -h; i <= h; ++i) {
    const double* a = h0_row(y_first + i);
    const double* b = h1_row(y_first + i);
    for (int x = 0; x < n_out; ++x) {
      box[x] += a[x];
      ramp[x] += i * a[x];
      moment[x] += b[x];
    }
  }
  const double hh = h;
  for (int y = y_first; y <= y_last; ++y) {
    float* fx = &map.fx[map.index(lo, y)];
    float* fy = &map.fy[map.index(lo, y)];
    double* bx = box.data();
    double* rp = ramp.data();
    double* mo = moment.data();
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
        fx[x] = static_cast<float>(mo[x] * g);
        fy[x] = static_cast<float>(rp[x] * g);
      }
    } else {
      for (int x = 0; x < n_out; ++x) {
        fx[x] = static_cast<float>(mo[x] * scale);
        fy[x] = static_cast<float>(rp[x] * scale);
      }
    }
  }
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
/// into bands computed in parallel (setup work, never a servo tick). Equals
/// force_map() of TangibleImage{prewitt, size, border} to float rounding,
/// the edge fades of ImageForce included.
/// @throws std::invalid_argument as TangibleImage, or for threads < 1.
inline void prewitt_force_map(const GrayImage& gray, int size, Border border, ForceMap& map,
                              double fade_px = default_fade_px, int threads = 1) {
  validate_mask_size(MaskKind::prewitt, size);
  validate_image_for_mask(gray, size);
  if (!std::isfinite(fade_px) || fade_px <= 0.0)
    throw std::invalid_argument("prewitt_force_map: fade width must be finite and positive [px]");
  if (threads < 1) throw std::invalid_argument("prewitt_force_map: threads must be at least 1");
  const int h = size / 2;
  const int width = gray.width();
  const int height = gray.height();
  const double scale = 1.0 / Mask<>::prewitt(size).step_response();

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
  std::vector<std::thread> workers;
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(bands));
  for (int band = bands - 1; band >= 0; --band) {
    const int first = lo + static_cast<int>(static_cast<long>(rows) * band / bands);
    const int last = lo + static_cast<int>(static_cast<long>(rows) * (band + 1) / bands) - 1;
    auto work = [&, band, first, last] {
      try {
        detail::prewitt_band(gray, h, border, fade_px, scale, lo, x_hi, y_hi, first, last, map);
      } catch (...) {
        errors[static_cast<std::size_t>(band)] = std::current_exception();
      }
    };
    if (band == 0) work();
    else workers.emplace_back(work);
  }
  for (std::thread& w : workers) w.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  if (full_mask) detail::extend_outside(map, lo, x_hi, lo, y_hi, fade_px);
}

/// The Prewitt map in a new ForceMap; see the overload that writes into one.
[[nodiscard]] inline ForceMap prewitt_force_map(const GrayImage& gray, int size, Border border,
                                                double fade_px = default_fade_px, int threads = 1) {
  ForceMap map;
  prewitt_force_map(gray, size, border, map, fade_px, threads);
  return map;
}

}  // namespace hapticfield
