// Tests of the texture filters: Butterworth (magnitude at the band edges,
// coefficients against independently derived references), biquads, FIR
// linear phase, the parametric equaliser, ARMA stability and variance.
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "hapticfield/texture/arma.hpp"
#include "hapticfield/texture/fir.hpp"
#include "hapticfield/texture/iir.hpp"
#include "hapticfield/texture/noise.hpp"
#include "hapticfield/texture/texture_field.hpp"

using namespace hapticfield;
using namespace hapticfield::texture;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;

namespace {

constexpr double fs = 1000.0;  // [Hz]

double db(std::complex<double> h) {
  return 20.0 * std::log10(std::abs(h));
}

using Poly = std::vector<double>;  // coefficients of z^0, z^-1, ...

Poly multiply(const Poly& a, const Poly& b) {
  Poly c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j)
      c[i + j] += a[i] * b[j];
  return c;
}

Poly power(const Poly& a, int n) {
  Poly r{1.0};
  for (int i = 0; i < n; ++i)
    r = multiply(r, a);
  return r;
}

// Analog Butterworth polynomial coefficients c_0..c_n of s^0..s^n (c_0 = c_n
// = 1) from the product formula c_k = prod_{m=1..k} cos((m-1) g) / sin(m g),
// g = pi / (2n) (e.g. Williams & Taylor, "Electronic Filter Design Handbook").
Poly analog_butterworth(int n) {
  const double g = std::numbers::pi / (2.0 * n);
  Poly c(static_cast<std::size_t>(n) + 1, 1.0);
  for (int k = 1; k <= n; ++k)
    c[static_cast<std::size_t>(k)] = c[static_cast<std::size_t>(k) - 1] * std::cos((k - 1) * g) / std::sin(k * g);
  return c;
}

// Bilinear transform with prewarping by polynomial substitution into
// H(s) = 1 / sum c_i (s/Wc)^i, K = tan(pi fc / fs) (no poles involved: an
// independent route to the same digital filter).
void reference_butterworth(int n, double fc, bool high, Poly& num, Poly& den) {
  const Poly c = analog_butterworth(n);
  const double k = std::tan(std::numbers::pi * fc / fs);
  // low-pass:  s/Wc = (1/K) (1 - z^-1)/(1 + z^-1); times K^n (1 + z^-1)^n:
  //   den = sum_i c_i K^(n-i) (1 - z^-1)^i (1 + z^-1)^(n-i),  num = K^n (1 + z^-1)^n
  // high-pass: s/Wc -> Wc/s = K (1 + z^-1)/(1 - z^-1); times (1 - z^-1)^n:
  //   den = sum_i c_i K^i (1 + z^-1)^i (1 - z^-1)^(n-i),      num = (1 - z^-1)^n
  const Poly minus{1.0, -1.0}, plus{1.0, 1.0};
  den.assign(static_cast<std::size_t>(n) + 1, 0.0);
  for (int i = 0; i <= n; ++i) {
    const Poly term =
        high ? multiply(power(plus, i), power(minus, n - i)) : multiply(power(minus, i), power(plus, n - i));
    const double scale = c[static_cast<std::size_t>(i)] * std::pow(k, high ? i : n - i);
    for (std::size_t j = 0; j < term.size(); ++j)
      den[j] += scale * term[j];
  }
  num = power(high ? minus : plus, n);
  for (double& v : num)
    v *= high ? 1.0 : std::pow(k, n);
  const double a0 = den[0];
  for (double& v : den)
    v /= a0;
  for (double& v : num)
    v /= a0;
}

template <int N>
void cascade_polynomials(const Butterworth<N>& f, Poly& num, Poly& den) {
  num = {1.0};
  den = {1.0};
  for (std::size_t i = 0; i < f.cascade().size(); ++i) {
    const auto& c = f.cascade().section(i).coefficients();
    num = multiply(num, {c.b0, c.b1, c.b2});
    den = multiply(den, {1.0, c.a1, c.a2});
  }
}

