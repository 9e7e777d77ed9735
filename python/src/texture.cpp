// Stochastic textures (Fritz & Barner 1996), filters, friction and HaTT models.
#include "field.hpp"

#include <hapticfield/texture.hpp>
#include <hapticfield/texture/hatt.hpp>

#include <pybind11/stl.h>

#include <cmath>
#include <utility>

namespace hapticfield::python {

using namespace hapticfield::texture;

namespace {

Interpolation interpolation_of(const std::string& name) {
  if (name == "nearest") return Interpolation::nearest;
  if (name == "linear") return Interpolation::linear;
  if (name == "cubic") return Interpolation::cubic;
  throw py::value_error("interpolation: unknown '" + name + "' (choose nearest, linear or cubic)");
}

TextureConfig params_of(double gain, double velocity_threshold, bool scale_with_normal_force, const V3& axes) {
  return TextureConfig{gain, velocity_threshold, scale_with_normal_force, glm3(axes)};
}

/// Calls f with the noise named by kind: uniform in [-sigma sqrt 3, sigma sqrt 3), Gaussian or Laplacian, all
/// of standard deviation sigma.
template <class F>
decltype(auto) with_noise(const std::string& kind, double sigma, F&& f) {
  if (!(std::isfinite(sigma) && sigma >= 0.0)) throw py::value_error("sigma: must be finite and >= 0 [texture units]");
  if (kind == "gaussian") return f(GaussianNoise(sigma));
  if (kind == "laplacian") return f(LaplacianNoise(sigma));
  if (kind == "uniform") {
    if (!(sigma > 0.0)) throw py::value_error("sigma: uniform noise needs sigma > 0");
    return f(UniformNoise(-std::sqrt(3.0) * sigma, std::sqrt(3.0) * sigma));
  }
  throw py::value_error("noise: unknown '" + kind + "' (choose gaussian, laplacian or uniform)");
}

template <class Noise, int Dim>
NoiseLattice<Noise, Dim> lattice(Noise noise, std::uint32_t seed, const V3& grain, const std::string& interp) {
  return NoiseLattice<Noise, Dim>(std::move(noise), seed, glm3(grain), interpolation_of(interp));
}

/// Calls f with a Butterworth filter of the run-time order.
template <class F>
decltype(auto) with_butterworth(int order, const std::string& band, double f1, double f2, double rate, F&& f) {
  auto make = [&]<int N>(std::integral_constant<int, N>) {
    if (band == "low_pass") return f(Butterworth<N>::low_pass(f1, rate));
    if (band == "high_pass") return f(Butterworth<N>::high_pass(f1, rate));
    if (band == "band_pass") return f(Butterworth<N>::band_pass(f1, f2, rate));
    throw py::value_error("band: unknown '" + band + "' (choose low_pass, high_pass or band_pass)");
  };
  switch (order) {
    case 1:
      return make(std::integral_constant<int, 1>{});
    case 2:
      return make(std::integral_constant<int, 2>{});
    case 3:
      return make(std::integral_constant<int, 3>{});
    case 4:
      return make(std::integral_constant<int, 4>{});
    case 5:
      return make(std::integral_constant<int, 5>{});
    case 6:
      return make(std::integral_constant<int, 6>{});
    case 7:
      return make(std::integral_constant<int, 7>{});
    case 8:
      return make(std::integral_constant<int, 8>{});
    default:
      throw py::value_error("order: Butterworth order must be 1..8");
  }
}

template <class Filter>
py::array_t<double> run_filter(Filter filter, const Array& x) {
  const py::ssize_t n = rows_of(x, 0, "signal");
  py::array_t<double> y(n);
  const double* in = x.data();
  double* out = y.mutable_data();
  py::gil_scoped_release release;
  for (py::ssize_t i = 0; i < n; ++i)
    out[i] = filter.process(in[i]);
  return y;
}

}  // namespace

void bind_texture(py::module_& m) {
  const char* texture_args =
      " gain [N per texture unit] (or [N/N] with scale_with_normal_force: Ft proportional to |Fc|), "
      "velocity_threshold [m/s] (silent below it), axes: weights along (t1, t2, n) of the surface frame "
      "((1, 1, 0): tangential only).";
  m.def(
      "lattice_texture",
      [](const std::string& noise, double sigma, std::uint32_t seed, const V3& grain, int dim,
         const std::string& interpolation, int octaves, double h, double gain, double velocity_threshold,
         bool scale_with_normal_force, const V3& axes) {
        const TextureConfig p = params_of(gain, velocity_threshold, scale_with_normal_force, axes);
        if (dim != 2 && dim != 3) throw py::value_error("dim: must be 2 (x, y) or 3");
        if (octaves < 0) throw py::value_error("octaves: must be >= 0 (0: no fBm)");
        return with_noise(noise, sigma, [&](auto n) {
          using N = decltype(n);
          const std::string d = noise + (octaves > 0 ? " fBm" : "") + " lattice texture";
          if (dim == 2) {
            auto l = lattice<N, 2>(n, seed, grain, interpolation);
            if (octaves > 0) return make_field(TextureField(SpatialSource(Fbm<N, 2>(std::move(l), h, octaves)), p), d);
            return make_field(TextureField(SpatialSource(std::move(l)), p), d);
          }
          auto l = lattice<N, 3>(n, seed, grain, interpolation);
          if (octaves > 0) return make_field(TextureField(SpatialSource(Fbm<N, 3>(std::move(l), h, octaves)), p), d);
          return make_field(TextureField(SpatialSource(std::move(l)), p), d);
        });
      },
      py::arg("noise") = "gaussian", py::arg("sigma") = 1.0, py::arg("seed") = 1u,
      py::arg("grain") = V3{1e-3, 1e-3, 1e-3}, py::arg("dim") = 2, py::arg("interpolation") = "linear",
      py::arg("octaves") = 0, py::arg("h") = 0.5, py::arg("gain") = 1.0, py::arg("velocity_threshold") = 1e-3,
      py::arg("scale_with_normal_force") = false, py::arg("axes") = V3{1.0, 1.0, 1.0},
      (std::string("A stochastic texture Ft sampled on a hashed noise lattice (Fritz & Barner 1996): noise "
                   "gaussian|laplacian|uniform of standard deviation sigma, seed, lattice spacing grain [m] per axis, "
                   "dim 2 (x, y) or 3, interpolation nearest|linear|cubic. octaves > 0 makes it fBm with "
                   "self-similarity h (PSD ~ f^-(2h+1)).") +
       texture_args)
          .c_str());
  m.def(
      "local_sphere_texture",
      [](const std::string& noise, double sigma, std::uint32_t seed, double radius, const V3& surface_normal,
         double gain, double velocity_threshold, bool scale_with_normal_force, const V3& axes) {
        const TextureConfig p = params_of(gain, velocity_threshold, scale_with_normal_force, axes);
        return with_noise(noise, sigma, [&](auto n) {
          using N = decltype(n);
          return make_field(TextureField(LocalSphere<N>(n, seed, radius, glm3(surface_normal)), p),
                            noise + " local-sphere texture");
        });
      },
      py::arg("noise") = "gaussian", py::arg("sigma") = 1.0, py::arg("seed") = 1u, py::arg("radius") = 5e-4,
      py::arg("surface_normal") = V3{0.0, 0.0, 1.0}, py::arg("gain") = 1.0, py::arg("velocity_threshold") = 1e-3,
      py::arg("scale_with_normal_force") = false, py::arg("axes") = V3{1.0, 1.0, 1.0},
      (std::string("A texture that draws a new noise sample each time the HIP leaves a ball of radius [m] (the "
                   "local circle on a surface of unit surface_normal).") +
       texture_args)
          .c_str());
  m.def(
      "temporal_texture",
      [](const std::string& noise, double sigma, std::uint32_t seed, int order, const std::string& band, double f1,
         double f2, double rate, double gain, double velocity_threshold, bool scale_with_normal_force, const V3& axes) {
        const TextureConfig p = params_of(gain, velocity_threshold, scale_with_normal_force, axes);
        return with_noise(noise, sigma, [&](auto n) {
          if (order == 0) return make_field(TextureField(TemporalSource(n, seed), p), noise + " temporal texture");
          return with_butterworth(order, band, f1, f2, rate, [&](auto filter) {
            return make_field(TextureField(TemporalSource(n, seed), p, filter),
                              noise + " temporal texture, Butterworth " + band);
          });
        });
      },
      py::arg("noise") = "gaussian", py::arg("sigma") = 1.0, py::arg("seed") = 1u, py::arg("order") = 4,
      py::arg("band") = "band_pass", py::arg("f1") = 30.0, py::arg("f2") = 120.0, py::arg("rate") = 1000.0,
      py::arg("gain") = 1.0, py::arg("velocity_threshold") = 1e-3, py::arg("scale_with_normal_force") = false,
      py::arg("axes") = V3{1.0, 1.0, 1.0},
      (std::string("A fresh noise sample every tick, filtered per component by a Butterworth filter of order "
                   "1..8 (0: unfiltered), band low_pass|high_pass (cutoff f1 [Hz]) or band_pass (f1..f2 [Hz]) "
                   "designed for the servo rate [Hz].") +
       texture_args)
          .c_str());
  m.def(
      "friction",
      [](double coulomb, double viscous, double drag, double smoothing_speed, bool scale_with_normal_force,
         const V3& surface_normal) {
        return make_field(Friction(FrictionConfig{coulomb, viscous, drag, smoothing_speed, scale_with_normal_force,
                                                  glm3(surface_normal)}),
                          "friction");
      },
      py::arg("coulomb") = 0.0, py::arg("viscous") = 0.0, py::arg("drag") = 0.0, py::arg("smoothing_speed") = 2e-3,
      py::arg("scale_with_normal_force") = false, py::arg("surface_normal") = V3{0.0, 0.0, 0.0},
      "Friction Ff = -(c + b |v| + d |v|^2) v/|v| (tangential v on a surface): coulomb c [N] (or mu [-] with "
      "scale_with_normal_force), viscous b [N s/m], drag d [N s^2/m^2], smoothed stick below smoothing_speed "
      "[m/s]; surface_normal used when the probe has none (zero: 3D friction).");
  m.def(
      "hatt_texture",
      [](const std::string& path, double effective_mass, const V3& surface_normal, std::uint32_t seed,
         double velocity_threshold, bool friction) {
        const HattModelSet set = load_hatt_model_set(path);
        HattConfig p;
        p.effective_mass = effective_mass;
        p.surface_normal = glm3(surface_normal);
        p.seed = seed;
        p.velocity_threshold = velocity_threshold;
        p.friction = friction;
        return make_field(HattTexture<>(set, p), "HaTT " + set.name);
      },
      py::arg("path"), py::arg("effective_mass") = 0.05, py::arg("surface_normal") = V3{0.0, 0.0, 1.0},
      py::arg("seed") = 1u, py::arg("velocity_threshold") = 1e-3, py::arg("friction") = true,
      "A HaTT data-driven texture (a modelSet XML file of the Penn Haptic Texture Toolkit): AR/ARMA vibration "
      "models chosen by tangential speed and |Fc|, run at the model's own sample rate, acceleration [m/s^2] "
      "times effective_mass [kg] along surface_normal, plus mu |Fc| friction. Raises FileError for a bad file.");
  m.def(
      "hatt_model",
      [](const std::string& path) {
        const HattModelSet set = load_hatt_model_set(path);
        py::dict d;
        d["name"] = set.name;
        d["mu"] = set.mu;
        d["sample_rate"] = set.sample_rate;
        d["ar_order"] = set.ar_order;
        d["ma_order"] = set.ma_order;
        d["models"] = set.models.size();
        return d;
      },
      py::arg("path"), "What a HaTT modelSet file holds: name, mu [-], sample_rate [Hz], ar_order, ma_order, models.");
  m.def(
      "butterworth",
      [](const Array& x, int order, const std::string& band, double f1, double f2, double rate) {
        return with_butterworth(order, band, f1, f2, rate, [&](auto filter) { return run_filter(filter, x); });
      },
      py::arg("signal"), py::arg("order") = 4, py::arg("band") = "low_pass", py::arg("f1") = 100.0, py::arg("f2") = 0.0,
      py::arg("rate") = 1000.0,
      "Filters a 1-D signal sampled at rate [Hz] with the library's Butterworth filter (order 1..8, bilinear "
      "transform, -3.01 dB at each edge): band low_pass|high_pass (cutoff f1 [Hz]) or band_pass (f1..f2 [Hz]).");
  m.def(
      "fir_low_pass",
      [](const Array& x, double cutoff, double rate) { return run_filter(FirFilter<63>::low_pass(cutoff, rate), x); },
      py::arg("signal"), py::arg("cutoff"), py::arg("rate") = 1000.0,
      "Filters a 1-D signal sampled at rate [Hz] with a 63-tap Hamming-windowed FIR low-pass at cutoff [Hz] "
      "(group delay 31 samples).");
  m.def(
      "noise",
      [](const std::string& kind, double sigma, std::uint32_t seed, py::ssize_t n) {
        if (n < 0) throw py::value_error("n: must be >= 0");
        return with_noise(kind, sigma, [&](auto noise) {
          auto out = matrix(n, 3);
          double* o = out.mutable_data();
          for (py::ssize_t i = 0; i < n; ++i) {
            const glm::dvec3 v = noise.sample(seed, Cell{static_cast<std::uint32_t>(i), 0, 0});
            o[3 * i] = v.x, o[3 * i + 1] = v.y, o[3 * i + 2] = v.z;
          }
          return out;
        });
      },
      py::arg("kind") = "gaussian", py::arg("sigma") = 1.0, py::arg("seed") = 1u, py::arg("n") = 1000,
      "n x 3 samples of the library's repeatable noise (gaussian|laplacian|uniform, standard deviation sigma) at "
      "lattice points (i, 0, 0), i = 0..n-1: a pure function of (seed, point).");
}

}  // namespace hapticfield::python
