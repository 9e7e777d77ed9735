#pragma once
/// @file lsf.hpp
/// Line spectral frequencies (LSFs) <-> AR polynomials, as used by the
/// data-driven HaTT texture models (their per-model filters are stored and
/// interpolated as LSFs so that interpolated filters stay stable).
/// lsf_to_ar<MaxOrder>() is noexcept and allocation-free (servo path);
/// the allocating forms are setup code and throw std::invalid_argument.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>
#include <stdexcept>
#include <vector>

#include "hapticfield/texture/arma.hpp"

namespace hapticfield::texture {

namespace detail {
/// poly *= (1 + c1 z^-1 + c2 z^-2) in place; n = number of coefficients (grows by 2).
template <std::size_t N>
constexpr void multiply_quadratic(std::array<double, N>& poly, std::size_t& n, double c1, double c2 = 1.0) noexcept {
  for (std::size_t k = n + 2; k-- > 0;) {
    double v = k < n ? poly[k] : 0.0;
    if (k >= 1 && k - 1 < n) v += c1 * poly[k - 1];
    if (k >= 2 && k - 2 < n) v += c2 * poly[k - 2];
    poly[k] = v;
  }
  n += 2;
}
/// poly *= (1 + s z^-1) in place.
template <std::size_t N>
constexpr void multiply_linear(std::array<double, N>& poly, std::size_t& n, double s) noexcept {
  for (std::size_t k = n + 1; k-- > 0;) {
    double v = k < n ? poly[k] : 0.0;
    if (k >= 1) v += s * poly[k - 1];
    poly[k] = v;
  }
  n += 1;
}
}  // namespace detail

/// LSFs w_1 < ... < w_p in (0, pi) [rad] -> AR polynomial a_0 = 1, a_1..a_p
/// of A(z) = 1 + a_1 z^-1 + ... + a_p z^-p (Kondoz, "Digital Speech", ch. 4;
/// the same construction as MATLAB's lsf2poly): the odd-numbered LSFs are
/// the roots of the sum polynomial, the even-numbered ones of the difference
/// polynomial, A = (P + Q) / 2. noexcept and allocation-free; returns false
/// when p is 0 or above MaxOrder or when `a` has fewer than p + 1 entries.
template <std::size_t MaxOrder>
[[nodiscard]] bool lsf_to_ar(std::span<const double> lsf, std::span<double> a) noexcept {
  const std::size_t p = lsf.size();
  if (p == 0 || p > MaxOrder || a.size() < p + 1) return false;
  std::array<double, MaxOrder + 4> sum{}, diff{};
  std::size_t ns = 1, nd = 1;
  sum[0] = diff[0] = 1.0;
  for (std::size_t i = 0; i < p; ++i) {
    const double c = -2.0 * std::cos(lsf[i]);
    if (i % 2 == 0)
      detail::multiply_quadratic(sum, ns, c);
    else
      detail::multiply_quadratic(diff, nd, c);
  }
  if (p % 2 == 1) {
    // odd order: z = 1 and z = -1 are both roots of the difference polynomial
    detail::multiply_quadratic(diff, nd, 0.0, -1.0);  // (1 - z^-2)
  } else {
    detail::multiply_linear(diff, nd, -1.0);  // root z = 1
    detail::multiply_linear(sum, ns, 1.0);    // root z = -1
  }
  for (std::size_t k = 0; k <= p; ++k)
    a[k] = 0.5 * (sum[k] + diff[k]);
  return true;
}

/// Allocating convenience form (setup): returns a_0 = 1, a_1..a_p.
/// @throws std::invalid_argument for LSFs that are not strictly increasing
///         in (0, pi) or an order above 256.
[[nodiscard]] inline std::vector<double> lsf_to_ar(std::span<const double> lsf) {
  if (lsf.empty() || lsf.size() > 256) throw std::invalid_argument("lsf_to_ar: order must be in 1..256");
  for (std::size_t i = 0; i < lsf.size(); ++i)
    if (!(lsf[i] > 0.0 && lsf[i] < std::numbers::pi) || (i > 0 && !(lsf[i] > lsf[i - 1])))
      throw std::invalid_argument("lsf_to_ar: LSFs must increase strictly within (0, pi) [rad]");
  std::vector<double> a(lsf.size() + 1);
  (void)lsf_to_ar<256>(lsf, a);
  return a;
}

/// AR polynomial a_0 = 1, a_1..a_p (minimum phase) -> its p LSFs [rad], the
/// zeros on the unit circle of the sum and difference polynomials
/// A(z) +- z^-(p+1) A(1/z), found by a sign scan and bisection.
/// @throws std::invalid_argument when a_0 != 1, a coefficient is not
///         finite, or A is not minimum phase (its LSFs do not interlace).
[[nodiscard]] inline std::vector<double> ar_to_lsf(std::span<const double> a) {
  if (a.size() < 2 || a[0] != 1.0) throw std::invalid_argument("ar_to_lsf: need a_0 = 1 and order >= 1");
  if (!is_stable(a.subspan(1))) throw std::invalid_argument("ar_to_lsf: AR polynomial is not minimum phase");
  const std::size_t p = a.size() - 1;
  const auto coeff = [&](std::size_t k) { return k <= p ? a[k] : 0.0; };
  const double half = (p + 1) / 2.0;
  // e^{j w (p+1)/2} S(e^{jw}) = sum s_k cos(w (k - (p+1)/2)), s_k symmetric;
  // e^{j w (p+1)/2} D(e^{jw}) = -j sum d_k sin(w (k - (p+1)/2)), d_k antisymmetric
  // The angles w (k - (p+1)/2), k = 0..p+1, step by w: cos and sin of each
  // follow from the two before (cos((m+1)w) = 2 cos w cos(mw) - cos((m-1)w)),
  // so one evaluation costs two trigonometric calls, not p + 2.
  const auto fs = [&](double w) {
    const double c1 = std::cos(w);
    double prev = std::cos(-w * half - w), cur = std::cos(-w * half);  // k = -1, 0
    double v = 0;
    for (std::size_t k = 0; k <= p + 1; ++k) {
      v += (coeff(k) + coeff(p + 1 - k)) * cur;
      const double next = 2.0 * c1 * cur - prev;
      prev = cur;
      cur = next;
    }
    return v;
  };
  const auto fd = [&](double w) {
    const double c1 = std::cos(w);
    double prev = std::sin(-w * half - w), cur = std::sin(-w * half);
    double v = 0;
    for (std::size_t k = 0; k <= p + 1; ++k) {
      v += (coeff(k) - coeff(p + 1 - k)) * cur;
      const double next = 2.0 * c1 * cur - prev;
      prev = cur;
      cur = next;
    }
    return v;
  };
  std::vector<double> roots;
  const std::size_t grid = 256 * (p + 1);
  const double lo = 1e-7, hi = std::numbers::pi - 1e-7;
  const auto scan = [&](const auto& f) {
    double w0 = lo, f0 = f(w0);
    for (std::size_t i = 1; i <= grid; ++i) {
      const double w1 = lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(grid);
      const double f1 = f(w1);
      if ((f0 < 0.0) != (f1 < 0.0)) {
        double a0 = w0, a1 = w1, fa = f0;
        for (int it = 0; it < 60; ++it) {
          const double m = 0.5 * (a0 + a1);
          const double fm = f(m);
          if ((fa < 0.0) == (fm < 0.0))
            a0 = m, fa = fm;
          else
            a1 = m;
        }
        roots.push_back(0.5 * (a0 + a1));
      }
      w0 = w1;
      f0 = f1;
    }
  };
  scan(fs);
  scan(fd);
  std::sort(roots.begin(), roots.end());
  if (roots.size() != p) throw std::invalid_argument("ar_to_lsf: could not isolate the LSFs (roots too close)");
  return roots;
}

}  // namespace hapticfield::texture