template <int N>
void check_butterworth() {
  INFO("order " << N);
  for (double fc : {10.0, 50.0, 200.0, 450.0}) {
    const auto lp = Butterworth<N>::low_pass(fc, fs);
    const auto hp = Butterworth<N>::high_pass(fc, fs);
    CHECK_THAT(db(lp.response(fc)), WithinAbs(-3.0103, 0.01));
    CHECK_THAT(db(hp.response(fc)), WithinAbs(-3.0103, 0.01));
    CHECK_THAT(std::abs(lp.response(0.0)), WithinAbs(1.0, 1e-9));
    CHECK_THAT(std::abs(hp.response(fs / 2.0)), WithinAbs(1.0, 1e-9));
    // coefficients against the bilinear transform of the analog polynomial
    for (bool high : {false, true}) {
      Poly rn, rd, gn, gd;
      reference_butterworth(N, fc, high, rn, rd);
      cascade_polynomials(high ? hp : lp, gn, gd);
      REQUIRE(gd.size() >= rd.size());
      for (std::size_t j = 0; j < gd.size(); ++j) {
        const double ref_d = j < rd.size() ? rd[j] : 0.0;
        const double ref_n = j < rn.size() ? rn[j] : 0.0;
        CHECK_THAT(gd[j], WithinAbs(ref_d, 1e-9 * (1.0 + std::fabs(ref_d))));
        CHECK_THAT(gn[j], WithinAbs(ref_n, 1e-9 * (1.0 + std::fabs(ref_n))));
      }
    }
  }
  // band-pass: -3.01 dB at both edges, 0 dB at the (warped) centre
  const double f1 = 40.0, f2 = 160.0;
  const auto bp = Butterworth<N>::band_pass(f1, f2, fs);
  CHECK_THAT(db(bp.response(f1)), WithinAbs(-3.0103, 0.01));
  CHECK_THAT(db(bp.response(f2)), WithinAbs(-3.0103, 0.01));
  const double w1 = std::tan(std::numbers::pi * f1 / fs), w2 = std::tan(std::numbers::pi * f2 / fs);
  const double centre = fs / std::numbers::pi * std::atan(std::sqrt(w1 * w2));
  CHECK_THAT(db(bp.response(centre)), WithinAbs(0.0, 1e-9));
  CHECK(db(bp.response(2.0)) < -3.0103);
  CHECK(db(bp.response(400.0)) < -3.0103);
}

}  // namespace

TEST_CASE("Butterworth order 1..8: -3.01 dB at cutoff, coefficients match the analog prototype") {
  check_butterworth<1>();
  check_butterworth<2>();
  check_butterworth<3>();
  check_butterworth<4>();
  check_butterworth<5>();
  check_butterworth<6>();
  check_butterworth<7>();
  check_butterworth<8>();
}

TEST_CASE("Butterworth order 2 low-pass matches hand-computed coefficients") {
  // fc = 100 Hz at fs = 1 kHz: K = tan(0.1 pi) = 0.3249197, K^2 = 0.1055728,
  // sqrt2 K = 0.4595058, D = 1 + sqrt2 K + K^2 = 1.5650786;
  // b = K^2/D (1, 2, 1), a1 = 2 (K^2 - 1)/D, a2 = (1 - sqrt2 K + K^2)/D.
  // (The same numbers as scipy.signal.butter(2, 0.2).)
  const auto lp = Butterworth<2>::low_pass(100.0, fs);
  const auto& c = lp.cascade().section(0).coefficients();
  CHECK_THAT(c.b0, WithinAbs(0.06745527, 1e-8));
  CHECK_THAT(c.b1, WithinAbs(0.13491055, 1e-8));
  CHECK_THAT(c.b2, WithinAbs(0.06745527, 1e-8));
  CHECK_THAT(c.a1, WithinAbs(-1.14298050, 1e-8));
  CHECK_THAT(c.a2, WithinAbs(0.41280160, 1e-8));
}

TEST_CASE("Butterworth steady state: a sine at the cutoff comes out at 1/sqrt(2)") {
  auto lp = Butterworth<4>::low_pass(100.0, fs);
  // RMS over whole periods (10 samples each) of a sine of amplitude A is
  // exactly A / sqrt 2, whatever the sampling phase
  double sum2 = 0;
  for (int n = 0; n < 4000; ++n) {
    const double y = lp.process(std::sin(2.0 * std::numbers::pi * 100.0 * n / fs));
    if (n >= 2000) sum2 += y * y;
  }
  CHECK_THAT(std::sqrt(2.0 * sum2 / 2000.0), WithinAbs(std::numbers::sqrt2 / 2.0, 1e-6));
}

