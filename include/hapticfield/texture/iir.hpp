#pragma once
/// @file iir.hpp
/// Recursive filters for spectral shaping of texture noise (Fritz & Barner
/// 1996, section 5.2): biquads, biquad cascades, Butterworth low / high /
/// band-pass of order 1..8 (bilinear transform with prewarping, designed at
/// setup), and a parametric equaliser of peaking biquads (Bristow-Johnson,
/// "Cookbook formulae for audio EQ biquad filter coefficients").
///
/// Setup may allocate nothing here but may throw; process() is noexcept,
/// allocation-free and O(sections).

#include <array>
#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticfield::texture {

/// y[n] = b0 x[n] + b1 x[n-1] + b2 x[n-2] - a1 y[n-1] - a2 y[n-2] (a0 = 1).
struct BiquadCoefficients {
  double b0{1.0};
  double b1{0.0};
  double b2{0.0};
  double a1{0.0};
  double a2{0.0};
};

namespace detail {
inline void require_sample_rate(double fs, const char* who) {
  if (!std::isfinite(fs) || fs <= 0.0)
    throw std::invalid_argument(std::string(who) + ": sample rate must be finite and > 0 [Hz]");
}
inline void require_below_nyquist(double f, double fs, const char* who, const char* name) {
  if (!std::isfinite(f) || f <= 0.0 || f >= fs / 2.0)
    throw std::invalid_argument(std::string(who) + ": " + name +
                                " must be > 0 and below Nyquist (sample rate / 2) [Hz]");
}
}  // namespace detail

/// One second-order section, transposed direct form II.
class Biquad {
 public:
  Biquad() = default;
  /// @throws std::invalid_argument for non-finite coefficients or poles on or
  ///         outside the unit circle (|a2| < 1 and |a1| < 1 + a2 is required).
  explicit Biquad(const BiquadCoefficients& c) : coefficients_(c) {
    const double v[] = {c.b0, c.b1, c.b2, c.a1, c.a2};
    for (double x : v)
      if (!std::isfinite(x)) throw std::invalid_argument("Biquad: coefficients must be finite");
    if (!(std::fabs(c.a2) < 1.0 && std::fabs(c.a1) < 1.0 + c.a2))
      throw std::invalid_argument("Biquad: unstable (poles on or outside the unit circle)");
  }

  [[nodiscard]] double process(double x) noexcept {
    const double y = coefficients_.b0 * x + s1_;
    s1_ = coefficients_.b1 * x - coefficients_.a1 * y + s2_;
    s2_ = coefficients_.b2 * x - coefficients_.a2 * y;
    return y;
  }
  void reset() noexcept { s1_ = s2_ = 0.0; }

  /// Complex frequency response at f [Hz] for sample rate fs [Hz].
  [[nodiscard]] std::complex<double> response(double f, double fs) const noexcept {
    const std::complex<double> z1 = std::polar(1.0, -2.0 * std::numbers::pi * f / fs);  // z^-1
    return (coefficients_.b0 + z1 * (coefficients_.b1 + z1 * coefficients_.b2)) /
           (1.0 + z1 * (coefficients_.a1 + z1 * coefficients_.a2));
  }
  [[nodiscard]] const BiquadCoefficients& coefficients() const noexcept { return coefficients_; }

 private:
  BiquadCoefficients coefficients_{};
  double s1_{0.0};
  double s2_{0.0};
};

/// Up to N biquads in series (N fixed at compile time).
template <std::size_t N>
requires(N >= 1) class BiquadCascade {
 public:
  BiquadCascade() = default;
  /// @throws std::invalid_argument for more than N sections or an unstable one.
  explicit BiquadCascade(const std::vector<BiquadCoefficients>& sections) {
    if (sections.size() > N) throw std::invalid_argument("BiquadCascade: more sections than capacity N");
    for (std::size_t i = 0; i < sections.size(); ++i)
      s_[i] = Biquad(sections[i]);
    used_ = sections.size();
  }
  [[nodiscard]] double process(double x) noexcept {
    for (std::size_t i = 0; i < used_; ++i)
      x = s_[i].process(x);
    return x;
  }
  void reset() noexcept {
    for (auto& s : s_)
      s.reset();
  }
  [[nodiscard]] std::complex<double> response(double f, double fs) const noexcept {
    std::complex<double> h{1.0, 0.0};
    for (std::size_t i = 0; i < used_; ++i)
      h *= s_[i].response(f, fs);
    return h;
  }
  [[nodiscard]] std::size_t size() const noexcept { return used_; }
  [[nodiscard]] const Biquad& section(std::size_t i) const noexcept { return s_[i]; }

 private:
  std::array<Biquad, N> s_{};
  std::size_t used_{0};
};

