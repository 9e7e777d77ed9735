#pragma once
/// @file spectral.hpp
/// Spectrally shaped spatial generators (Fritz & Barner 1996, section 5):
/// fractional Brownian motion (fBm) with self-similarity h, Fourier synthesis
/// from sine / square / sawtooth terms, and the modulated texture
/// Ft(p) = S(p) g(p) + N(p).

#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/texture/lattice.hpp"

namespace hapticfield::texture {

/// fBm: f(p) = sum_{o=0}^{O-1} 2^{-h o} L_o(2^o p) / norm, where L_o is the
/// lattice with a different seed per octave and norm = sqrt(sum 2^{-2 h o})
/// keeps the variance of the base lattice. Each octave carries the base
/// spectrum shifted up by a factor 2 in frequency with 2^{-2h} of the power
/// spread over twice the bandwidth, so the power spectral density of a
/// straight-line trace falls as f^{-(2h + 1)} between the first and the last
/// octave (the 1/f^beta law of fBm, beta = 2h + 1; Mandelbrot & Van Ness 1968).
template <NoiseSource Noise, int Dim = 3>
class Fbm {
 public:
  /// @param h  self-similarity (Hurst) exponent, 0 <= h <= 2
  /// @param octaves  1..24
  /// @throws std::invalid_argument for h or octaves out of range.
  Fbm(NoiseLattice<Noise, Dim> base, double h, int octaves) : base_(std::move(base)), h_(h), octaves_(octaves) {
    if (!std::isfinite(h) || h < 0.0 || h > 2.0)
      throw std::invalid_argument("Fbm: self-similarity h must be in [0, 2]");
    if (octaves < 1 || octaves > 24) throw std::invalid_argument("Fbm: octaves must be in 1..24");
    double sum = 0.0;
    for (int o = 0; o < octaves; ++o)
      sum += std::pow(2.0, -2.0 * h * o);
    inv_norm_ = 1.0 / std::sqrt(sum);
    gain_ = std::pow(2.0, -h);
  }

  [[nodiscard]] glm::dvec3 operator()(const glm::dvec3& p) const noexcept {
    glm::dvec3 sum{0.0};
    double amplitude = 1.0;
    double frequency = 1.0;
    for (int o = 0; o < octaves_; ++o) {
      sum += amplitude * base_.at(frequency * p, base_.seed() + 0x68E31DA4u * static_cast<std::uint32_t>(o));
      amplitude *= gain_;
      frequency *= 2.0;
    }
    return sum * inv_norm_;
  }

  /// Expected log-log slope of the power spectrum of a line trace: -(2h + 1).
  [[nodiscard]] double spectral_slope() const noexcept { return -(2.0 * h_ + 1.0); }