TEST_CASE("bad filter parameters throw at setup") {
  CHECK_THROWS_AS(Butterworth<4>::low_pass(500.0, fs), std::invalid_argument);  // at Nyquist
  CHECK_THROWS_AS(Butterworth<4>::low_pass(600.0, fs), std::invalid_argument);  // above
  CHECK_THROWS_AS(Butterworth<4>::high_pass(0.0, fs), std::invalid_argument);
  CHECK_THROWS_AS(Butterworth<4>::band_pass(100.0, 50.0, fs), std::invalid_argument);
  CHECK_THROWS_AS(Butterworth<4>::band_pass(100.0, 500.0, fs), std::invalid_argument);
  CHECK_THROWS_AS(Butterworth<4>::low_pass(100.0, -1.0), std::invalid_argument);
  CHECK_THROWS_AS(FirFilter<31>::low_pass(500.0, fs), std::invalid_argument);
  CHECK_THROWS_AS(FirFilter<32>::high_pass(100.0, fs), std::invalid_argument);  // even taps
  CHECK_THROWS_AS((Equaliser<1>({EqualiserBand{600.0, 1.0, 6.0}}, fs)), std::invalid_argument);
  CHECK_THROWS_AS((Equaliser<1>({EqualiserBand{100.0, 0.0, 6.0}}, fs)), std::invalid_argument);
  CHECK_THROWS_AS(Biquad(BiquadCoefficients{1.0, 0.0, 0.0, -2.0, 1.0}), std::invalid_argument);  // double pole at 1
  CHECK_THROWS_AS(Biquad(BiquadCoefficients{1.0, 0.0, 0.0, 0.0, 1.01}), std::invalid_argument);  // |pole| > 1
}

TEST_CASE("FIR by windowed sinc: symmetric taps, linear phase, group delay (N-1)/2") {
  const auto lp = FirFilter<41>::low_pass(100.0, fs);
  const auto hp = FirFilter<41>::high_pass(200.0, fs, Window::blackman);
  const auto bp = FirFilter<40>::band_pass(100.0, 200.0, fs);
  const auto check_symmetric = [](const auto& taps) {
    for (std::size_t i = 0; i < taps.size(); ++i)
      REQUIRE(taps[i] == Approx(taps[taps.size() - 1 - i]).margin(1e-15));
  };
  check_symmetric(lp.taps());
  check_symmetric(hp.taps());
  check_symmetric(bp.taps());
  CHECK_THAT(std::abs(lp.response(0.0, fs)), WithinAbs(1.0, 1e-12));
  CHECK_THAT(std::abs(hp.response(fs / 2, fs)), WithinAbs(1.0, 1e-3));
  CHECK(db(lp.response(250.0, fs)) < -40.0);  // Hamming stopband
  CHECK(db(hp.response(50.0, fs)) < -60.0);   // Blackman stopband
  // phase is exactly -w (N-1)/2 (mod pi) at every frequency: H e^{j w D} is real
  for (double f = 5.0; f < 500.0; f += 7.0) {
    for (auto [h, d] : {std::pair{lp.response(f, fs), 20.0}, std::pair{bp.response(f, fs), 19.5}}) {
      const std::complex<double> rotated = h * std::polar(1.0, 2.0 * std::numbers::pi * f / fs * d);
      REQUIRE(std::fabs(rotated.imag()) < 1e-12);
    }
  }
  CHECK(FirFilter<41>::group_delay() == 20.0);
  // a passband sine comes out delayed by exactly (N-1)/2 samples
  auto f = lp;
  const double w = 2.0 * std::numbers::pi * 30.0 / fs;
  const double gain = std::abs(lp.response(30.0, fs));
  for (int n = 0; n < 400; ++n) {
    const double y = f.process(std::sin(w * n));
    if (n >= 40) REQUIRE_THAT(y, WithinAbs(gain * std::sin(w * (n - 20)), 1e-12));
  }
}