namespace detail {
/// Bilinear transform of an analog pole s [rad/s]: z = (2 fs + s) / (2 fs - s).
[[nodiscard]] inline std::complex<double> bilinear(std::complex<double> s, double fs) noexcept {
  return (2.0 * fs + s) / (2.0 * fs - s);
}
/// Denominator of a section holding the pole pair (z, conj z).
[[nodiscard]] inline BiquadCoefficients pole_pair(std::complex<double> z) noexcept {
  BiquadCoefficients c;
  c.a1 = -2.0 * z.real();
  c.a2 = std::norm(z);
  return c;
}
/// Scales the numerator so |H(e^{j w})| = 1 at the normalised frequency w.
inline void normalise_at(BiquadCoefficients& c, double w) {
  const std::complex<double> z1 = std::polar(1.0, -w);
  const double g = std::abs((c.b0 + z1 * (c.b1 + z1 * c.b2)) / (1.0 + z1 * (c.a1 + z1 * c.a2)));
  c.b0 /= g;
  c.b1 /= g;
  c.b2 /= g;
}
}  // namespace detail

/// Butterworth filter kinds.
enum class FilterBand { low_pass, high_pass, band_pass };

/// Butterworth filter of order 1..8 (band-pass: order N gives 2N poles in N
/// sections), designed at setup from the analog prototype poles
/// p_k = exp(j pi (2k + N + 1) / (2N)) by the bilinear transform with the
/// band edges prewarped, W = 2 fs tan(pi f / fs), so the magnitude is exactly
/// 1/sqrt(2) (-3.0103 dB) at each band edge. Passband gain 1.
template <int Order>
requires(Order >= 1 && Order <= 8) class Butterworth {
 public:
  Butterworth() = default;

  /// @throws std::invalid_argument unless 0 < cutoff < fs / 2.
  [[nodiscard]] static Butterworth low_pass(double cutoff, double fs) {
    return Butterworth(FilterBand::low_pass, cutoff, 0.0, fs);
  }
  /// @throws std::invalid_argument unless 0 < cutoff < fs / 2.
  [[nodiscard]] static Butterworth high_pass(double cutoff, double fs) {
    return Butterworth(FilterBand::high_pass, cutoff, 0.0, fs);
  }
  /// @throws std::invalid_argument unless 0 < low < high < fs / 2.
  [[nodiscard]] static Butterworth band_pass(double low, double high, double fs) {
    return Butterworth(FilterBand::band_pass, low, high, fs);
  }

  [[nodiscard]] double process(double x) noexcept { return cascade_.process(x); }
  void reset() noexcept { cascade_.reset(); }
  [[nodiscard]] std::complex<double> response(double f) const noexcept { return cascade_.response(f, fs_); }
  [[nodiscard]] const BiquadCascade<Order>& cascade() const noexcept { return cascade_; }
  [[nodiscard]] double sample_rate() const noexcept { return fs_; }

 private:
  Butterworth(FilterBand band, double f1, double f2, double fs) : fs_(fs) {
    detail::require_sample_rate(fs, "Butterworth");
    detail::require_below_nyquist(f1, fs, "Butterworth", band == FilterBand::band_pass ? "low edge" : "cutoff");
    if (band == FilterBand::band_pass) {
      detail::require_below_nyquist(f2, fs, "Butterworth", "high edge");
      if (!(f2 > f1)) throw std::invalid_argument("Butterworth: band-pass high edge must exceed low edge [Hz]");
    }
    constexpr int n = Order;
    std::vector<std::complex<double>> proto;  // poles with Im >= 0 (one per conjugate pair)
    for (int k = 0; k < n; ++k) {
      const std::complex<double> p = std::polar(1.0, std::numbers::pi * (2.0 * k + n + 1.0) / (2.0 * n));
      if (p.imag() >= -1e-12) proto.push_back(p.imag() < 1e-12 ? std::complex<double>(-1.0, 0.0) : p);
    }
    std::vector<BiquadCoefficients> sections;
    const double w1 = 2.0 * fs * std::tan(std::numbers::pi * f1 / fs);
    if (band != FilterBand::band_pass) {
      const bool low = band == FilterBand::low_pass;
      for (const auto& p : proto) {
        const std::complex<double> s = low ? w1 * p : w1 / p;
        const std::complex<double> z = detail::bilinear(s, fs);
        BiquadCoefficients c;
        if (p.imag() == 0.0) {  // first-order section (odd order)
          c.a1 = -z.real();
          c.a2 = 0.0;
          c.b0 = 1.0;
          c.b1 = low ? 1.0 : -1.0;
          c.b2 = 0.0;
        } else {
          c = detail::pole_pair(z);
          c.b0 = 1.0;
          c.b1 = low ? 2.0 : -2.0;
          c.b2 = 1.0;
        }
        detail::normalise_at(c, low ? 0.0 : std::numbers::pi);
        sections.push_back(c);
      }
    } else {
      const double w2 = 2.0 * fs * std::tan(std::numbers::pi * f2 / fs);
      const double w0 = std::sqrt(w1 * w2);
      const double bw = w2 - w1;
      const double centre = 2.0 * std::atan(w0 / (2.0 * fs));  // digital centre [rad/sample]
      std::vector<std::complex<double>> real_poles;
      for (const auto& p : proto) {
        // LP -> BP: s^2 - p B s + W0^2 = 0
        const std::complex<double> root = std::sqrt(p * p * bw * bw - 4.0 * w0 * w0);
        const std::complex<double> s_plus = (p * bw + root) / 2.0;
        const std::complex<double> s_minus = (p * bw - root) / 2.0;
        for (const auto& s : {s_plus, s_minus}) {
          const std::complex<double> z = detail::bilinear(s, fs);
          if (p.imag() != 0.0) {
            sections.push_back(detail::pole_pair(z));  // its conjugate comes from conj(p)
          } else if (std::fabs(z.imag()) > 1e-12) {
            if (z.imag() > 0.0) sections.push_back(detail::pole_pair(z));
          } else {
            real_poles.push_back(z);
          }
        }
      }
      for (std::size_t i = 0; i + 1 < real_poles.size(); i += 2) {
        BiquadCoefficients c;
        c.a1 = -(real_poles[i].real() + real_poles[i + 1].real());
        c.a2 = real_poles[i].real() * real_poles[i + 1].real();
        sections.push_back(c);
      }
      for (auto& c : sections) {
        c.b0 = 1.0;
        c.b1 = 0.0;
        c.b2 = -1.0;
        detail::normalise_at(c, centre);
      }
    }
    cascade_ = BiquadCascade<Order>(sections);
  }

  BiquadCascade<Order> cascade_{};
  double fs_{1000.0};
};

