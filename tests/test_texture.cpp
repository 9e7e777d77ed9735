// Tests of the texture generators and forces: noise primitives, lattices,
// local sphere, fBm, Fourier synthesis, texture / friction / flow fields,
// data visualisation and false texturing.
//
// Statistical checks use 1e6 seeded samples and 5-sigma bounds computed from
// the known distribution (chance of a false failure ~6e-7 per check; the
// seeds are fixed, so a run is deterministic anyway).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <set>
#include <vector>

#include "hapticfield/core.hpp"
#include "hapticfield/texture/data_texture.hpp"
#include "hapticfield/texture/fft.hpp"
#include "hapticfield/texture/friction.hpp"
#include "hapticfield/texture/lattice.hpp"
#include "hapticfield/texture/local_sphere.hpp"
#include "hapticfield/texture/noise.hpp"
#include "hapticfield/texture/spectral.hpp"
#include "hapticfield/texture/texture_field.hpp"
#if HAPTICFIELD_TEST_IMAGE_MAPS
#include "hapticfield/image/load.hpp"
#include "hapticfield/texture/image_maps.hpp"
#endif

using namespace hapticfield;
using namespace hapticfield::texture;
using Catch::Matchers::WithinAbs;

namespace {

constexpr int n_samples = 1'000'000;

Cell cell(int i) {
  return Cell{static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i / 977), 3u};
}

struct Moments {
  double mean{0}, var{0}, skew{0}, kurt{0}, mad{0};
};

template <class Fn>
Moments moments(Fn&& sample) {
  std::vector<double> x(n_samples);
  double sum = 0;
  for (int i = 0; i < n_samples; ++i)
    sum += (x[static_cast<std::size_t>(i)] = sample(i));
  Moments m;
  m.mean = sum / n_samples;
  double m2 = 0, m3 = 0, m4 = 0, ad = 0;
  for (double v : x) {
    const double d = v - m.mean;
    m2 += d * d;
    m3 += d * d * d;
    m4 += d * d * d * d;
    ad += std::fabs(d);
  }
  m2 /= n_samples;
  m.var = m2;
  m.skew = m3 / n_samples / std::pow(m2, 1.5);
  m.kurt = m4 / n_samples / (m2 * m2);
  m.mad = ad / n_samples;
  return m;
}

double five_sigma(double per_sample_variance) {
  return 5.0 * std::sqrt(per_sample_variance / n_samples);
}

Probe moving(glm::dvec3 p, glm::dvec3 v = {0.05, 0.0, 0.0}, double fn = 1.0) {
  Probe probe;
  probe.position = p;
  probe.velocity = v;
  probe.normal_force = fn;
  return probe;
}

}  // namespace

// --- noise primitives ---------------------------------------------------------

TEST_CASE("the permutation table is a permutation of 0..255") {
  std::set<int> seen;
  for (std::uint32_t i = 0; i < 256; ++i)
    seen.insert(permutation(i));
  REQUIRE(seen.size() == 256);
  REQUIRE(permutation(256) == permutation(0));  // indices wrap at 256
}

TEST_CASE("noise is a pure function of (seed, lattice point)") {
  const GaussianNoise g(1.0);
  for (int i = 0; i < 100; ++i) {
    const Cell c{static_cast<std::uint32_t>(i * 31), static_cast<std::uint32_t>(-i), 5};
    REQUIRE(g.sample(42, c) == g.sample(42, c));
    REQUIRE(hash(42, c.x, c.y, c.z) == hash(42, c.x, c.y, c.z));
    REQUIRE(g.sample(42, c) != g.sample(43, c));
  }
  // no period of 256 along an axis (the avalanche mix removes the table's period)
  REQUIRE(hash(1, 0, 0, 0) != hash(1, 256, 0, 0));
  REQUIRE(uniform01(1, Cell{0, 0, 0}) != uniform01(1, Cell{256, 0, 0}));
}

TEST_CASE("uniform01: mean 1/2, variance 1/12, range (0, 1)") {
  double lo = 1, hi = 0;
  const Moments m = moments([&](int i) {
    const double u = uniform01(7, cell(i));
    lo = std::min(lo, u);
    hi = std::max(hi, u);
    return u;
  });
  REQUIRE(lo > 0.0);
  REQUIRE(hi < 1.0);
  CHECK_THAT(m.mean, WithinAbs(0.5, five_sigma(1.0 / 12)));
  // Var of (u - 1/2)^2 for a uniform: 1/80 - 1/144
  CHECK_THAT(m.var, WithinAbs(1.0 / 12, five_sigma(1.0 / 80 - 1.0 / 144)));
}

TEST_CASE("Gaussian: mean 0, variance 1, skewness 0, kurtosis 3") {
  const Moments m = moments([](int i) { return gaussian(11, cell(i)); });
  CHECK_THAT(m.mean, WithinAbs(0.0, five_sigma(1.0)));
  CHECK_THAT(m.var, WithinAbs(1.0, five_sigma(2.0)));    // Var(g^2) = 2
  CHECK_THAT(m.skew, WithinAbs(0.0, five_sigma(6.0)));   // asymptotic SE^2 = 6/n
  CHECK_THAT(m.kurt, WithinAbs(3.0, five_sigma(24.0)));  // asymptotic SE^2 = 24/n
  CHECK_THAT(m.mad, WithinAbs(std::sqrt(2.0 / std::numbers::pi), five_sigma(1.0 - 2.0 / std::numbers::pi)));
}

TEST_CASE("GaussianNoise components are independent N(mean, sigma^2)") {
  const GaussianNoise g(0.5, 2.0);
  const Moments mx = moments([&](int i) { return g.sample(3, cell(i)).x; });
  const Moments mz = moments([&](int i) { return g.sample(3, cell(i)).z; });
  CHECK_THAT(mx.mean, WithinAbs(2.0, five_sigma(0.25)));
  CHECK_THAT(mz.var, WithinAbs(0.25, five_sigma(2.0 * 0.0625)));
  double cxy = 0;
  for (int i = 0; i < n_samples; ++i) {
    const glm::dvec3 s = g.sample(3, cell(i)) - 2.0;
    cxy += s.x * s.y;
  }
  CHECK_THAT(cxy / n_samples, WithinAbs(0.0, five_sigma(0.0625)));
}

