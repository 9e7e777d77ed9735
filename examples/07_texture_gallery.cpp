// texture_gallery [--out DIR] [--hatt DIR]
//
// Strokes every texture kind of the library along a straight line at a fixed
// speed (50 mm/s, 1 kHz servo rate, 2 s) on the plane z = 0 pressed with
// 1 N, F = Fc + texture through contact() (flow: in free space), and writes, per
// kind, the force trace and its power spectrum as a PNG plot and CSV files,
// plus gallery.png with all the plots. With --hatt DIR, also every HaTT
// modelSet file in DIR (the toolkit's XML/ folder). No device is driven.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.hpp"
#include "common/plots.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"

using namespace hapticfield;
using namespace hapticfield::texture;
namespace fs = std::filesystem;

namespace {

constexpr double rate = 1000.0;       // servo rate [Hz]
constexpr double speed = 0.05;        // stroke speed [m/s]
constexpr double duration = 2.0;      // [s]
constexpr double normal_force = 1.0;  // |Fc| [N]
constexpr double stiffness = 1000.0;  // of the stroked plane [N/m]

struct Trace {
  std::string name;
  std::string description;
  std::vector<glm::dvec3> force;  // [N] per tick
  int axis{0};                    // component plotted
};

// one stroke along +x at constant speed, pressed normal_force / stiffness into z = 0
template <class Field>
Trace stroke_field(const std::string& name, const std::string& description, Field& field, double rate_hz) {
  Trace t{name, description, {}, 0};
  const int n = static_cast<int>(duration * rate_hz);
  for (int i = 0; i < n; ++i) {
    Probe p;
    p.time = i / rate_hz;
    p.period = 1.0 / rate_hz;
    p.position = glm::dvec3{-0.05 + speed * p.time, 0.002, -normal_force / stiffness};
    p.velocity = glm::dvec3{speed, 0.0, 0.0};
    t.force.push_back(field.force(p));
  }
  double best = -1;
  for (int k = 0; k < 3; ++k) {
    double m = 0, v = 0;
    for (const auto& f : t.force)
      m += f[k];
    m /= double(t.force.size());
    for (const auto& f : t.force)
      v += (f[k] - m) * (f[k] - m);
    if (v > best) best = v, t.axis = k;
  }
  return t;
}

// a texture or friction on the plane: F = Fc + part, the part seeing |Fc| = 1 N
// and the plane's normal +z of each tick
template <class Field>
Trace stroke(const std::string& name, const std::string& description, Field&& part, double rate_hz = rate) {
  auto on_plane = contact(PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, stiffness, 0.0}),
                          std::forward<Field>(part));
  return stroke_field(name, description, on_plane, rate_hz);
}

// a field felt in free space (flow), on the same path
template <class Field>
Trace stroke_free(const std::string& name, const std::string& description, Field&& field, double rate_hz = rate) {
  return stroke_field(name, description, field, rate_hz);
}

// Welch power spectral density [N^2/Hz], Hann window, 256-sample segments, 50 % overlap
std::vector<double> welch(const std::vector<double>& x, double fs) {
  const std::size_t seg = 256;
  std::vector<double> psd(seg / 2 + 1, 0.0);
  double mean = 0;
  for (double v : x)
    mean += v;
  mean /= double(x.size());
  double wsum = 0;
  for (std::size_t i = 0; i < seg; ++i) {
    const double w = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * double(i) / double(seg));
    wsum += w * w;
  }
  int count = 0;
  for (std::size_t start = 0; start + seg <= x.size(); start += seg / 2, ++count) {
    std::vector<std::complex<double>> a(seg);
    for (std::size_t i = 0; i < seg; ++i)
      a[i] = (x[start + i] - mean) * (0.5 - 0.5 * std::cos(2 * std::numbers::pi * double(i) / double(seg)));
    fft(a);
    for (std::size_t k = 0; k <= seg / 2; ++k)
      psd[k] += std::norm(a[k]) * (k == 0 || k == seg / 2 ? 1.0 : 2.0) / (fs * wsum);
  }
  for (double& p : psd)
    p /= std::max(count, 1);
  return psd;
}

