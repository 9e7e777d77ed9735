#pragma once
/// @file noise.hpp
/// Repeatable noise primitives (Fritz & Barner, "Stochastic models for haptic
/// texture", SPIE 1996, section 3): uniform, Gaussian, Laplacian, multivariate
/// Gaussian with a full covariance, Gaussian mixtures.
///
/// Every sample is a pure function of (seed, lattice point, stream): the same
/// arguments always give the same value, on every platform. The lattice point
/// is scrambled through a 256-entry permutation table as in Perlin's noise
/// (Perlin, SIGGRAPH 1985 / 2002), then avalanched by a 32-bit integer mix so
/// that the pattern does not repeat every 256 cells. All arithmetic is on
/// uint32_t (wrap-around is defined; signed overflow would not be).

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

namespace hapticfield::texture {

namespace detail {

/// Perlin-style permutation of 0..255, built at compile time by a Fisher-Yates
/// shuffle driven by a fixed linear congruential generator (so the table is a
/// true permutation by construction).
consteval std::array<std::uint8_t, 256> make_permutation() {
  std::array<std::uint8_t, 256> p{};
  for (std::size_t i = 0; i < 256; ++i)
    p[i] = static_cast<std::uint8_t>(i);
  std::uint32_t state = 0x2545F491u;
  for (std::size_t i = 255; i > 0; --i) {
    state = state * 1664525u + 1013904223u;  // Numerical Recipes LCG
    const std::size_t j = (state >> 8) % (i + 1);
    const std::uint8_t t = p[i];
    p[i] = p[j];
    p[j] = t;
  }
  return p;
}

inline constexpr std::array<std::uint8_t, 256> permutation = make_permutation();

/// 32-bit avalanche mix (xor-shift-multiply, full period bijection on uint32).
[[nodiscard]] constexpr std::uint32_t mix(std::uint32_t x) noexcept {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

}  // namespace detail

/// The 256-entry permutation table (exposed for tests and documentation).
[[nodiscard]] constexpr std::uint8_t permutation(std::uint32_t i) noexcept {
  return detail::permutation[i & 255u];
}

/// Hash of (seed, lattice point x, y, z, stream) to a uniformly distributed
/// uint32. The lattice coordinates are taken modulo 2^32 (uint32 wrap).
[[nodiscard]] constexpr std::uint32_t hash(std::uint32_t seed, std::uint32_t x, std::uint32_t y, std::uint32_t z,
                                           std::uint32_t stream = 0) noexcept {
  // Perlin's nested table lookup on the low 8 bits of each coordinate ...
  const std::uint32_t p =
      detail::permutation[(detail::permutation[(detail::permutation[x & 255u] + y) & 255u] + z) & 255u];
  // ... then a full-width mix of every bit so the lattice does not repeat.
  std::uint32_t h = detail::mix(seed ^ (stream * 0x9E3779B9u));
  h = detail::mix(h ^ x);
  h = detail::mix(h + y * 0x85EBCA77u);
  h = detail::mix(h ^ (z * 0xC2B2AE3Du) ^ (p << 24));
  return h;
}

/// Lattice point with signed integer coordinates (cell index).
struct Cell {
  std::uint32_t x{0};  ///< x index modulo 2^32
  std::uint32_t y{0};  ///< y index modulo 2^32
  std::uint32_t z{0};  ///< z index modulo 2^32
};

/// Uniform sample in the open interval (0, 1), resolution 2^-32.
[[nodiscard]] inline double uniform01(std::uint32_t seed, Cell c, std::uint32_t stream = 0) noexcept {
  return (static_cast<double>(hash(seed, c.x, c.y, c.z, stream)) + 0.5) * 0x1p-32;
}

/// Standard normal sample N(0, 1) by the Box-Muller transform. Range:
/// |g| <= sqrt(2 ln 2^33) ~ 6.76 (the smallest uniform is 2^-33).
[[nodiscard]] inline double gaussian(std::uint32_t seed, Cell c, std::uint32_t stream = 0) noexcept {
  const double u1 = uniform01(seed, c, 2u * stream);
  const double u2 = uniform01(seed, c, 2u * stream + 1u);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

/// Three independent standard normal samples (two Box-Muller pairs).
[[nodiscard]] inline glm::dvec3 gaussian3(std::uint32_t seed, Cell c, std::uint32_t stream = 0) noexcept {
  const double r1 = std::sqrt(-2.0 * std::log(uniform01(seed, c, 4u * stream)));
  const double t1 = 2.0 * std::numbers::pi * uniform01(seed, c, 4u * stream + 1u);
  const double r2 = std::sqrt(-2.0 * std::log(uniform01(seed, c, 4u * stream + 2u)));
  const double t2 = 2.0 * std::numbers::pi * uniform01(seed, c, 4u * stream + 3u);
  return glm::dvec3{r1 * std::cos(t1), r1 * std::sin(t1), r2 * std::cos(t2)};
}

/// Laplacian sample with zero mean and unit variance (scale b = 1/sqrt 2) by
/// the inverse CDF. Range: |l| <= ln(2^32) / sqrt 2 ~ 15.7.
[[nodiscard]] inline double laplacian(std::uint32_t seed, Cell c, std::uint32_t stream = 0) noexcept {
  const double u = uniform01(seed, c, stream) - 0.5;  // (-0.5, 0.5)
  const double magnitude = -std::log1p(-2.0 * std::fabs(u)) * (1.0 / std::numbers::sqrt2);
  return u < 0.0 ? -magnitude : magnitude;
}

/// A vector noise distribution: `sample(seed, cell)` gives one repeatable
/// 3-vector per lattice point.
template <class N>
concept NoiseSource = requires(const N& n, std::uint32_t seed, Cell c) {
  { n.sample(seed, c) }
  noexcept->std::same_as<glm::dvec3>;
};

namespace detail {
inline void require_finite(double v, const char* what) {
  if (!std::isfinite(v)) throw std::invalid_argument(std::string(what) + " must be finite");
}
inline void require_finite(const glm::dvec3& v, const char* what) {
  require_finite(v.x, what);
  require_finite(v.y, what);
  require_finite(v.z, what);
}

/// Lower-triangular L with L L^T = C (Cholesky). C must be symmetric positive
/// semi-definite; an axis of zero variance (its row and column all zero) is
/// accepted and gives a zero component (a lateral-only texture has zero
/// variance in z). An indefinite or asymmetric C throws.
inline glm::dmat3 cholesky(const glm::dmat3& c, const char* what) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (!std::isfinite(c[j][i])) throw std::invalid_argument(std::string(what) + ": covariance must be finite");
      const double scale = std::fmax(1.0, std::fmax(std::fabs(c[i][j]), std::fabs(c[j][i])));
      if (std::fabs(c[j][i] - c[i][j]) > 1e-12 * scale)
        throw std::invalid_argument(std::string(what) + ": covariance must be symmetric");
    }
  double largest = 0.0;
  for (int i = 0; i < 3; ++i)
    largest = std::fmax(largest, c[i][i]);
  const double tolerance = 1e-12 * std::fmax(largest, 1e-300);
  // element (row r, column k) of a GLM matrix is m[k][r]
  glm::dmat3 l{0.0};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k <= r; ++k) {
      double s = c[k][r];
      for (int m = 0; m < k; ++m)
        s -= l[m][r] * l[m][k];
      if (r == k) {
        if (s < -tolerance)
          throw std::invalid_argument(std::string(what) + ": covariance is not positive (semi-)definite [unit^2]");
        if (s <= tolerance) {
          // zero pivot: the rest of this column must vanish too
          for (int below = r + 1; below < 3; ++below) {
            double t = c[r][below];
            for (int m = 0; m < r; ++m)
              t -= l[m][below] * l[m][r];
            if (std::fabs(t) > std::sqrt(tolerance) * std::sqrt(std::fmax(largest, 1e-300)))
              throw std::invalid_argument(std::string(what) + ": covariance is not positive (semi-)definite [unit^2]");
          }
          l[r][r] = 0.0;
        } else {
          l[r][r] = std::sqrt(s);
        }
      } else {
        l[k][r] = l[k][k] > 0.0 ? s / l[k][k] : 0.0;
      }
    }
  }
  return l;
}
}  // namespace detail

