// bench_texture [--samples N]
//
// Per-sample cost of every texture generator, filter and field, and of a
// full texture tick (temporal Gaussian noise + three 4th-order Butterworth
// band-passes, one per force component + friction), as a Markdown table.
//
// Mean: a timed loop of N calls divided by N. p99 and worst: each call timed
// on its own with steady_clock (includes the clock's own ~20 ns). Ratios are
// against a baseline measured in the same run: a spring field F = -k x
// called through the same harness. Target: full texture tick <= 1 us.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "hapticfield/core.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"

using namespace hapticfield;
using namespace hapticfield::texture;
using clock_type = std::chrono::steady_clock;

namespace {

template <class T>
inline void keep(const T& value) {
  asm volatile("" : : "r,m"(value) : "memory");
}

struct Stats {
  double mean_ns{0}, p99_ns{0}, worst_ns{0};
};

Probe probe_at(int i) {
  Probe p;
  p.position = glm::dvec3{-0.05 + i * 5e-5, 0.002 + 1e-6 * (i % 7), 0.0};
  p.velocity = glm::dvec3{0.05, 0.001, 0.0};
  p.normal_force = 1.0 + 0.1 * (i % 3);
  p.time = i * 1e-3;
  return p;
}

template <class Fn>
Stats measure(Fn&& fn, int n) {
  for (int i = 0; i < 2000; ++i)
    fn(i);  // warm caches and branch predictors
  const auto t0 = clock_type::now();
  for (int i = 0; i < n; ++i)
    fn(i);
  const auto t1 = clock_type::now();
  Stats s;
  s.mean_ns = std::chrono::duration<double, std::nano>(t1 - t0).count() / n;
  std::vector<double> each(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const auto a = clock_type::now();
    fn(i);
    const auto b = clock_type::now();
    each[static_cast<std::size_t>(i)] = std::chrono::duration<double, std::nano>(b - a).count();
  }
  std::sort(each.begin(), each.end());
  s.p99_ns = each[static_cast<std::size_t>(0.99 * (n - 1))];
  s.worst_ns = each.back();
  return s;
}

struct Row {
  std::string name;
  Stats s;
};

}  // namespace