void draw_panel(cv::Mat& img, cv::Rect box, const std::vector<double>& xs, const std::vector<double>& ys,
                const std::string& xlabel, const std::string& ylabel, cv::Scalar colour) {
  cv::rectangle(img, box, cv::Scalar(180, 180, 180), 1);
  if (ys.empty()) return;
  double lo = *std::min_element(ys.begin(), ys.end()), hi = *std::max_element(ys.begin(), ys.end());
  const bool flat = !(hi > lo);
  if (flat) lo -= 1.0, hi += 1.0;  // a constant trace is drawn mid-panel
  const double x0 = xs.front(), x1 = xs.back() > xs.front() ? xs.back() : xs.front() + 1.0;
  std::vector<cv::Point> pts;
  for (std::size_t i = 0; i < ys.size(); ++i)
    pts.emplace_back(box.x + static_cast<int>((xs[i] - x0) / (x1 - x0) * (box.width - 1)),
                     box.y + box.height - 1 - static_cast<int>((ys[i] - lo) / (hi - lo) * (box.height - 1)));
  cv::polylines(img, pts, false, colour, 1, cv::LINE_AA);
  char buf[160];
  if (flat)
    std::snprintf(buf, sizeof buf, "%s   constant %.3g %s", xlabel.c_str(), lo + 1.0, ylabel.c_str());
  else
    std::snprintf(buf, sizeof buf, "%s   [%.3g .. %.3g] %s", xlabel.c_str(), lo, hi, ylabel.c_str());
  cv::putText(img, buf, {box.x + 4, box.y + box.height + 14}, cv::FONT_HERSHEY_SIMPLEX, 0.38, cv::Scalar(60, 60, 60), 1,
              cv::LINE_AA);
}