/// Independent uniform components in [low, high).
/// Mean (low + high) / 2, variance (high - low)^2 / 12 per component.
class UniformNoise {
 public:
  /// @throws std::invalid_argument unless low < high, both finite.
  UniformNoise(double low = -1.0, double high = 1.0) : low_(low), width_(high - low) {
    detail::require_finite(low, "UniformNoise: low");
    detail::require_finite(high, "UniformNoise: high");
    if (!(high > low)) throw std::invalid_argument("UniformNoise: high must exceed low");
  }
  [[nodiscard]] glm::dvec3 sample(std::uint32_t seed, Cell c) const noexcept {
    return glm::dvec3{low_ + width_ * uniform01(seed, c, 0), low_ + width_ * uniform01(seed, c, 1),
                      low_ + width_ * uniform01(seed, c, 2)};
  }
  [[nodiscard]] double mean() const noexcept { return low_ + width_ / 2.0; }
  [[nodiscard]] double variance() const noexcept { return width_ * width_ / 12.0; }

 private:
  double low_;
  double width_;
};

/// Independent Gaussian components N(mean, sigma^2).
/// Range: mean +- 6.76 sigma.
class GaussianNoise {
 public:
  /// @throws std::invalid_argument for a negative or non-finite sigma.
  explicit GaussianNoise(double sigma = 1.0, double mean = 0.0) : sigma_(sigma), mean_(mean) {
    detail::require_finite(sigma, "GaussianNoise: sigma");
    detail::require_finite(mean, "GaussianNoise: mean");
    if (sigma < 0.0) throw std::invalid_argument("GaussianNoise: sigma must be >= 0 (negative variance)");
  }
  /// From a variance [unit^2] instead of a standard deviation.
  /// @throws std::invalid_argument for a negative variance.
  [[nodiscard]] static GaussianNoise from_variance(double variance, double mean = 0.0) {
    if (!(variance >= 0.0) || !std::isfinite(variance))
      throw std::invalid_argument("GaussianNoise: variance must be finite and >= 0 [unit^2]");
    return GaussianNoise(std::sqrt(variance), mean);
  }
  [[nodiscard]] glm::dvec3 sample(std::uint32_t seed, Cell c) const noexcept {
    return mean_ + sigma_ * gaussian3(seed, c);
  }
  [[nodiscard]] double sigma() const noexcept { return sigma_; }