 private:
  NoiseLattice<Noise, Dim> base_;
  double h_;
  int octaves_;
  double inv_norm_{1.0};
  double gain_{1.0};
};

/// Periodic waveforms for Fourier synthesis, each of unit amplitude.
enum class Waveform {
  sine,      ///< sin(x)
  square,    ///< sign(sin(x)) (+1 on [0, pi), -1 on [pi, 2 pi))
  sawtooth,  ///< rises linearly from -1 at x = 0 to +1 at x -> 2 pi
};

/// One term of a Fourier synthesis: a * w(2 pi f (d . p) + phi).
struct FourierTerm {
  Waveform waveform{Waveform::sine};
  double amplitude{1.0};                ///< a [N or unit of the texture]
  double frequency{100.0};              ///< spatial frequency f [1/m]
  double phase{0.0};                    ///< phi [rad]
  glm::dvec3 direction{1.0, 0.0, 0.0};  ///< unit wave direction d
};

namespace detail {
[[nodiscard]] inline double waveform(Waveform w, double x) noexcept {
  switch (w) {
    case Waveform::sine:
      return std::sin(x);
    case Waveform::square: {
      const double r = x - 2.0 * std::numbers::pi * std::floor(x / (2.0 * std::numbers::pi));
      return r < std::numbers::pi ? 1.0 : -1.0;
    }
    case Waveform::sawtooth: {
      const double r = x / (2.0 * std::numbers::pi);
      return 2.0 * (r - std::floor(r)) - 1.0;
    }
  }
  return 0.0;
}
}  // namespace detail

/// Fourier synthesis: g(p) = axis * sum_k a_k w_k(2 pi f_k (d_k . p) + phi_k).
/// The scalar sum is put along a force axis (unit vector, e.g. the surface
/// normal for bumps or a lateral axis for gratings). Range: |g| <= sum |a_k|.
class FourierSynthesis {
 public:
  /// @throws std::invalid_argument for no term, a non-finite amplitude or
  ///         phase, a negative or non-finite frequency, a direction that is
  ///         not unit length, or an axis that is not unit length.
  FourierSynthesis(std::vector<FourierTerm> terms, glm::dvec3 axis = glm::dvec3{0.0, 0.0, 1.0})
      : terms_(std::move(terms)), axis_(axis) {
    if (terms_.empty()) throw std::invalid_argument("FourierSynthesis: no term");
    for (const auto& t : terms_) {
      if (!std::isfinite(t.amplitude) || !std::isfinite(t.phase))
        throw std::invalid_argument("FourierSynthesis: amplitude and phase [rad] must be finite");
      if (!std::isfinite(t.frequency) || t.frequency < 0.0)
        throw std::invalid_argument("FourierSynthesis: frequency must be finite and >= 0 [1/m]");
      if (std::fabs(glm::length(t.direction) - 1.0) > 1e-9)
        throw std::invalid_argument("FourierSynthesis: direction must be a unit vector");
    }
    if (std::fabs(glm::length(axis) - 1.0) > 1e-9)
      throw std::invalid_argument("FourierSynthesis: axis must be a unit vector");
  }

  [[nodiscard]] double scalar(const glm::dvec3& p) const noexcept {
    double sum = 0.0;
    for (const auto& t : terms_)
      sum += t.amplitude *
             detail::waveform(t.waveform, 2.0 * std::numbers::pi * t.frequency * glm::dot(t.direction, p) + t.phase);
    return sum;
  }

  [[nodiscard]] glm::dvec3 operator()(const glm::dvec3& p) const noexcept {
    const double s = scalar(p);
    return std::isfinite(s) ? s * axis_ : glm::dvec3{0.0};
  }

 private:
  std::vector<FourierTerm> terms_;
  glm::dvec3 axis_{0.0, 0.0, 1.0};
};

/// Ft(p) = (s + m(p).x) g(p) + n(p) (Fritz & Barner 1996, eq. for the
/// "modulated" texture): a base generator g scaled by a multiplicative noise
/// around the constant s and offset by an additive noise n.
template <SpatialGenerator G, SpatialGenerator Mul, SpatialGenerator Add>
class ModulatedTexture {
 public:
  /// @param scale  constant part s of the multiplicative term
  /// @throws std::invalid_argument for a non-finite scale.
  ModulatedTexture(G base, double scale, Mul multiplicative, Add additive)
      : g_(std::move(base)), s_(scale), m_(std::move(multiplicative)), n_(std::move(additive)) {
    if (!std::isfinite(scale)) throw std::invalid_argument("ModulatedTexture: scale must be finite");
  }

  [[nodiscard]] glm::dvec3 operator()(const glm::dvec3& p) const noexcept {
    return (s_ + glm::dvec3(m_(p)).x) * glm::dvec3(g_(p)) + glm::dvec3(n_(p));
  }

 private:
  G g_;
  double s_;
  Mul m_;
  Add n_;
};

static_assert(SpatialGenerator<FourierSynthesis>);
static_assert(SpatialGenerator<Fbm<GaussianNoise>>);

}  // namespace hapticfield::texture