TEST_CASE("parametric equaliser: exact gain at each centre, unity far away") {
  Equaliser<2> eq({EqualiserBand{50.0, 1.0, 6.0}, EqualiserBand{250.0, 0.5, -12.0}}, fs);
  // each band's skirt adds a little at the other's centre (< 0.2 dB here)
  CHECK_THAT(db(eq.response(50.0)), WithinAbs(6.0, 0.2));
  CHECK_THAT(db(eq.response(250.0)), WithinAbs(-12.0, 0.2));
  Equaliser<1> one({EqualiserBand{100.0, 1.0, 9.0}}, fs);
  CHECK_THAT(db(one.response(100.0)), WithinAbs(9.0, 1e-9));
  CHECK_THAT(db(one.response(0.0)), WithinAbs(0.0, 1e-9));
  CHECK_THAT(db(one.response(500.0)), WithinAbs(0.0, 1e-9));
}

TEST_CASE("ARMA stability by the step-down recursion") {
  // (1 - 0.5 z^-1)(1 + 0.8 z^-1) = 1 + 0.3 z^-1 - 0.4 z^-2: poles 0.5, -0.8
  CHECK(is_stable(std::vector<double>{0.3, -0.4}));
  // (1 - 0.5 z^-1)(1 - 1.2 z^-1) = 1 - 1.7 z^-1 + 0.6 z^-2: pole 1.2
  CHECK_FALSE(is_stable(std::vector<double>{-1.7, 0.6}));
  // complex pair of radius 0.99 and 1.01 at 60 degrees: 1 - 2 r cos z^-1 + r^2 z^-2
  CHECK(is_stable(std::vector<double>{-0.99, 0.9801}));
  CHECK_FALSE(is_stable(std::vector<double>{-1.01, 1.0201}));
  CHECK_FALSE(is_stable(std::vector<double>{-1.0}));  // pole on the unit circle
  CHECK_THROWS_AS((Arma<2, 0>({-1.7, 0.6}, {1.0})), std::invalid_argument);
  CHECK_THROWS_AS((Arma<1, 1>({-1.0}, {1.0, 0.5})), std::invalid_argument);
}

TEST_CASE("ARMA output variance equals input variance times sum h^2") {
  const auto run_variance = [](auto filter) {
    const int n = 1'000'000;
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
      const double y = filter.process(gaussian(5, Cell{static_cast<std::uint32_t>(i), 0, 0}));
      if (i >= 1000) s += y, s2 += y * y;
    }
    const double m = s / (n - 1000);
    return s2 / (n - 1000) - m * m;
  };
  // AR(1), y = 0.9 y[n-1] + x: var = 1 / (1 - 0.81) (closed form)
  CHECK_THAT(run_variance(Arma<1, 0>({-0.9}, {1.0})), WithinRel(1.0 / 0.19, 0.03));
  // ARMA(1,1), y = 0.6 y[n-1] + x + 0.4 x[n-1]: var = (1 + 2 a b + b^2) / (1 - a^2)
  CHECK_THAT(run_variance(Arma<1, 1>({-0.6}, {1.0, 0.4})), WithinRel((1 + 2 * 0.6 * 0.4 + 0.16) / (1 - 0.36), 0.02));
  // ARMA(3,2): against the sum of the squared impulse response
  const Arma<3, 2> arma({-0.5, 0.3, -0.2}, {1.0, -0.4, 0.25});
  double sum_h2 = 0;
  for (double h : arma.impulse_response(2000))
    sum_h2 += h * h;
  CHECK_THAT(run_variance(arma), WithinRel(sum_h2, 0.02));
}

TEST_CASE("per-component filtering of a vector texture") {
  PerComponent<Butterworth<4>> f(Butterworth<4>::low_pass(50.0, fs));
  PerComponent<Butterworth<4>> g(Butterworth<4>::low_pass(50.0, fs));
  Butterworth<4> x = Butterworth<4>::low_pass(50.0, fs);
  for (int i = 0; i < 100; ++i) {
    const glm::dvec3 in = gaussian3(1, Cell{static_cast<std::uint32_t>(i), 0, 0});
    const glm::dvec3 out = f.process(in);
    REQUIRE(out.x == x.process(in.x));
    (void)g.process(glm::dvec3{in.x, 0.0, 0.0});
  }
  f.reset();
  REQUIRE(f.process(glm::dvec3{0.0}) == glm::dvec3{0.0});
}