 private:
  double sigma_;
  double mean_;
};

/// Independent Laplacian components with the given mean and standard
/// deviation (scale b = sigma / sqrt 2). Range: mean +- 15.7 sigma.
class LaplacianNoise {
 public:
  /// @throws std::invalid_argument for a negative or non-finite sigma.
  explicit LaplacianNoise(double sigma = 1.0, double mean = 0.0) : sigma_(sigma), mean_(mean) {
    detail::require_finite(sigma, "LaplacianNoise: sigma");
    detail::require_finite(mean, "LaplacianNoise: mean");
    if (sigma < 0.0) throw std::invalid_argument("LaplacianNoise: sigma must be >= 0 (negative variance)");
  }
  [[nodiscard]] glm::dvec3 sample(std::uint32_t seed, Cell c) const noexcept {
    return glm::dvec3{mean_ + sigma_ * laplacian(seed, c, 0), mean_ + sigma_ * laplacian(seed, c, 1),
                      mean_ + sigma_ * laplacian(seed, c, 2)};
  }

 private:
  double sigma_;
  double mean_;
};

/// Multivariate Gaussian N(mean, C) with a full 3x3 covariance C: x = mean +
/// L g with L L^T = C (Cholesky, computed once at construction) and g three
/// independent standard normals. Range: each component within mean_i +-
/// 6.76 * sqrt(3 C_ii).
class MultivariateGaussianNoise {
 public:
  /// @throws std::invalid_argument when C is not symmetric positive
  ///         (semi-)definite or not finite; a zero-variance axis is allowed.
  MultivariateGaussianNoise(const glm::dvec3& mean, const glm::dmat3& covariance)
      : mean_(mean), l_(detail::cholesky(covariance, "MultivariateGaussianNoise")) {
    detail::require_finite(mean, "MultivariateGaussianNoise: mean");
  }
  [[nodiscard]] glm::dvec3 sample(std::uint32_t seed, Cell c) const noexcept { return mean_ + l_ * gaussian3(seed, c); }
  /// The Cholesky factor L (lower triangular).
  [[nodiscard]] const glm::dmat3& factor() const noexcept { return l_; }