/// One band of a parametric equaliser.
struct EqualiserBand {
  double centre{100.0};   ///< centre frequency [Hz]
  double bandwidth{1.0};  ///< bandwidth [octaves] between the half-gain (dB) points
  double gain_db{0.0};    ///< gain at the centre [dB]
};

/// Parametric equaliser: Bands peaking biquads in series (RBJ cookbook:
/// A = 10^(g/40), alpha = sin w0 sinh(ln2/2 BW w0 / sin w0)). Each band has
/// exactly gain_db at its centre and unity gain far from it.
template <std::size_t Bands>
requires(Bands >= 1) class Equaliser {
 public:
  Equaliser() = default;
  /// @throws std::invalid_argument for a centre not in (0, fs/2), a
  ///         non-positive bandwidth or a non-finite gain.
  Equaliser(const std::array<EqualiserBand, Bands>& bands, double fs) : fs_(fs) {
    detail::require_sample_rate(fs, "Equaliser");
    std::vector<BiquadCoefficients> sections;
    for (const auto& b : bands) {
      detail::require_below_nyquist(b.centre, fs, "Equaliser", "centre");
      if (!std::isfinite(b.bandwidth) || b.bandwidth <= 0.0)
        throw std::invalid_argument("Equaliser: bandwidth must be finite and > 0 [octaves]");
      if (!std::isfinite(b.gain_db)) throw std::invalid_argument("Equaliser: gain must be finite [dB]");
      const double a = std::pow(10.0, b.gain_db / 40.0);
      const double w0 = 2.0 * std::numbers::pi * b.centre / fs;
      const double alpha = std::sin(w0) * std::sinh(std::numbers::ln2 / 2.0 * b.bandwidth * w0 / std::sin(w0));
      const double a0 = 1.0 + alpha / a;
      BiquadCoefficients c;
      c.b0 = (1.0 + alpha * a) / a0;
      c.b1 = -2.0 * std::cos(w0) / a0;
      c.b2 = (1.0 - alpha * a) / a0;
      c.a1 = c.b1;
      c.a2 = (1.0 - alpha / a) / a0;
      sections.push_back(c);
    }
    cascade_ = BiquadCascade<Bands>(sections);
  }
  [[nodiscard]] double process(double x) noexcept { return cascade_.process(x); }
  void reset() noexcept { cascade_.reset(); }
  [[nodiscard]] std::complex<double> response(double f) const noexcept { return cascade_.response(f, fs_); }

 private:
  BiquadCascade<Bands> cascade_{};
  double fs_{1000.0};
};

}  // namespace hapticfield::texture
