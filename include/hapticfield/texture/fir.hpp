#pragma once
/// @file fir.hpp
/// Linear-phase FIR filters designed by the windowed-sinc method (Oppenheim
/// & Schafer, "Discrete-Time Signal Processing", section 7.5) for spectral
/// shaping of texture noise (Fritz & Barner 1996, section 5.2). The taps are
/// symmetric, so the group delay is (Taps - 1) / 2 samples at every frequency.

#include <array>
#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>
#include <stdexcept>

#include "hapticfield/texture/iir.hpp"

namespace hapticfield::texture {

/// Window applied to the ideal (sinc) impulse response.
enum class Window {
  rectangular,  ///< no taper (sharpest transition, -21 dB stopband)
  hamming,      ///< 0.54 - 0.46 cos (-53 dB stopband)
  blackman,     ///< 0.42 - 0.5 cos + 0.08 cos 2x (-74 dB stopband)
};

/// FIR filter with Taps coefficients (fixed at compile time).
template <std::size_t Taps>
requires(Taps >= 1) class FirFilter {
 public:
  FirFilter() { taps_[0] = 1.0; }
  /// Arbitrary taps h[0..Taps-1].
  /// @throws std::invalid_argument for a non-finite tap.
  explicit FirFilter(const std::array<double, Taps>& taps) : taps_(taps) {
    for (double t : taps)
      if (!std::isfinite(t)) throw std::invalid_argument("FirFilter: taps must be finite");
  }

  /// Low-pass, DC gain 1.
  /// @throws std::invalid_argument unless 0 < cutoff < fs / 2.
  [[nodiscard]] static FirFilter low_pass(double cutoff, double fs, Window w = Window::hamming) {
    detail::require_sample_rate(fs, "FirFilter");
    detail::require_below_nyquist(cutoff, fs, "FirFilter", "cutoff");
    FirFilter f(ideal_low_pass(cutoff / fs, w));
    double sum = 0.0;
    for (double t : f.taps_)
      sum += t;
    for (double& t : f.taps_)
      t /= sum;
    return f;
  }
  /// High-pass by spectral inversion (delta - low-pass), gain 1 at Nyquist.
  /// Needs an odd tap count (an even, symmetric FIR is zero at Nyquist).
  /// @throws std::invalid_argument for an even Taps or a bad cutoff.
  [[nodiscard]] static FirFilter high_pass(double cutoff, double fs, Window w = Window::hamming) {
    if (Taps % 2 == 0) throw std::invalid_argument("FirFilter: a high-pass needs an odd number of taps");
    FirFilter f = low_pass(cutoff, fs, w);
    for (double& t : f.taps_)
      t = -t;
    f.taps_[(Taps - 1) / 2] += 1.0;
    return f;
  }
  /// Band-pass: difference of two windowed sincs, gain 1 at the band centre.
  /// @throws std::invalid_argument unless 0 < low < high < fs / 2.
  [[nodiscard]] static FirFilter band_pass(double low, double high, double fs, Window w = Window::hamming) {
    detail::require_sample_rate(fs, "FirFilter");
    detail::require_below_nyquist(low, fs, "FirFilter", "low edge");
    detail::require_below_nyquist(high, fs, "FirFilter", "high edge");
    if (!(high > low)) throw std::invalid_argument("FirFilter: band-pass high edge must exceed low edge [Hz]");
    const auto hi = ideal_low_pass(high / fs, w);
    const auto lo = ideal_low_pass(low / fs, w);
    std::array<double, Taps> taps{};
    for (std::size_t i = 0; i < Taps; ++i)
      taps[i] = hi[i] - lo[i];
    FirFilter f(taps);
    const double g = std::abs(f.response((low + high) / 2.0, fs));
    if (g > 0.0)
      for (double& t : f.taps_)
        t /= g;
    return f;
  }

  [[nodiscard]] double process(double x) noexcept {
    // Each input is stored twice (at pos and pos + Taps) so that
    // history_[pos + i] = x[n - i] for i = 0..Taps-1 without wrapping.
    pos_ = pos_ == 0 ? Taps - 1 : pos_ - 1;
    history_[pos_] = x;
    history_[pos_ + Taps] = x;
    double y = 0.0;
    for (std::size_t i = 0; i < Taps; ++i)
      y += taps_[i] * history_[pos_ + i];
    return y;
  }
  void reset() noexcept {
    history_.fill(0.0);
    pos_ = 0;
  }

  [[nodiscard]] const std::array<double, Taps>& taps() const noexcept { return taps_; }
  /// Group delay of a symmetric (linear-phase) design [samples].
  [[nodiscard]] static constexpr double group_delay() noexcept { return (Taps - 1) / 2.0; }
  [[nodiscard]] std::complex<double> response(double f, double fs) const noexcept {
    std::complex<double> h{0.0, 0.0};
    for (std::size_t n = 0; n < Taps; ++n)
      h += taps_[n] * std::polar(1.0, -2.0 * std::numbers::pi * f / fs * static_cast<double>(n));
    return h;
  }

 private:
  static std::array<double, Taps> ideal_low_pass(double fc_norm, Window w) {
    std::array<double, Taps> h{};
    const double m = (Taps - 1) / 2.0;
    for (std::size_t n = 0; n < Taps; ++n) {
      const double k = static_cast<double>(n) - m;
      const double sinc =
          k == 0.0 ? 2.0 * fc_norm : std::sin(2.0 * std::numbers::pi * fc_norm * k) / (std::numbers::pi * k);
      const double x = Taps == 1 ? 0.0 : 2.0 * std::numbers::pi * static_cast<double>(n) / (Taps - 1);
      double win = 1.0;
      if (w == Window::hamming) win = 0.54 - 0.46 * std::cos(x);
      if (w == Window::blackman) win = 0.42 - 0.5 * std::cos(x) + 0.08 * std::cos(2.0 * x);
      h[n] = sinc * win;
    }
    return h;
  }

  std::array<double, Taps> taps_{};
  std::array<double, 2 * Taps> history_{};
  std::size_t pos_{0};
};

}  // namespace hapticfield::texture