 private:
  glm::dvec3 mean_{0.0};
  glm::dmat3 l_{1.0};
};

/// One component of a Gaussian mixture.
struct MixtureComponent {
  double weight{1.0};          ///< relative weight (>= 0; normalised at setup)
  glm::dvec3 mean{0.0};        ///< component mean
  glm::dmat3 covariance{1.0};  ///< component covariance (symmetric PSD)
};

/// Gaussian mixture: a component is chosen with probability w_k / sum w, then
/// a multivariate Gaussian sample of that component is drawn.
class GaussianMixtureNoise {
 public:
  /// @throws std::invalid_argument for no component, a negative or
  ///         non-finite weight, all weights zero, or a bad covariance.
  explicit GaussianMixtureNoise(const std::vector<MixtureComponent>& components) {
    if (components.empty()) throw std::invalid_argument("GaussianMixtureNoise: no component");
    double total = 0.0;
    for (const auto& c : components) {
      if (!std::isfinite(c.weight) || c.weight < 0.0)
        throw std::invalid_argument("GaussianMixtureNoise: weights must be finite and >= 0");
      total += c.weight;
    }
    if (!(total > 0.0)) throw std::invalid_argument("GaussianMixtureNoise: weights sum to zero");
    double running = 0.0;
    for (const auto& c : components) {
      running += c.weight / total;
      detail::require_finite(c.mean, "GaussianMixtureNoise: mean");
      parts_.push_back(Part{running, c.mean, detail::cholesky(c.covariance, "GaussianMixtureNoise")});
    }
    parts_.back().cumulative = 1.0;
  }
  [[nodiscard]] glm::dvec3 sample(std::uint32_t seed, Cell c) const noexcept {
    const double u = uniform01(seed, c, 7u);
    std::size_t k = 0;
    while (k + 1 < parts_.size() && u > parts_[k].cumulative)
      ++k;
    return parts_[k].mean + parts_[k].l * gaussian3(seed, c);
  }
  [[nodiscard]] std::size_t size() const noexcept { return parts_.size(); }

 private:
  struct Part {
    double cumulative{0.0};
    glm::dvec3 mean{0.0};
    glm::dmat3 l{1.0};
  };
  std::vector<Part> parts_;
};

/// A faster stand-in for any noise: Size samples of it are drawn once at
/// setup (entry i = noise.sample(table_seed, {i, 0, 0})), and a lattice point
/// reads entry hash(seed, point) mod Size, a Perlin-style hashed table. The
/// marginal distribution is the table's empirical one (Size draws of the
/// original); neighbouring points stay independent, but only Size distinct
/// vectors occur. One hash and one load per sample instead of the
/// distribution's transcendental functions (see bench_texture). The table is
/// shared, read-only, between copies.
template <NoiseSource Noise, std::size_t Size = 4096>
requires(Size >= 16 && (Size & (Size - 1)) == 0) class TabulatedNoise {
 public:
  explicit TabulatedNoise(const Noise& noise, std::uint32_t table_seed = 0x5EEDu)
      : table_(make_table(noise, table_seed)) {}
  [[nodiscard]] glm::dvec3 sample(std::uint32_t seed, Cell c) const noexcept {
    return (*table_)[hash(seed, c.x, c.y, c.z) & (Size - 1)];
  }
  [[nodiscard]] const std::vector<glm::dvec3>& table() const noexcept { return *table_; }

 private:
  static std::shared_ptr<const std::vector<glm::dvec3>> make_table(const Noise& noise, std::uint32_t table_seed) {
    auto t = std::make_shared<std::vector<glm::dvec3>>(Size);
    for (std::size_t i = 0; i < Size; ++i)
      (*t)[i] = noise.sample(table_seed, Cell{static_cast<std::uint32_t>(i), 0, 0});
    return t;
  }
  std::shared_ptr<const std::vector<glm::dvec3>> table_;
};

static_assert(NoiseSource<UniformNoise>);
static_assert(NoiseSource<GaussianNoise>);
static_assert(NoiseSource<LaplacianNoise>);
static_assert(NoiseSource<MultivariateGaussianNoise>);
static_assert(NoiseSource<GaussianMixtureNoise>);
static_assert(NoiseSource<TabulatedNoise<GaussianNoise>>);

}  // namespace hapticfield::texture
