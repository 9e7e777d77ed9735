#pragma once
/// @file psd.hpp
/// Power spectral densities for checking synthesised vibration: Welch's
/// averaged periodogram of a signal (Welch, IEEE Trans. Audio
/// Electroacoustics 15(2), 1967) and the closed-form PSD of an ARMA model
/// driven by white noise, S(f) = var g^2 |B(e^jw)|^2 / |A(e^jw)|^2 / fs
/// (one-sided: doubled between 0 and Nyquist). Offline: allocates.

#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>
#include <span>
#include <stdexcept>
#include <vector>

#include "hapticfield/texture/fft.hpp"

namespace hapticfield::offline {

/// One-sided PSD on bins k = 0..segment/2, f_k = k fs / segment [Hz].
struct Spectrum {
  std::vector<double> frequency;  ///< [Hz]
  std::vector<double> density;    ///< [unit^2 / Hz]
  std::size_t segments{0};        ///< segments averaged (Welch)
};

/// Welch PSD: Hann-windowed segments of `segment` samples (a power of two),
/// overlapping by half, each mean-removed, periodograms averaged, scaled so
/// that the density integrates to the signal's variance.
/// @throws std::invalid_argument for a segment that is not a power of two
///         >= 8, or a signal shorter than one segment.
[[nodiscard]] inline Spectrum welch_psd(std::span<const double> x, double sample_rate, std::size_t segment) {
  if (segment < 8 || (segment & (segment - 1)) != 0)
    throw std::invalid_argument("welch_psd: segment must be a power of two >= 8");
  if (x.size() < segment) throw std::invalid_argument("welch_psd: signal shorter than one segment");
  std::vector<double> window(segment);
  double w2 = 0.0;
  for (std::size_t i = 0; i < segment; ++i) {
    window[i] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(segment));
    w2 += window[i] * window[i];
  }
  Spectrum s;
  const std::size_t bins = segment / 2 + 1;
  s.frequency.resize(bins);
  s.density.assign(bins, 0.0);
  for (std::size_t k = 0; k < bins; ++k)
    s.frequency[k] = static_cast<double>(k) * sample_rate / static_cast<double>(segment);
  std::vector<std::complex<double>> buf(segment);
  for (std::size_t start = 0; start + segment <= x.size(); start += segment / 2) {
    double mean = 0.0;
    for (std::size_t i = 0; i < segment; ++i)
      mean += x[start + i];
    mean /= static_cast<double>(segment);
    for (std::size_t i = 0; i < segment; ++i)
      buf[i] = (x[start + i] - mean) * window[i];
    texture::fft(buf);
    for (std::size_t k = 0; k < bins; ++k)
      s.density[k] += std::norm(buf[k]);
    ++s.segments;
  }
  for (std::size_t k = 0; k < bins; ++k) {
    const bool edge = k == 0 || k == bins - 1;
    s.density[k] *= (edge ? 1.0 : 2.0) / (sample_rate * w2 * static_cast<double>(s.segments));
  }
  return s;
}

/// Closed-form one-sided PSD of y = (g B(z) / A(z)) e with white noise e of
/// variance `variance`, at frequency f [Hz] for sampling rate fs [Hz]:
/// 2 var g^2 |B|^2 / (|A|^2 fs). a = 1, a_1..a_p (A(z) = sum a_k z^-k);
/// b = b_0..b_q (empty: B = 1).
[[nodiscard]] inline double arma_psd(std::span<const double> a, std::span<const double> b, double variance, double gain,
                                     double f, double fs) {
  const double w = 2.0 * std::numbers::pi * f / fs;
  const auto poly = [w](std::span<const double> c) {
    std::complex<double> v{0.0, 0.0};
    for (std::size_t k = 0; k < c.size(); ++k)
      v += c[k] * std::polar(1.0, -w * static_cast<double>(k));
    return v;
  };
  const double num = b.empty() ? 1.0 : std::norm(poly(b));
  return 2.0 * variance * gain * gain * num / (std::norm(poly(a)) * fs);
}

}  // namespace hapticfield::offline