TEST_CASE("Laplacian: unit variance, kurtosis 6, mean |x| = 1/sqrt(2)") {
  const Moments m = moments([](int i) { return laplacian(5, cell(i)); });
  CHECK_THAT(m.mean, WithinAbs(0.0, five_sigma(1.0)));
  CHECK_THAT(m.var, WithinAbs(1.0, five_sigma(5.0)));  // Var(x^2) = E x^4 - 1 = 6 - 1
  // E x^8 = 8! b^8 = 2520 with b^2 = 1/2; kurtosis SE^2 ~ Var(x^4)/n = (2520 - 36)/n
  CHECK_THAT(m.kurt, WithinAbs(6.0, five_sigma(2520.0 - 36.0)));
  CHECK_THAT(m.mad, WithinAbs((1.0 / std::numbers::sqrt2), five_sigma(0.5)));
}

TEST_CASE("multivariate Gaussian reproduces a full covariance") {
  // symmetric positive definite, with strong correlations
  glm::dmat3 c{0.0};
  const double cov[3][3] = {{4.0, 1.2, -0.8}, {1.2, 2.0, 0.5}, {-0.8, 0.5, 1.0}};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      c[k][r] = cov[r][k];
  const glm::dvec3 mean{0.1, -0.2, 0.3};
  const MultivariateGaussianNoise mv(mean, c);
  std::vector<glm::dvec3> s(n_samples);
  glm::dvec3 sum{0.0};
  for (int i = 0; i < n_samples; ++i)
    sum += (s[static_cast<std::size_t>(i)] = mv.sample(9, cell(i)));
  const glm::dvec3 m = sum / double(n_samples);
  for (int r = 0; r < 3; ++r)
    CHECK_THAT(m[r], WithinAbs(mean[r], five_sigma(cov[r][r])));
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) {
      double e = 0;
      for (const auto& v : s)
        e += (v[r] - m[r]) * (v[k] - m[k]);
      e /= n_samples;
      // Var of (x_r x_k) for a Gaussian pair: s_rr s_kk + s_rk^2
      CHECK_THAT(e, WithinAbs(cov[r][k], five_sigma(cov[r][r] * cov[k][k] + cov[r][k] * cov[r][k])));
    }
}

TEST_CASE("zero variance in z gives a lateral-only texture") {
  glm::dmat3 c{0.0};
  c[0][0] = 1.0;
  c[1][1] = 2.0;
  c[0][1] = c[1][0] = 0.5;
  const MultivariateGaussianNoise mv(glm::dvec3{0.0}, c);
  for (int i = 0; i < 1000; ++i)
    REQUIRE(mv.sample(1, cell(i)).z == 0.0);
}