int main(int argc, char** argv) {
  int n = 200000;
  if (argc == 3 && std::string(argv[1]) == "--samples") n = std::max(1000, std::atoi(argv[2]));
  std::vector<Row> rows;
  const auto field_row = [&](const std::string& name, auto&& field) {
    rows.push_back({name, measure([&](int i) { keep(field.force(probe_at(i))); }, n)});
  };

  struct Spring {
    glm::dvec3 force(const Probe& p) const noexcept { return -200.0 * p.position; }
  };
  field_row("baseline: spring F = -k x", Spring{});

  // noise primitives
  const GaussianNoise gauss(1.0);
  glm::dmat3 cov{0.0};
  cov[0][0] = 0.3, cov[1][1] = 0.1, cov[0][1] = cov[1][0] = 0.12;
  const MultivariateGaussianNoise mvn(glm::dvec3{0.0}, cov);
  const GaussianMixtureNoise mix({{0.8, glm::dvec3{0.0}, glm::dmat3{0.02}}, {0.2, glm::dvec3{0.0}, glm::dmat3{1.0}}});
  const auto cell = [](int i) { return Cell{static_cast<std::uint32_t>(i), 7u, 0u}; };
  rows.push_back({"uniform01 (1 value)", measure([&](int i) { keep(uniform01(1, cell(i))); }, n)});
  rows.push_back({"UniformNoise (3 values)", measure([&](int i) { keep(UniformNoise().sample(1, cell(i))); }, n)});
  rows.push_back({"GaussianNoise (3 values)", measure([&](int i) { keep(gauss.sample(1, cell(i))); }, n)});
  rows.push_back(
      {"LaplacianNoise (3 values)", measure([&](int i) { keep(LaplacianNoise(1.0).sample(1, cell(i))); }, n)});
  rows.push_back({"MultivariateGaussianNoise", measure([&](int i) { keep(mvn.sample(1, cell(i))); }, n)});
  rows.push_back({"GaussianMixtureNoise (2 comp.)", measure([&](int i) { keep(mix.sample(1, cell(i))); }, n)});

  // lattices and spatial generators
  const glm::dvec3 grain{1e-3};
  for (auto [mode, label] : {std::pair{Interpolation::nearest, "nearest"}, std::pair{Interpolation::linear, "linear"},
                             std::pair{Interpolation::cubic, "cubic"}}) {
    const NoiseLattice<GaussianNoise, 2> l2(gauss, 1, grain, mode);
    const NoiseLattice<GaussianNoise, 3> l3(gauss, 1, grain, mode);
    rows.push_back({std::string("2D lattice, ") + label, measure([&](int i) { keep(l2(probe_at(i).position)); }, n)});
    rows.push_back({std::string("3D lattice, ") + label, measure([&](int i) { keep(l3(probe_at(i).position)); }, n)});
  }
  const TabulatedNoise<GaussianNoise> table(gauss);
  rows.push_back({"TabulatedNoise<Gaussian> (3 values)", measure([&](int i) { keep(table.sample(1, cell(i))); }, n)});
  const NoiseLattice<TabulatedNoise<GaussianNoise>, 2> t2(table, 1, grain, Interpolation::cubic);
  const NoiseLattice<TabulatedNoise<GaussianNoise>, 3> t3(table, 1, grain, Interpolation::cubic);
  rows.push_back({"2D lattice, cubic, tabulated Gaussian", measure([&](int i) { keep(t2(probe_at(i).position)); }, n)});
  rows.push_back({"3D lattice, cubic, tabulated Gaussian", measure([&](int i) { keep(t3(probe_at(i).position)); }, n)});
  const Fbm<GaussianNoise, 2> fbm(NoiseLattice<GaussianNoise, 2>(gauss, 1, grain * 4.0), 0.5, 4);
  rows.push_back({"fBm 2D linear, 4 octaves", measure([&](int i) { keep(fbm(probe_at(i).position)); }, n)});
  const FourierSynthesis fourier({{Waveform::sine, 0.3, 500.0, 0.0, glm::dvec3{1, 0, 0}},
                                  {Waveform::square, 0.15, 1200.0, 0.0, glm::dvec3{1, 0, 0}},
                                  {Waveform::sawtooth, 0.1, 2200.0, 0.0, glm::dvec3{1, 0, 0}}});
  rows.push_back({"Fourier synthesis, 3 terms", measure([&](int i) { keep(fourier(probe_at(i).position)); }, n)});
  LocalSphere<GaussianNoise> sphere(gauss, 1, 5e-4);
  rows.push_back({"local sphere", measure([&](int i) { keep(sphere.sample(probe_at(i).position)); }, n)});

  // filters (one scalar sample)
  auto run_filter = [&](const std::string& name, auto filter) {
    rows.push_back({name, measure([&](int i) { keep(filter.process(std::sin(i * 0.1))); }, n)});
  };
  run_filter("biquad", Biquad(BiquadCoefficients{0.2, 0.4, 0.2, -0.5, 0.3}));
  run_filter("Butterworth<2> low-pass", Butterworth<2>::low_pass(100.0, 1000.0));
  run_filter("Butterworth<4> low-pass", Butterworth<4>::low_pass(100.0, 1000.0));
  run_filter("Butterworth<4> band-pass (4 sections)", Butterworth<4>::band_pass(30.0, 120.0, 1000.0));
  run_filter("Butterworth<8> low-pass", Butterworth<8>::low_pass(100.0, 1000.0));
  run_filter("Equaliser<3>",
             Equaliser<3>({EqualiserBand{40, 1, 6}, EqualiserBand{120, 1, -6}, EqualiserBand{300, 1, 3}}, 1000.0));
  run_filter("FIR 31 taps", FirFilter<31>::low_pass(100.0, 1000.0));
  run_filter("FIR 63 taps", FirFilter<63>::low_pass(100.0, 1000.0));
  run_filter("ARMA(4,2)", Arma<4, 2>({-0.5, 0.3, -0.2, 0.1}, {1.0, 0.4, 0.2}));

  // fields
  field_row("friction (Coulomb + viscous + drag)",
            Friction(FrictionConfig{0.3, 2.0, 1.0, 2e-3, true, glm::dvec3{0, 0, 1}}));
  field_row("stick-slip friction (spring anchor)", StickSlipFriction(StickSlipConfig{}));
  field_row("full texture tick: noise + 3 x Butterworth<4> LP + friction",
            sum(TextureField(TemporalSource(gauss, 1), TextureConfig{0.3, 1e-3, true, glm::dvec3{1.0}},
                             Butterworth<4>::low_pass(100.0, 1000.0)),
                Friction(FrictionConfig{0.3, 0.5, 0.0, 2e-3, true, glm::dvec3{0, 0, 1}})));
  field_row("full texture tick, band-pass (3 x 4 sections)",
            sum(TextureField(TemporalSource(gauss, 1), TextureConfig{0.3, 1e-3, true, glm::dvec3{1.0}},
                             Butterworth<4>::band_pass(30.0, 120.0, 1000.0)),
                Friction(FrictionConfig{0.3, 0.5, 0.0, 2e-3, true, glm::dvec3{0, 0, 1}})));
  field_row("spatial texture: 2D cubic lattice + friction",
            sum(TextureField(SpatialSource(NoiseLattice<GaussianNoise, 2>(gauss, 1, grain, Interpolation::cubic)),
                             TextureConfig{}),
                Friction(FrictionConfig{0.3, 0.5, 0.0, 2e-3, true, glm::dvec3{0, 0, 1}})));
  field_row("flow texture (3D cubic lattice)",
            FlowTexture(NoiseLattice<GaussianNoise, 3>(gauss, 1, grain, Interpolation::cubic), FlowConfig{}));

  // HaTT: a synthetic AR(20) set with 3 models and 1 triangle (real HaTT
  // sets have more triangles; locating grows linearly with their number and
  // the LSF -> AR conversion as p^2; measure real files with texture_gallery --hatt)
  const HattModelSet set = parse_hatt_model_set(R"(<modelSet><mu>0.3</mu><numMod>3</numMod><numTri>1</numTri>
    <speedList><value>20</value><value>400</value><value>200</value></speedList>
    <forceList><value>0.2</value><value>0.2</value><value>4</value></forceList>
    <tri><value>1</value><value>2</value><value>3</value></tri><numARCoeff>20</numARCoeff><numMACoeff>0</numMACoeff>
    <model><ARlsf>0.1 0.2 0.35 0.5 0.6 0.8 0.9 1.1 1.2 1.4 1.5 1.7 1.8 2.0 2.1 2.3 2.4 2.6 2.8 3.0</ARlsf><var>0.1</var><speedMod>20</speedMod><forceMod>0.2</forceMod></model>
    <model><ARlsf>0.12 0.22 0.37 0.52 0.62 0.82 0.92 1.12 1.22 1.42 1.52 1.72 1.82 2.02 2.12 2.32 2.42 2.62 2.82 3.02</ARlsf><var>0.2</var><speedMod>400</speedMod><forceMod>0.2</forceMod></model>
    <model><ARlsf>0.08 0.18 0.33 0.48 0.58 0.78 0.88 1.08 1.18 1.38 1.48 1.68 1.78 1.98 2.08 2.28 2.38 2.58 2.78 2.98</ARlsf><var>0.3</var><speedMod>200</speedMod><forceMod>4</forceMod></model>
    </modelSet>)",
                                                "bench");
  HattTexture<32> every_tick(set, HattConfig{0.05, glm::dvec3{0, 0, 1}, 1, 1, 1e-3, true});
  HattTexture<32> every_10(set, HattConfig{0.05, glm::dvec3{0, 0, 1}, 1, 10, 1e-3, true});
  field_row("HaTT AR(20) tick, update every tick", every_tick);
  field_row("HaTT AR(20) tick, update every 10 ticks", every_10);
  rows.push_back({"HaTT update(): locate + LSF interp + lsf_to_ar(20)", measure(
                                                                            [&](int i) {
                                                                              every_tick.update(50.0 + (i % 300),
                                                                                                0.5 + 0.01 * (i % 300));
                                                                              keep(every_tick.variance());
                                                                            },
                                                                            n)});

  // a set the size of the larger real ones: 8 x 8 (speed, force) grid, 98
  // triangles, AR(40); the point moves across the grid so locating scans
  HattModelSet big;
  big.mu = 0.3;
  big.ar_order = 40;
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      big.speeds.push_back(20.0 + 380.0 * i / 7.0);
      big.forces.push_back(0.2 + 3.8 * j / 7.0);
      HattModel m;
      m.speed = big.speeds.back();
      m.force = big.forces.back();
      m.variance = 0.1 + 0.01 * (i + j);
      for (int k = 0; k < 40; ++k)
        m.ar_lsf.push_back(std::numbers::pi * (k + 0.5 + 0.3 * std::sin(i + 2.0 * j + k)) / 41.0);
      big.models.push_back(m);
    }
  for (int j = 0; j < 7; ++j)
    for (int i = 0; i < 7; ++i) {
      const int v = j * 8 + i;
      big.triangles.push_back({v, v + 1, v + 9});
      big.triangles.push_back({v, v + 9, v + 8});
    }
  HattTexture<40> big_tex(big, HattConfig{0.05, glm::dvec3{0, 0, 1}, 1, 1, 1e-3, true});
  rows.push_back({"HaTT update(), 64 models, 98 triangles, AR(40)", measure(
                                                                        [&](int i) {
                                                                          big_tex.update(20.0 + (i % 380),
                                                                                         0.2 + 0.0095 * (i % 400));
                                                                          keep(big_tex.variance());
                                                                        },
                                                                        n)});
  field_row("HaTT AR(40) tick, 98 triangles, update every tick", big_tex);

  // setup code (not per tick): reading model files and converting <ARcoeff>
  const auto ar_of_order = [](int p) {
    std::vector<double> a(static_cast<std::size_t>(p) + 1, 0.0);
    a[0] = 1.0;
    a[1] = -0.5;
    return a;
  };
  const std::vector<double> a20 = ar_of_order(20), a64 = ar_of_order(64);
  const int setup_n = std::max(50, n / 1000);
  rows.push_back({"setup: ar_to_lsf, order 20", measure([&](int) { keep(ar_to_lsf(a20)[0]); }, setup_n)});
  rows.push_back({"setup: ar_to_lsf, order 64", measure([&](int) { keep(ar_to_lsf(a64)[0]); }, setup_n)});
  const std::string toolkit =
      hapticfield::read_file(HAPTICFIELD_SOURCE_DIR "/tests/data/hatt/Models_Toolkit 1kHz ARMA.xml");
  rows.push_back({"setup: parse a toolkit 1 kHz ARMA file (6 KB, 4 models)",
                  measure([&](int) { keep(parse_hatt_model_set(toolkit, "bench").mu); }, setup_n)});
  const std::string hostile =
      hapticfield::read_file(HAPTICFIELD_SOURCE_DIR "/tests/fuzz/corpus_hatt/hostile_2000_coefficients.xml");
  rows.push_back(
      {"setup: reject the 4.5 KB file with 2000 <ARcoeff> values", measure(
                                                                       [&](int) {
                                                                         try {
                                                                           (void)parse_hatt_model_set(hostile, "bench");
                                                                         } catch (const HattFileError& e) {
                                                                           keep(static_cast<double>(e.what()[0]));
                                                                         }
                                                                       },
                                                                       setup_n)});

  const Stats& base = rows.front().s;
  std::printf("Texture benchmark: %d samples per row; ratios against the baseline row.\n\n", n);
  std::printf("| %-62s | %9s | %9s | %10s | %10s | %11s |\n", "operation (one sample / tick)", "mean [ns]", "p99 [ns]",
              "worst [ns]", "mean ratio", "worst ratio");
  std::printf("|%s|%s|%s|%s|%s|%s|\n", std::string(64, '-').c_str(), std::string(11, '-').c_str(),
              std::string(11, '-').c_str(), std::string(12, '-').c_str(), std::string(12, '-').c_str(),
              std::string(13, '-').c_str());
  for (const auto& r : rows)
    std::printf("| %-62s | %9.1f | %9.1f | %10.1f | %10.1f | %11.2f |\n", r.name.c_str(), r.s.mean_ns, r.s.p99_ns,
                r.s.worst_ns, r.s.mean_ns / base.mean_ns, r.s.worst_ns / base.worst_ns);
  for (const auto& r : rows)
    if (r.name.rfind("full texture tick: noise", 0) == 0)
      std::printf("\nfull texture tick: mean %.0f ns, p99 %.0f ns (target <= 1000 ns: %s)\n", r.s.mean_ns, r.s.p99_ns,
                  r.s.p99_ns <= 1000.0 ? "met" : "NOT met");
  return 0;
}
