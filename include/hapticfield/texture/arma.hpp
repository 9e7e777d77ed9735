#pragma once
/// @file arma.hpp
/// ARMA(p, q) filters from coefficients (Fritz & Barner 1996, section 5.3;
/// Box & Jenkins): A(z) y = B(z) x with A(z) = 1 + a1 z^-1 + ... + ap z^-p
/// and B(z) = b0 + b1 z^-1 + ... + bq z^-q, i.e.
///   y[n] = sum_{k=0..q} b_k x[n-k] - sum_{k=1..p} a_k y[n-k].
/// Stability (all poles strictly inside the unit circle) is checked at setup
/// by the step-down (Schur-Cohn) recursion: the reflection coefficients of
/// A(z) must all satisfy |k| < 1.

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <vector>

namespace hapticfield::texture {

/// Reflection coefficients of the monic polynomial 1 + a1 z^-1 + ... + ap z^-p
/// by the step-down recursion (Levinson run backwards). Allocates (setup only).
[[nodiscard]] inline std::vector<double> reflection_coefficients(std::span<const double> a) {
  std::vector<double> cur(a.begin(), a.end());  // a1..ap
  std::vector<double> k(cur.size());
  for (std::size_t m = cur.size(); m > 0; --m) {
    const double km = cur[m - 1];
    k[m - 1] = km;
    if (!(std::fabs(km) < 1.0)) return k;  // unstable; later ones irrelevant
    std::vector<double> next(m - 1);
    for (std::size_t i = 1; i < m; ++i)
      next[i - 1] = (cur[i - 1] - km * cur[m - 1 - i]) / (1.0 - km * km);
    cur = next;
  }
  return k;
}

/// True when every root of 1 + a1 z^-1 + ... + ap z^-p lies strictly inside
/// the unit circle (and every coefficient is finite).
[[nodiscard]] inline bool is_stable(std::span<const double> a) {
  for (double v : a)
    if (!std::isfinite(v)) return false;
  for (double k : reflection_coefficients(a))
    if (!(std::fabs(k) < 1.0)) return false;
  return true;
}

/// ARMA(P, Q) filter with orders fixed at compile time.
template <std::size_t P, std::size_t Q>
class Arma {
 public:
  /// Pass-through (y = x) until given coefficients.
  Arma() { b_[0] = 1.0; }
  /// @param a  a1..aP of A(z) (leading 1 implied)
  /// @param b  b0..bQ of B(z)
  /// @throws std::invalid_argument for a non-finite coefficient or poles on or
  ///         outside the unit circle.
  Arma(const std::array<double, P>& a, const std::array<double, Q + 1>& b) : a_(a), b_(b) {
    for (double v : b)
      if (!std::isfinite(v)) throw std::invalid_argument("Arma: MA coefficients must be finite");
    if (!is_stable(std::span<const double>(a_.data(), P)))
      throw std::invalid_argument("Arma: AR polynomial unstable (a pole on or outside the unit circle) or not finite");
  }

  [[nodiscard]] double process(double x) noexcept {
    // shift histories (P, Q are small; a ring buffer costs more branches)
    double y = b_[0] * x;
    for (std::size_t k = 1; k <= Q; ++k)
      y += b_[k] * x_[k - 1];
    for (std::size_t k = 1; k <= P; ++k)
      y -= a_[k - 1] * y_[k - 1];
    if constexpr (Q > 0) {
      for (std::size_t k = Q - 1; k > 0; --k)
        x_[k] = x_[k - 1];
      x_[0] = x;
    }
    if constexpr (P > 0) {
      for (std::size_t k = P - 1; k > 0; --k)
        y_[k] = y_[k - 1];
      y_[0] = y;
    }
    return y;
  }
  void reset() noexcept {
    x_.fill(0.0);
    y_.fill(0.0);
  }

  /// First n samples of the impulse response (setup / analysis only).
  [[nodiscard]] std::vector<double> impulse_response(std::size_t n) const {
    Arma copy = *this;
    copy.reset();
    std::vector<double> h(n);
    for (std::size_t i = 0; i < n; ++i)
      h[i] = copy.process(i == 0 ? 1.0 : 0.0);
    return h;
  }

 private:
  std::array<double, P> a_{};
  std::array<double, Q + 1> b_{};
  std::array<double, (Q > 0 ? Q : 1)> x_{};
  std::array<double, (P > 0 ? P : 1)> y_{};
};

}  // namespace hapticfield::texture