TEST_CASE("bad noise parameters throw at setup") {
  CHECK_THROWS_AS(GaussianNoise(-1.0), std::invalid_argument);
  CHECK_THROWS_AS(GaussianNoise::from_variance(-0.1), std::invalid_argument);
  CHECK_THROWS_AS(LaplacianNoise(-1.0), std::invalid_argument);
  CHECK_THROWS_AS(UniformNoise(1.0, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(GaussianNoise(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  glm::dmat3 indefinite{1.0};
  indefinite[0][1] = indefinite[1][0] = 2.0;  // eigenvalues 3 and -1
  CHECK_THROWS_AS(MultivariateGaussianNoise(glm::dvec3{0.0}, indefinite), std::invalid_argument);
  glm::dmat3 negative{1.0};
  negative[2][2] = -1.0;
  CHECK_THROWS_AS(MultivariateGaussianNoise(glm::dvec3{0.0}, negative), std::invalid_argument);
  glm::dmat3 asymmetric{1.0};
  asymmetric[0][1] = 0.3;
  CHECK_THROWS_AS(MultivariateGaussianNoise(glm::dvec3{0.0}, asymmetric), std::invalid_argument);
  glm::dmat3 zero_var_but_correlated{1.0};
  zero_var_but_correlated[2][2] = 0.0;
  zero_var_but_correlated[0][2] = zero_var_but_correlated[2][0] = 0.5;  // not PSD
  CHECK_THROWS_AS(MultivariateGaussianNoise(glm::dvec3{0.0}, zero_var_but_correlated), std::invalid_argument);
  CHECK_THROWS_AS(GaussianMixtureNoise({}), std::invalid_argument);
  CHECK_THROWS_AS(GaussianMixtureNoise({{-1.0, glm::dvec3{0.0}, glm::dmat3{1.0}}}), std::invalid_argument);
  CHECK_THROWS_AS(GaussianMixtureNoise({{1.0, glm::dvec3{0.0}, indefinite}}), std::invalid_argument);
}

TEST_CASE("Gaussian mixture: mean and variance of the mixture") {
  // 1D check on x: w = (0.25, 0.75), means (-2, 1), variances (0.5, 0.1)
  glm::dmat3 c1{0.5}, c2{0.1};
  const GaussianMixtureNoise mix({{1.0, glm::dvec3{-2.0}, c1}, {3.0, glm::dvec3{1.0}, c2}});
  const double mean = 0.25 * -2.0 + 0.75 * 1.0;
  const double second = 0.25 * (0.5 + 4.0) + 0.75 * (0.1 + 1.0);
  const double var = second - mean * mean;
  const Moments m = moments([&](int i) { return mix.sample(21, cell(i)).x; });
  CHECK_THAT(m.mean, WithinAbs(mean, five_sigma(var)));
  // 4th central moment of the mixture bounds Var(x^2); use a generous 20 * var^2
  CHECK_THAT(m.var, WithinAbs(var, five_sigma(20.0 * var * var)));
  // fraction in the first component: x < -0.5 (both components ~5 sigma away)
  // P(x < -0.5) = 0.25 Phi(1.5 / sqrt 0.5) + 0.75 Phi(-1.5 / sqrt 0.1)
  const auto phi = [](double z) { return 0.5 * std::erfc(-z / std::numbers::sqrt2); };
  const double p_low = 0.25 * phi(1.5 / std::sqrt(0.5)) + 0.75 * phi(-1.5 / std::sqrt(0.1));
  int low = 0;
  for (int i = 0; i < n_samples; ++i)
    low += mix.sample(21, cell(i)).x < -0.5;
  CHECK_THAT(double(low) / n_samples, WithinAbs(p_low, five_sigma(p_low * (1.0 - p_low))));
}

TEST_CASE("tabulated noise: a hashed table of samples of the wrapped noise, read uniformly") {
  const GaussianNoise g(1.0);
  const TabulatedNoise<GaussianNoise, 1024> t(g, 77);
  REQUIRE(t.table().size() == 1024);
  for (std::uint32_t i = 0; i < 1024; ++i)
    REQUIRE(t.table()[i] == g.sample(77, Cell{i, 0, 0}));
  std::vector<int> hits(1024, 0);
  int not_in_table = 0, not_repeatable = 0;
  for (int i = 0; i < 200000; ++i) {
    const glm::dvec3 v = t.sample(5, cell(i));
    not_repeatable += v != t.sample(5, cell(i));
    // which entry was read (entries are distinct with probability ~1)
    const auto it = std::find(t.table().begin(), t.table().end(), v);
    if (it == t.table().end())
      ++not_in_table;
    else
      ++hits[static_cast<std::size_t>(it - t.table().begin())];
  }
  REQUIRE(not_in_table == 0);
  REQUIRE(not_repeatable == 0);
  // chi-square of 200000 reads over 1024 entries: 1023 dof, mean 1023, sd 45.2
  double chi2 = 0;
  const double expect = 200000.0 / 1024.0;
  for (int h : hits)
    chi2 += (h - expect) * (h - expect) / expect;
  CHECK_THAT(chi2, WithinAbs(1023.0, 5.0 * 45.2));
  const NoiseLattice<TabulatedNoise<GaussianNoise, 1024>, 3> lat(t, 1, glm::dvec3{1e-3}, Interpolation::cubic);
  REQUIRE(is_finite(lat(glm::dvec3{0.3e-3, 1.7e-3, -2.2e-3})));
}

// --- lattices -------------------------------------------------------------------

TEST_CASE("lattices interpolate through the lattice samples") {
  const GaussianNoise g(1.0);
  const glm::dvec3 grain{1e-3, 2e-3, 4e-3};
  for (auto mode : {Interpolation::nearest, Interpolation::linear, Interpolation::cubic}) {
    const NoiseLattice<GaussianNoise, 3> lat(g, 99, grain, mode);
    for (int i = -3; i < 3; ++i) {
      const glm::dvec3 p{i * grain.x, (i + 1) * grain.y, (2 - i) * grain.z};
      const glm::dvec3 expect = g.sample(99, Cell{static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i + 1),
                                                  static_cast<std::uint32_t>(2 - i)});
      const glm::dvec3 got = lat(p);
      for (int k = 0; k < 3; ++k)
        REQUIRE_THAT(got[k], WithinAbs(expect[k], 1e-9));
    }
  }
}

TEST_CASE("2D lattices ignore z; per-axis grain stretches the pattern") {
  const NoiseLattice<GaussianNoise, 2> lat(GaussianNoise(1.0), 5, glm::dvec3{1e-3, 3e-3, 1.0}, Interpolation::cubic);
  const glm::dvec3 p{0.37e-3, 1.3e-3, 0.0};
  REQUIRE(lat(p) == lat(p + glm::dvec3{0, 0, 0.123}));
  const NoiseLattice<GaussianNoise, 2> stretched(GaussianNoise(1.0), 5, glm::dvec3{2e-3, 6e-3, 1.0},
                                                 Interpolation::cubic);
  REQUIRE(glm::length(stretched(2.0 * p) - lat(p)) < 1e-12);
  CHECK_THROWS_AS((NoiseLattice<GaussianNoise, 3>(GaussianNoise(1.0), 1, glm::dvec3{1e-3, 0.0, 1e-3})),
                  std::invalid_argument);
  REQUIRE(lat(glm::dvec3{std::numeric_limits<double>::quiet_NaN(), 0, 0}) == glm::dvec3{0.0});
  REQUIRE(lat(glm::dvec3{1e300, 0, 0}) == glm::dvec3{0.0});
}

TEST_CASE("linear and cubic lattices are continuous; cubic also in the first derivative") {
  const double grain = 1e-3;
  const NoiseLattice<GaussianNoise, 3> lin(GaussianNoise(1.0), 8, glm::dvec3{grain}, Interpolation::linear);
  const NoiseLattice<GaussianNoise, 3> cub(GaussianNoise(1.0), 8, glm::dvec3{grain}, Interpolation::cubic);
  const NoiseLattice<GaussianNoise, 3> near(GaussianNoise(1.0), 8, glm::dvec3{grain}, Interpolation::nearest);
  const double h = 1e-9;  // [m], 1e-6 of a cell
  int linear_kinks = 0, nearest_jumps = 0;
  for (int i = -20; i < 20; ++i) {
    // cross the x cell edge at an off-lattice y, z
    const glm::dvec3 edge{i * grain, 0.3 * grain, 0.7 * grain};
    const glm::dvec3 e{h, 0, 0};
    for (int k = 0; k < 3; ++k) {
      REQUIRE(std::fabs(lin(edge - e)[k] - lin(edge + e)[k]) < 1e-5);
      REQUIRE(std::fabs(cub(edge - e)[k] - cub(edge + e)[k]) < 1e-5);
      // one-sided slopes [1/cell] on either side of the edge
      const double step = 1e-4 * grain;
      const double cl = (cub(edge)[k] - cub(edge - glm::dvec3{step, 0, 0})[k]) / 1e-4;
      const double cr = (cub(edge + glm::dvec3{step, 0, 0})[k] - cub(edge)[k]) / 1e-4;
      REQUIRE(std::fabs(cl - cr) < 1e-2);
      const double ll = (lin(edge)[k] - lin(edge - glm::dvec3{step, 0, 0})[k]) / 1e-4;
      const double lr = (lin(edge + glm::dvec3{step, 0, 0})[k] - lin(edge)[k]) / 1e-4;
      linear_kinks += std::fabs(ll - lr) > 1e-2;
    }
    const glm::dvec3 mid{(i + 0.5) * grain, 0.0, 0.0};
    nearest_jumps += glm::length(near(mid - glm::dvec3{h, 0, 0}) - near(mid + glm::dvec3{h, 0, 0})) > 1e-3;
  }
  // the derivative test can fail: linear interpolation has kinks at edges
  REQUIRE(linear_kinks > 60);
  REQUIRE(nearest_jumps > 30);
}

// --- local sphere -------------------------------------------------------------------

TEST_CASE("local sphere draws a new sample each time the HIP leaves the ball") {
  const double r = 1e-3;
  LocalSphere<GaussianNoise> ls(GaussianNoise(1.0), 4, r);
  glm::dvec3 prev = ls.sample(glm::dvec3{0.0});
  REQUIRE(ls.samples_drawn() == 2);
  const double step = 1e-5;
  double largest_jump = 0;
  // 10.5 mm along x in 10 um steps: each exit happens within one step past
  // r, so the exits are at about 1.01, 2.02, ..., 10.1 mm: 10 new samples
  for (int i = 1; i <= 1050; ++i) {
    const glm::dvec3 v = ls.sample(glm::dvec3{i * step, 0, 0});
    largest_jump = std::max(largest_jump, glm::length(v - prev));
    prev = v;
  }
  CHECK(ls.samples_drawn() == 2 + 10);
  // continuous: a 10 um step moves the value by about (10 um / r) |a - b|
  CHECK(largest_jump < 0.1);
  // repeatable after reset
  ls.reset();
  const glm::dvec3 a = ls.sample(glm::dvec3{0.0});
  ls.reset();
  REQUIRE(ls.sample(glm::dvec3{0.0}) == a);
}

TEST_CASE("local circle: motion along the surface normal draws no sample") {
  LocalSphere<GaussianNoise> lc(GaussianNoise(1.0), 4, 1e-3, glm::dvec3{0, 0, 1});
  (void)lc.sample(glm::dvec3{0.0});
  for (int i = 0; i < 100; ++i)
    (void)lc.sample(glm::dvec3{0, 0, i * 1e-3});
  REQUIRE(lc.samples_drawn() == 2);
  (void)lc.sample(glm::dvec3{2e-3, 0, 0.5});
  REQUIRE(lc.samples_drawn() == 3);
  CHECK_THROWS_AS(LocalSphere<GaussianNoise>(GaussianNoise(1.0), 1, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(LocalSphere<GaussianNoise>(GaussianNoise(1.0), 1, 1e-3, glm::dvec3{0, 0, 2}), std::invalid_argument);
}

// --- fBm spectrum -------------------------------------------------------------------

TEST_CASE("fft equals the DFT computed term by term") {
  std::vector<std::complex<double>> x(64);
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = {std::sin(0.37 * double(i * i)), std::cos(1.3 * double(i))};
  std::vector<std::complex<double>> fast = x;
  fft(fast);
  for (std::size_t k = 0; k < x.size(); ++k) {
    std::complex<double> direct{0.0, 0.0};
    for (std::size_t n = 0; n < x.size(); ++n)
      direct += x[n] * std::polar(1.0, -2.0 * std::numbers::pi * double(k * n) / double(x.size()));
    REQUIRE(std::abs(fast[k] - direct) <= 1e-9);
  }
  std::vector<std::complex<double>> bad(48);
  CHECK_THROWS_AS(fft(bad), std::invalid_argument);
}

namespace {
// least-squares slope of log10 PSD vs log10 f over [f_lo, f_hi], with the
// Welch-averaged periodogram binned in equal log-frequency bins.
double fbm_slope(double h, int octaves) {
  const double grain = 1e-3;
  const NoiseLattice<GaussianNoise, 2> base(GaussianNoise(1.0), 77, glm::dvec3{grain}, Interpolation::linear);
  const Fbm<GaussianNoise, 2> fbm(base, h, octaves);
  // 512 samples per base cell: Nyquist (256 cycles per cell) lies above the
  // top octave (2^(octaves-1) cycles per cell for octaves = 8), so no octave aliases
  const std::size_t seg = 4096;
  const double per_cell = 512.0;
  const double dx = grain / per_cell;
  const int segments = 32;
  std::vector<double> psd(seg / 2, 0.0);
  for (int s = 0; s < segments; ++s) {
    std::vector<std::complex<double>> a(seg);
    for (std::size_t i = 0; i < seg; ++i) {
      const double x = (double(s) * seg + double(i)) * dx;
      const double hann = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * double(i) / double(seg));
      // along the lattice line y = 0: off a line, the y blend weight (and so
      // the variance) of each octave would differ, tilting the spectrum
      a[i] = hann * fbm(glm::dvec3{x, 0.0, 0.0}).x;
    }
    fft(a);
    for (std::size_t k = 0; k < seg / 2; ++k)
      psd[k] += std::norm(a[k]);
  }
  // frequencies in cycles per base cell: k / (seg dx / grain) = k per_cell / seg
  // fit from 1/2 cycle per cell up to 2^(octaves-3) cycles per cell (away
  // from both ends of the octave stack)
  const double f_lo = 0.5, f_hi = std::pow(2.0, octaves - 3);
  std::vector<double> lx, ly;
  const int bins = 24;
  for (int b = 0; b < bins; ++b) {
    const double l0 = std::log10(f_lo) + (std::log10(f_hi) - std::log10(f_lo)) * b / bins;
    const double l1 = std::log10(f_lo) + (std::log10(f_hi) - std::log10(f_lo)) * (b + 1) / bins;
    double sx = 0, sp = 0;
    int count = 0;
    for (std::size_t k = 1; k < seg / 2; ++k) {
      const double f = double(k) * per_cell / double(seg);
      if (std::log10(f) >= l0 && std::log10(f) < l1) {
        sx += std::log10(f);
        sp += psd[k];
        ++count;
      }
    }
    if (count > 0) {
      lx.push_back(sx / count);
      ly.push_back(std::log10(sp / count));
    }
  }
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < lx.size(); ++i)
    mx += lx[i], my += ly[i];
  mx /= double(lx.size());
  my /= double(ly.size());
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < lx.size(); ++i)
    sxy += (lx[i] - mx) * (ly[i] - my), sxx += (lx[i] - mx) * (lx[i] - mx);
  return sxy / sxx;
}
}  // namespace

TEST_CASE("fBm power spectrum falls as f^-(2h+1) (within 0.1)") {
  for (double h : {0.3, 0.5, 0.8}) {
    const double slope = fbm_slope(h, 8);
    INFO("h = " << h << ", measured slope " << slope << ", expected " << -(2 * h + 1));
    CHECK_THAT(slope, WithinAbs(-(2.0 * h + 1.0), 0.1));
  }
  CHECK_THROWS_AS(
      (Fbm<GaussianNoise, 3>(NoiseLattice<GaussianNoise, 3>(GaussianNoise(1.0), 1, glm::dvec3{1e-3}), -0.1, 4)),
      std::invalid_argument);
  CHECK_THROWS_AS(
      (Fbm<GaussianNoise, 3>(NoiseLattice<GaussianNoise, 3>(GaussianNoise(1.0), 1, glm::dvec3{1e-3}), 0.5, 0)),
      std::invalid_argument);
}

// --- Fourier synthesis -----------------------------------------------------------------

TEST_CASE("Fourier synthesis of sine, square and sawtooth terms") {
  const FourierSynthesis sine({{Waveform::sine, 0.5, 200.0, 0.25, glm::dvec3{1, 0, 0}}}, glm::dvec3{0, 1, 0});
  for (double x : {0.0, 1.1e-3, 2.7e-3, -4e-3}) {
    const glm::dvec3 v = sine(glm::dvec3{x, 5.0, 7.0});
    CHECK_THAT(v.y, WithinAbs(0.5 * std::sin(2 * std::numbers::pi * 200.0 * x + 0.25), 1e-12));
    CHECK(v.x == 0.0);
  }
  const FourierSynthesis square({{Waveform::square, 1.0, 100.0, 0.0, glm::dvec3{0, 1, 0}}});
  CHECK(square(glm::dvec3{0, 1e-3, 0}).z == 1.0);   // phase 0.2 pi
  CHECK(square(glm::dvec3{0, 6e-3, 0}).z == -1.0);  // phase 1.2 pi
  const FourierSynthesis saw({{Waveform::sawtooth, 2.0, 100.0, 0.0, glm::dvec3{1, 0, 0}}});
  CHECK_THAT(saw(glm::dvec3{2.5e-3, 0, 0}).z, WithinAbs(2.0 * (2.0 * 0.25 - 1.0), 1e-12));
  CHECK_THAT(saw(glm::dvec3{7.5e-3, 0, 0}).z, WithinAbs(2.0 * (2.0 * 0.75 - 1.0), 1e-9));
  // sum of terms
  const FourierSynthesis both(
      {{Waveform::sine, 1.0, 50.0, 0.0, glm::dvec3{1, 0, 0}}, {Waveform::sine, 0.3, 150.0, 1.0, glm::dvec3{1, 0, 0}}});
  const double x = 1.7e-3;
  CHECK_THAT(
      both(glm::dvec3{x, 0, 0}).z,
      WithinAbs(std::sin(2 * std::numbers::pi * 50 * x) + 0.3 * std::sin(2 * std::numbers::pi * 150 * x + 1.0), 1e-12));
  CHECK_THROWS_AS(FourierSynthesis({}), std::invalid_argument);
  CHECK_THROWS_AS(FourierSynthesis({{Waveform::sine, 1.0, -5.0, 0.0, glm::dvec3{1, 0, 0}}}), std::invalid_argument);
  CHECK_THROWS_AS(FourierSynthesis({{Waveform::sine, 1.0, 5.0, 0.0, glm::dvec3{1, 1, 0}}}), std::invalid_argument);
}

TEST_CASE("modulated texture Ft = S g + N") {
  const FourierSynthesis g({{Waveform::sine, 1.0, 100.0, 0.0, glm::dvec3{1, 0, 0}}});
  const NoiseLattice<GaussianNoise, 2> mul(GaussianNoise(0.2), 1, glm::dvec3{1e-3}, Interpolation::linear);
  const NoiseLattice<GaussianNoise, 2> add(GaussianNoise(0.05), 2, glm::dvec3{1e-3}, Interpolation::linear);
  const ModulatedTexture<FourierSynthesis, decltype(mul), decltype(add)> ft(g, 2.0, mul, add);
  for (double x : {0.3e-3, 1.7e-3, 4.1e-3}) {
    const glm::dvec3 p{x, 0.2e-3, 0};
    const glm::dvec3 expect = (2.0 + mul(p).x) * g(p) + add(p);
    REQUIRE(glm::length(ft(p) - expect) < 1e-15);
  }
}

// --- texture fields ----------------------------------------------------------------------

TEST_CASE("texture is silent at rest and below the velocity threshold") {
  TextureField field(TemporalSource(GaussianNoise(1.0), 3), TextureConfig{0.5, 2e-3, false, glm::dvec3{1.0}});
  REQUIRE(field.force(moving(glm::dvec3{0.0}, glm::dvec3{0.0})) == glm::dvec3{0.0});
  REQUIRE(field.force(moving(glm::dvec3{0.0}, glm::dvec3{1e-3, 1e-3, 0})) == glm::dvec3{0.0});
  REQUIRE(glm::length(field.force(moving(glm::dvec3{0.0}, glm::dvec3{0.01, 0, 0}))) > 0.0);
  // non-finite input: zero
  REQUIRE(field.force(moving(glm::dvec3{std::numeric_limits<double>::quiet_NaN()})) == glm::dvec3{0.0});
  REQUIRE(field.force(moving(glm::dvec3{0.0}, glm::dvec3{std::numeric_limits<double>::infinity(), 0, 0})) ==
          glm::dvec3{0.0});
  CHECK_THROWS_AS(TextureField(TemporalSource(GaussianNoise(1.0), 3), TextureConfig{1.0, -1.0, false, glm::dvec3{1.0}}),
                  std::invalid_argument);
}

TEST_CASE("temporal texture is repeatable per seed and scales with |Fc|") {
  const TextureConfig params{0.5, 0.0, true, glm::dvec3{1.0, 1.0, 0.0}};
  TextureField a(TemporalSource(GaussianNoise(1.0), 3), params);
  TextureField b(TemporalSource(GaussianNoise(1.0), 3), params);
  for (int i = 0; i < 50; ++i) {
    const glm::dvec3 fa = a.force(moving(glm::dvec3{0.0}, glm::dvec3{0.1, 0, 0}, 1.0));
    const glm::dvec3 fb = b.force(moving(glm::dvec3{0.0}, glm::dvec3{0.1, 0, 0}, 3.0));
    REQUIRE(glm::length(fb - 3.0 * fa) < 1e-12);
    REQUIRE(fa.z == 0.0);  // lateral only
  }
  a.reset();
  TextureField c(TemporalSource(GaussianNoise(1.0), 3), params);
  REQUIRE(a.force(moving(glm::dvec3{0.0})) == c.force(moving(glm::dvec3{0.0})));
}

TEST_CASE("spatial texture: the same spot feels the same; distance source follows the path") {
  const NoiseLattice<GaussianNoise, 2> lat(GaussianNoise(1.0), 9, glm::dvec3{5e-4}, Interpolation::cubic);
  TextureField spatial{SpatialSource(lat), TextureConfig{}};
  const glm::dvec3 p{1.23e-3, -4.5e-3, 0.0};
  const glm::dvec3 f1 = spatial.force(moving(p, glm::dvec3{0.02, 0, 0}));
  (void)spatial.force(moving(p + glm::dvec3{3e-3, 0, 0}));
  REQUIRE(spatial.force(moving(p, glm::dvec3{-0.02, 0.01, 0})) == f1);

  TextureField along{DistanceSource(lat), TextureConfig{}};
  (void)along.force(moving(glm::dvec3{0.0}));
  (void)along.force(moving(glm::dvec3{0.0, 3e-3, 0.0}));
  const glm::dvec3 f = along.force(moving(glm::dvec3{4e-3, 3e-3, 0.0}));
  REQUIRE(along.source().distance() == Approx(7e-3));
  REQUIRE(glm::length(f - lat(glm::dvec3{7e-3, 0, 0})) < 1e-9);
}

TEST_CASE("friction opposes velocity and follows c s(|v|) + b|v| + d|v|^2") {
  const FrictionConfig p{0.4, 2.0, 10.0, 1e-3, false, glm::dvec3{0.0}};
  const Friction fr(p);
  for (int i = 0; i < 200; ++i) {
    const glm::dvec3 v{std::sin(i * 1.3) * 0.2, std::cos(i * 0.7) * 0.1, std::sin(i * 2.9) * 0.05};
    Probe probe = moving(glm::dvec3{0.0}, v);
    const glm::dvec3 f = fr.force(probe);
    const double speed = glm::length(v);
    REQUIRE(glm::dot(f, v) < 0.0);
    REQUIRE(glm::length(glm::cross(f, v)) < 1e-12 * glm::length(f) * speed + 1e-15);
    const double expect = 0.4 * speed / std::sqrt(speed * speed + 1e-6) + 2.0 * speed + 10.0 * speed * speed;
    REQUIRE_THAT(glm::length(f), WithinAbs(expect, 1e-12));
  }
  REQUIRE(fr.force(moving(glm::dvec3{0.0}, glm::dvec3{0.0})) == glm::dvec3{0.0});
}

TEST_CASE("Coulomb friction does not chatter near zero speed") {
  const Friction fr(FrictionConfig{1.0, 0.0, 0.0, 1e-3, false, glm::dvec3{0.0}});
  // a hand jittering at +-1 um/s: the force stays tiny instead of flipping +-1 N
  for (double v : {1e-6, -1e-6, 5e-7, -5e-7})
    REQUIRE(std::fabs(fr.force(moving({}, {v, 0, 0})).x) < 1.1e-3);
  // continuous in v: the largest change between neighbouring speeds is small
  double worst = 0;
  for (int i = -1000; i < 1000; ++i) {
    const double a = fr.force(moving({}, {i * 1e-6, 0, 0})).x;
    const double b = fr.force(moving({}, {(i + 1) * 1e-6, 0, 0})).x;
    worst = std::max(worst, std::fabs(a - b));
  }
  REQUIRE(worst < 1.1e-3);
  // far from zero it is the full Coulomb force
  REQUIRE_THAT(fr.force(moving({}, {0.1, 0, 0})).x, WithinAbs(-1.0, 1e-4));
}

TEST_CASE("friction scaled by |Fc| and restricted to the tangent plane") {
  const Friction fr(FrictionConfig{0.5, 0.0, 0.0, 1e-4, true, glm::dvec3{0, 0, 1}});
  const glm::dvec3 f = fr.force(moving({}, {0.1, 0.0, -0.3}, 2.0));
  REQUIRE_THAT(f.x, WithinAbs(-1.0, 1e-5));
  REQUIRE(f.z == 0.0);
  CHECK_THROWS_AS(Friction(FrictionConfig{-0.1, 0, 0, 1e-3, false, glm::dvec3{0.0}}), std::invalid_argument);
  CHECK_THROWS_AS(Friction(FrictionConfig{0.1, 0, 0, 0.0, false, glm::dvec3{0.0}}), std::invalid_argument);
  REQUIRE(fr.force(moving({}, {std::numeric_limits<double>::quiet_NaN(), 0, 0})) == glm::dvec3{0.0});
}

TEST_CASE("stick-slip friction: spring while stuck, kinetic limit while sliding, quiet at rest") {
  StickSlipFriction fr(StickSlipConfig{2000.0, 0.5, 0.4, true, glm::dvec3{0, 0, 1}});
  const auto at = [](double x, double fn = 1.0) { return moving(glm::dvec3{x, 0.0, 0.0}, glm::dvec3{0.0}, fn); };
  REQUIRE(fr.force(at(0.0)) == glm::dvec3{0.0});
  // stuck: 0.1 mm stretch -> 0.2 N back toward the anchor (below mu_s |Fc| = 0.5 N)
  CHECK_THAT(fr.force(at(1e-4)).x, WithinAbs(-0.2, 1e-12));
  CHECK_FALSE(fr.sliding());
  CHECK(fr.force(at(0.0)) == glm::dvec3{0.0});
  // slide: push 3 mm in 10 um steps; breakaway past 0.25 mm, then 0.4 N opposing +x
  glm::dvec3 f{0.0};
  for (int i = 1; i <= 300; ++i)
    f = fr.force(at(i * 1e-5));
  CHECK(fr.sliding());
  CHECK_THAT(f.x, WithinAbs(-0.4, 1e-12));
  CHECK_THAT(fr.anchor().x, WithinAbs(3e-3 - 0.4 / 2000.0, 1e-12));
  // jitter of +-1 um at the end: the force moves by at most k * 2 um, never flips to +0.4 N
  double lo = 1, hi = -1;
  for (int i = 0; i < 100; ++i) {
    const double x = 3e-3 + (i % 2 ? 1e-6 : -1e-6);
    const double fx = fr.force(at(x)).x;
    lo = std::min(lo, fx), hi = std::max(hi, fx);
  }
  CHECK(hi - lo <= 2000.0 * 2e-6 + 1e-12);
  CHECK(hi < 0.0);
  // reversing: stuck again, then slides the other way with +0.4 N
  for (int i = 1; i <= 300; ++i)
    f = fr.force(at(3e-3 - i * 1e-5));
  CHECK_THAT(f.x, WithinAbs(0.4, 1e-12));
  // no normal force: no friction
  CHECK_THAT(glm::length(fr.force(at(0.0, 0.0))), WithinAbs(0.0, 1e-15));
  CHECK_THROWS_AS(StickSlipFriction(StickSlipConfig{2000.0, 0.3, 0.4, true, glm::dvec3{0, 0, 1}}),
                  std::invalid_argument);
  CHECK_THROWS_AS(StickSlipFriction(StickSlipConfig{0.0, 0.5, 0.4, true, glm::dvec3{0, 0, 1}}), std::invalid_argument);
  CHECK(fr.force(moving(glm::dvec3{std::numeric_limits<double>::quiet_NaN()})) == glm::dvec3{0.0});
}

TEST_CASE("F = Fc + Ft + Ff composes through sum()") {
  struct Wall {  // penalty wall at z = 0, k = 500 N/m
    glm::dvec3 force(const Probe& p) const noexcept {
      return p.position.z < 0 ? glm::dvec3{0, 0, -500.0 * p.position.z} : glm::dvec3{0.0};
    }
  };
  const NoiseLattice<GaussianNoise, 2> lat(GaussianNoise(1.0), 9, glm::dvec3{5e-4}, Interpolation::linear);
  auto total = sum(Wall{}, TextureField(SpatialSource(lat), TextureConfig{0.2, 1e-3, true, glm::dvec3{1, 1, 0}}),
                   Friction(FrictionConfig{0.3, 0, 0, 1e-3, true, glm::dvec3{0, 0, 1}}));
  Probe p = moving(glm::dvec3{1e-3, 2e-3, -2e-3}, glm::dvec3{0.05, 0, 0}, 1.0);
  const glm::dvec3 f = total.force(p);
  const glm::dvec3 expect = Wall{}.force(p) + 0.2 * glm::dvec3{lat(p.position).x, lat(p.position).y, 0.0} +
                            Friction(FrictionConfig{0.3, 0, 0, 1e-3, true, glm::dvec3{0, 0, 1}}).force(p);
  REQUIRE(glm::length(f - expect) < 1e-12);
  AnyField erased = std::move(total);
  REQUIRE(glm::length(erased.force(p) - expect) < 1e-12);
}

TEST_CASE("flow texture: mean shift pushes, viscous drag resists") {
  const NoiseLattice<GaussianNoise, 3> lat(GaussianNoise(1.0), 2, glm::dvec3{2e-3}, Interpolation::cubic);
  const FlowTexture flow(lat, FlowConfig{glm::dvec3{0.2, 0, 0}, 0.1, 3.0});
  const glm::dvec3 p{1e-3, 2e-3, 3e-3};
  const glm::dvec3 at_rest = flow.force(moving(p, glm::dvec3{0.0}));
  REQUIRE(glm::length(at_rest - (glm::dvec3{0.2, 0, 0} + 0.1 * lat(p))) < 1e-15);
  const glm::dvec3 v{0.0, 0.1, 0.0};
  REQUIRE(glm::length(flow.force(moving(p, v)) - (at_rest - 3.0 * v)) < 1e-15);
  // mean over space is the shift
  glm::dvec3 mean{0.0};
  for (int i = 0; i < 20000; ++i)
    mean += flow.force(moving(glm::dvec3{i * 0.77e-3, i * 0.31e-3, i * 0.13e-3}, {}));
  mean /= 20000.0;
  REQUIRE_THAT(mean.x, WithinAbs(0.2, 0.01));
  CHECK_THROWS_AS(FlowTexture(lat, FlowConfig{glm::dvec3{0.0}, 1.0, -1.0}), std::invalid_argument);
}

// --- data visualisation and false texturing --------------------------------------------------

TEST_CASE("data value modulates texture amplitude and friction") {
  // 2 x 1 map: left pixel 0, right pixel 1; 1 px per mm, pixel 0 at x = 0
  const PlaneMapping mapping(1.0, glm::dvec2{0.0, 0.0});
  const ScalarMap map(2, 1, {0.0f, 1.0f}, mapping);
  CHECK_THAT(map.value(glm::dvec3{0.0}), WithinAbs(0.0, 1e-12));
  CHECK_THAT(map.value(glm::dvec3{1e-3, 0, 0}), WithinAbs(1.0, 1e-12));
  CHECK_THAT(map.value(glm::dvec3{0.25e-3, 0, 0}), WithinAbs(0.25, 1e-12));
  CHECK(map.value(glm::dvec3{5e-3, 0, 0}, -1.0) == -1.0);
  DataModulated friction(Friction(FrictionConfig{1.0, 0, 0, 1e-4, false, glm::dvec3{0.0}}), map, 0.2, 0.8);
  const glm::dvec3 v{0.1, 0, 0};
  CHECK_THAT(friction.force(moving(glm::dvec3{0.0}, v)).x, WithinAbs(-0.2, 1e-5));
  CHECK_THAT(friction.force(moving(glm::dvec3{1e-3, 0, 0}, v)).x, WithinAbs(-1.0, 1e-5));
  CHECK_THROWS_AS(ScalarMap(2, 2, {0.0f}, mapping), std::invalid_argument);
}

TEST_CASE("false texturing: each label gets its own texture") {
  const PlaneMapping mapping(1.0, glm::dvec2{0.0, 0.0});
  const LabelMap labels(3, 1, {0, 1, 2}, mapping);
  struct Constant {
    glm::dvec3 f;
    glm::dvec3 force(const Probe&) const noexcept { return f; }
  };
  std::vector<AnyField> textures;
  textures.emplace_back();  // label 0: smooth
  textures.emplace_back(Constant{glm::dvec3{1, 0, 0}});
  textures.emplace_back(Constant{glm::dvec3{0, 2, 0}});
  FalseTexture ft(labels, std::move(textures));
  CHECK(ft.force(moving(glm::dvec3{0.0})) == glm::dvec3{0.0});
  CHECK(ft.force(moving(glm::dvec3{1e-3, 0, 0})) == glm::dvec3{1, 0, 0});
  CHECK(ft.force(moving(glm::dvec3{2.2e-3, 0, 0})) == glm::dvec3{0, 2, 0});
  CHECK(ft.force(moving(glm::dvec3{9e-3, 0, 0})) == glm::dvec3{0.0});  // off the map
  CHECK(ft.region(glm::dvec3{1e-3, 0, 0}) == 1);
  std::vector<AnyField> too_few(2);
  CHECK_THROWS_AS(FalseTexture(labels, std::move(too_few)), std::invalid_argument);
}

#if HAPTICFIELD_TEST_IMAGE_MAPS
TEST_CASE("image maps: gray levels to data values and label bands") {
  // 4 x 1 BGR image with gray levels 0, 64, 128, 255 (B = G = R)
  cv::Mat img(1, 4, CV_8UC3);
  const int levels[] = {0, 64, 128, 255};
  for (int x = 0; x < 4; ++x)
    img.at<cv::Vec3b>(0, x) = cv::Vec3b(levels[x], levels[x], levels[x]);
  const PlaneMapping mapping(1.0, glm::dvec2{0.0, 0.0});  // 1 px per mm, pixel 0 at the origin
  const ScalarMap data = scalar_map_from_image(img, mapping);
  CHECK_THAT(data.value(glm::dvec3{1e-3, 0, 0}), WithinAbs(64.0 / 255.0, 1e-6));
  CHECK_THAT(data.value(glm::dvec3{3e-3, 0, 0}), WithinAbs(1.0, 1e-6));
  const LabelMap bands = label_map_from_gray_levels(img, 4, mapping);  // label = gray * 4 / 256
  CHECK(bands.label(glm::dvec3{0.0}) == 0);
  CHECK(bands.label(glm::dvec3{1e-3, 0, 0}) == 1);
  CHECK(bands.label(glm::dvec3{2e-3, 0, 0}) == 2);
  CHECK(bands.label(glm::dvec3{3e-3, 0, 0}) == 3);
  CHECK_THROWS_AS(label_map_from_gray_levels(img, 0, mapping), std::invalid_argument);
  CHECK_THROWS_AS(scalar_map_from_image(cv::Mat(), mapping), std::invalid_argument);
  // the same missing file gives the same error as anywhere else (one loader)
  CHECK_THROWS_AS(hapticfield::load_image(std::string(HAPTICFIELD_SOURCE_DIR) + "/no/such/image.png"), FileError);
  // the shipped photograph loads and covers its whole extent with labels
  const cv::Mat coffee = hapticfield::load_image(std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png");
  const LabelMap regions = label_map_from_gray_levels(coffee, 4, PlaneMapping::fit(coffee.cols, coffee.rows, 100.0));
  CHECK(regions.width() == 600);
  CHECK(regions.max_label() == 3);
}
#endif