cv::Mat plot(const Trace& t, double fs, const std::vector<double>& psd) {
  cv::Mat img(420, 640, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(img, t.name, {10, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, t.description, {10, 42}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(80, 80, 80), 1, cv::LINE_AA);
  std::vector<double> xs, ys;
  const std::size_t shown = std::min<std::size_t>(t.force.size(), 500);  // first 0.5 s
  for (std::size_t i = 0; i < shown; ++i)
    xs.push_back(i / fs), ys.push_back(t.force[i][t.axis]);
  const char* axes = "xyz";
  draw_panel(img, {40, 55, 580, 140}, xs, ys, "time 0..0.5 s", std::string("F") + axes[t.axis] + " [N]",
             cv::Scalar(160, 60, 0));
  std::vector<double> lf, lp;
  for (std::size_t k = 1; k < psd.size(); ++k)
    lf.push_back(std::log10(k * fs / 256.0)), lp.push_back(10.0 * std::log10(std::max(psd[k], 1e-20)));
  draw_panel(img, {40, 235, 580, 150}, lf, lp, "log10 f: 3.9 .. 500 Hz", "PSD [dB re 1 N^2/Hz]",
             cv::Scalar(0, 100, 200));
  return img;
}

// index of the plotted traces for scripts/hapticfield_plots.py: stem,name,axis,description,rate_Hz
void write_index_row(std::ofstream& index, const std::string& stem, const Trace& t, double fs) {
  const auto quoted = [](std::string s) {
    for (std::size_t i = s.find('"'); i != std::string::npos; i = s.find('"', i + 2))
      s.insert(i, 1, '"');
    return '"' + s + '"';
  };
  index << quoted(stem) << ',' << quoted(t.name) << ',' << t.axis << ',' << quoted(t.description) << ',' << fs << '\n';
}

/// Writes a trace's CSV files and simple plot; returns the plot's line for the
/// file list printed at the end (each file listed once, whoever drew it).
std::string write_outputs(const Trace& t, const fs::path& out, double fs, std::vector<cv::Mat>& tiles,
                          std::ofstream& index) {
  std::vector<double> x;
  for (const auto& f : t.force)
    x.push_back(f[t.axis]);
  const auto psd = welch(x, fs);
  std::string stem = t.name;
  for (char& c : stem)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  {
    std::ofstream csv(out / (stem + "_trace.csv"));
    csv << "time_s,fx_N,fy_N,fz_N\n";
    for (std::size_t i = 0; i < t.force.size(); ++i)
      csv << i / fs << ',' << t.force[i].x << ',' << t.force[i].y << ',' << t.force[i].z << '\n';
  }
  {
    std::ofstream csv(out / (stem + "_psd.csv"));
    csv << "frequency_Hz,psd_N2_per_Hz\n";
    for (std::size_t k = 0; k < psd.size(); ++k)
      csv << k * fs / 256.0 << ',' << psd[k] << '\n';
  }
  write_index_row(index, stem, t, fs);
  const cv::Mat img = plot(t, fs, psd);
  cv::imwrite((out / (stem + ".png")).string(), img);
  tiles.push_back(img);
  return "  " + stem + ".png  (" + t.description + ")";
}

constexpr const char* usage =
    "usage: texture_gallery [--out DIR] [--hatt DIR]\n"
    "Strokes every texture kind at 50 mm/s, 1 N, 1 kHz for 2 s and writes each force\n"
    "trace and its power spectrum (PNG and CSV) and gallery.png.\n"
    "  --out DIR    output folder, created if needed (default out/texture_gallery)\n"
    "  --hatt DIR   also every HaTT modelSet XML file in DIR (the toolkit's XML/ folder);\n"
    "               each at most 16 MB, <SampleRate> in 100..100000 Hz\n"
    "  -h, --help   this text\n"
    "Exit status: 0 done, 1 bad input (HaTT files, output folder), 2 usage error.\n";

int run(const fs::path& out, const fs::path& hatt_dir) {
  {
    fs::create_directories(out);
    std::vector<Trace> traces;
    const TextureConfig lateral{0.5, 1e-3, false, glm::dvec3{1.0, 1.0, 0.0}};
    const TextureConfig normal{0.5, 1e-3, false, glm::dvec3{0.0, 0.0, 1.0}};
    const glm::dvec3 grain{1e-3, 1e-3, 1e-3};  // 1 mm: 50 Hz at 50 mm/s

    traces.push_back(stroke(
        "uniform lattice", "uniform noise, 2D lattice 1 mm, linear",
        TextureField(SpatialSource(NoiseLattice<UniformNoise, 2>(UniformNoise(-1, 1), 1, grain, Interpolation::linear)),
                     lateral)));
    traces.push_back(stroke("gaussian nearest", "Gaussian, 2D lattice 1 mm, nearest",
                            TextureField(SpatialSource(NoiseLattice<GaussianNoise, 2>(GaussianNoise(0.5), 2, grain,
                                                                                      Interpolation::nearest)),
                                         lateral)));
    traces.push_back(stroke(
        "gaussian cubic", "Gaussian, 2D lattice 1 mm, Catmull-Rom cubic",
        TextureField(SpatialSource(NoiseLattice<GaussianNoise, 2>(GaussianNoise(0.5), 2, grain, Interpolation::cubic)),
                     lateral)));
    traces.push_back(stroke("laplacian", "Laplacian, 2D lattice 0.5 mm, linear",
                            TextureField(SpatialSource(NoiseLattice<LaplacianNoise, 2>(
                                             LaplacianNoise(0.5), 3, grain * 0.5, Interpolation::linear)),
                                         lateral)));
    glm::dmat3 cov{0.0};
    cov[0][0] = 0.3, cov[1][1] = 0.1, cov[0][1] = cov[1][0] = 0.12;  // lateral only (zero z variance)
    traces.push_back(stroke("multivariate gaussian", "full covariance, zero z variance, 3D lattice 1 mm",
                            TextureField(SpatialSource(NoiseLattice<MultivariateGaussianNoise, 3>(
                                             MultivariateGaussianNoise(glm::dvec3{0.0}, cov), 4, grain)),
                                         TextureConfig{})));
    traces.push_back(stroke("gaussian mixture", "two components (smooth / rough), 2D lattice 0.5 mm",
                            TextureField(SpatialSource(NoiseLattice<GaussianMixtureNoise, 2>(
                                             GaussianMixtureNoise({{0.8, glm::dvec3{0.0}, glm::dmat3{0.02}},
                                                                   {0.2, glm::dvec3{0.0}, glm::dmat3{1.0}}}),
                                             5, grain * 0.5)),
                                         lateral)));
    traces.push_back(
        stroke("local sphere", "new Gaussian sample each 0.5 mm of travel",
               TextureField(LocalSphere<GaussianNoise>(GaussianNoise(0.5), 6, 5e-4, glm::dvec3{0, 0, 1}), lateral)));
    traces.push_back(
        stroke("fbm h=0.5", "fBm, 6 octaves from 4 mm, PSD ~ f^-2",
               TextureField(SpatialSource(Fbm<GaussianNoise, 2>(
                                NoiseLattice<GaussianNoise, 2>(GaussianNoise(0.5), 7, grain * 4.0), 0.5, 6)),
                            lateral)));
    traces.push_back(stroke(
        "fourier synthesis", "sine 25 Hz + square 60 Hz + sawtooth 110 Hz (at 50 mm/s)",
        TextureField(SpatialSource(FourierSynthesis({{Waveform::sine, 0.3, 500.0, 0.0, glm::dvec3{1, 0, 0}},
                                                     {Waveform::square, 0.15, 1200.0, 0.0, glm::dvec3{1, 0, 0}},
                                                     {Waveform::sawtooth, 0.1, 2200.0, 0.0, glm::dvec3{1, 0, 0}}})),
                     normal)));
    traces.push_back(stroke(
        "modulated grating", "Ft = (1 + m) sine 100 Hz + n, Gaussian lattices",
        TextureField(
            SpatialSource(ModulatedTexture(FourierSynthesis({{Waveform::sine, 0.3, 2000.0, 0.0, glm::dvec3{1, 0, 0}}}),
                                           1.0, NoiseLattice<GaussianNoise, 2>(GaussianNoise(0.4), 8, grain * 3.0),
                                           NoiseLattice<GaussianNoise, 2>(GaussianNoise(0.03), 9, grain * 0.2))),
            normal)));
    traces.push_back(stroke(
        "temporal butterworth", "white Gaussian per tick, band-pass 4th order 30..120 Hz",
        TextureField(TemporalSource(GaussianNoise(1.0), 10), lateral, Butterworth<4>::band_pass(30.0, 120.0, rate))));
    traces.push_back(
        stroke("temporal fir", "white Gaussian per tick, FIR 63 taps low-pass 60 Hz",
               TextureField(TemporalSource(GaussianNoise(1.0), 11), lateral, FirFilter<63>::low_pass(60.0, rate))));
    traces.push_back(
        stroke("temporal equaliser", "white Gaussian per tick, +12 dB at 40 Hz, +6 dB at 200 Hz",
               TextureField(TemporalSource(GaussianNoise(0.2), 12), lateral,
                            Equaliser<2>({EqualiserBand{40.0, 0.5, 12.0}, EqualiserBand{200.0, 1.0, 6.0}}, rate))));
    traces.push_back(
        stroke("temporal arma", "ARMA(2,1): resonance near 80 Hz",
               TextureField(
                   TemporalSource(GaussianNoise(0.1), 13), lateral,
                   Arma<2, 1>({-2.0 * 0.95 * std::cos(2 * std::numbers::pi * 80.0 / rate), 0.95 * 0.95}, {1.0, 0.5}))));
    traces.push_back(stroke("friction", "Coulomb mu = 0.3 (smoothed) + viscous 2 N s/m, opposing +x",
                            Friction(FrictionConfig{0.3, 2.0, 0.0, 2e-3, true, glm::dvec3{0, 0, 1}})));
    traces.push_back(stroke_free(
        "flow", "3D vector lattice 2 mm, mean shift 0.2 N in -x, drag 1 N s/m",
        FlowTexture(NoiseLattice<GaussianNoise, 3>(GaussianNoise(0.2), 14, grain * 2.0, Interpolation::cubic),
                    FlowConfig{glm::dvec3{-0.2, 0, 0}, 1.0, 1.0})));

    std::vector<cv::Mat> tiles;
    std::vector<std::string> listed;  // one line per plot, printed once at the end
    std::ofstream index(out / "gallery.csv");
    index << "stem,name,axis,description,rate_Hz\n";
    for (const auto& t : traces)
      listed.push_back(write_outputs(t, out, rate, tiles, index));

    if (!hatt_dir.empty()) {
      for (const auto& file : hatt_model_files(hatt_dir)) {
        const HattModelSet set = load_hatt_model_set(file);
        HattTexture<128> tex(set, HattConfig{0.05, glm::dvec3{0, 0, 1}, 1, 1, 1e-3, false});
        // run at the model's own sample rate (HaTT: 10 kHz)
        Trace t = stroke("hatt " + set.name,
                         std::string(set.ma_order > 0 ? "HaTT ARMA" : "HaTT AR") + " model at 50 mm/s, 1 N, " +
                             std::to_string(int(set.sample_rate)) + " Hz",
                         tex, set.sample_rate);
        t.axis = 2;
        listed.push_back(write_outputs(t, out, set.sample_rate, tiles, index));
      }
    }

    // montage: 3 columns of half-size plots
    const int cols = 3;
    const int rows = static_cast<int>((tiles.size() + cols - 1) / cols);
    cv::Mat gallery(rows * 210, cols * 320, CV_8UC3, cv::Scalar(255, 255, 255));
    for (std::size_t i = 0; i < tiles.size(); ++i) {
      cv::Mat small;
      cv::resize(tiles[i], small, cv::Size(320, 210), 0, 0, cv::INTER_AREA);
      small.copyTo(gallery(cv::Rect(static_cast<int>(i % cols) * 320, static_cast<int>(i / cols) * 210, 320, 210)));
    }
    if (!cv::imwrite((out / "gallery.png").string(), gallery))
      throw FileError("--out: cannot write '" + (out / "gallery.png").string() + "'");
    // Redrawn with axes, ticks, units and legends by matplotlib when present;
    // the script lists nothing (--quiet): the files are listed here, once.
    index.close();
    std::string why;
    const bool matplotlib = plots::matplotlib({"texture", "--dir", out.string(), "--quiet"}, why);
    std::cout << "writing to " << out.string() << " ("
              << (matplotlib ? "drawn with matplotlib" : "simple plots: " + why) << "):\n";
    for (const std::string& line : listed)
      std::cout << line << '\n';
    std::cout << "  gallery.png (" << tiles.size() << " plots)\n"
              << "  gallery.csv and, per plot, STEM_trace.csv (time_s, fx_N, fy_N, fz_N) and STEM_psd.csv "
                 "(frequency_Hz, psd_N2_per_Hz)\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::main("texture_gallery", usage, argc, argv, [](cli::Parser& p) {
    std::string out = "out/texture_gallery";
    std::string hatt_dir;
    bool out_given = false;
    while (p.next()) {
      if (p.is("--out"))
        out = p.output_dir(), out_given = true;
      else if (p.is("--hatt"))
        hatt_dir = p.value();
      else
        p.unknown();
    }
    if (!out_given) p.default_output_dir("--out", out);
    if (!hatt_dir.empty() && !fs::is_directory(hatt_dir)) throw FileError("--hatt: '" + hatt_dir + "' is not a folder");
    p.finish();
    return run(out, hatt_dir);
  });
}
