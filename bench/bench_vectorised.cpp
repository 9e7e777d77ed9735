// The baseline for the Python module's vectorised evaluation: the same
// scene (a plane, the picture, a Gaussian lattice texture and friction,
// F = Fc + Ft + Ff) evaluated at the same N probes by a plain C++ loop over
// the concrete field type. python/bench_forces.py runs this in the same run
// and reports the ratio; the checksum shows both computed the same forces.
//
// --scene light: the plane and friction only, so the per-probe overhead of
// the Python path (type erasure, numpy copies) shows. The loop is a function
// of its own for each field type, as the module's batch loop is (inlined
// into main, GCC compiled the light scene's loop 1.4x slower). --erased: the scene
// through one AnyField, as a C++ program that picks its field at run time.
//
//   bench_vectorised [IMAGE] [--probes N] [--repeats R] [--scene full|light] [--erased]
#include <hapticfield/core.hpp>
#include <hapticfield/kernels.hpp>
#include <hapticfield/texture.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace hf = hapticfield;
using namespace hapticfield::texture;
using Clock = std::chrono::steady_clock;

/// The loop over the probes, one function for each field type (kept out of
/// main so that the compiler optimises it on its own, as the module's loop).
template <class F>
[[gnu::noinline]] void evaluate(F& field, const std::vector<double>& pos, const std::vector<double>& vel,
                                std::vector<double>& out, long n) {
  hf::Probe probe;
  for (long i = 0; i < n; ++i) {
    probe.position = {pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]};
    probe.velocity = {vel[3 * i], vel[3 * i + 1], vel[3 * i + 2]};
    probe.time = static_cast<double>(i) * hf::servo_period;
    const glm::dvec3 f = field.force(probe);
    out[3 * i] = f.x, out[3 * i + 1] = f.y, out[3 * i + 2] = f.z;
  }
}

int main(int argc, char** argv) {
  std::string path = std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png";
  long n = 1000000;
  int repeats = 5;
  bool light = false;
  bool erased = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::printf(
          "usage: bench_vectorised [IMAGE] [--probes N] [--repeats R] [--scene full|light] [--erased]\n"
          "Times a C++ loop over N probes of the scene python/bench_forces.py evaluates from Python.\n");
      return 0;
    } else if (!std::strcmp(argv[i], "--probes") && i + 1 < argc) {
      n = std::atol(argv[++i]);
    } else if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc) {
      repeats = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--erased")) {
      erased = true;
    } else if (!std::strcmp(argv[i], "--scene") && i + 1 < argc) {
      const std::string scene = argv[++i];
      if (scene != "full" && scene != "light") {
        std::fprintf(stderr, "bench_vectorised: --scene must be full or light\n");
        return 2;
      }
      light = scene == "light";
    } else if (argv[i][0] != '-') {
      path = argv[i];
    } else {
      std::fprintf(stderr, "bench_vectorised: unknown option '%s'\n", argv[i]);
      return 2;
    }
  }
  if (n < 1 || repeats < 1) {
    std::fprintf(stderr, "bench_vectorised: --probes and --repeats must be >= 1\n");
    return 2;
  }
  try {
    const hf::GrayImage gray = hf::load_gray(path);
    auto scene = [&] {
      return hf::contact(
          hf::PlaneConstraint(hf::PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1500.0, 0.0}),
          hf::TangibleImageField(hf::TangibleImage(gray, hf::TangibleConfig{}),
                                 hf::PlaneMapping::fit(gray.width(), gray.height(), 80.0), 1.0),
          TextureField(SpatialSource(NoiseLattice<GaussianNoise, 2>(GaussianNoise(0.5), 3, glm::dvec3{1e-3},
                                                                    Interpolation::linear)),
                       TextureConfig{0.3, 1e-3, true, glm::dvec3{1, 1, 0}}),
          Friction(FrictionConfig{0.4, 0.5, 0.0, 2e-3, true, glm::dvec3{0.0}}));
    };
    // The probes of python/bench_forces.py: scattered over the picture, 1 mm into the plane [m], [m/s].
    std::vector<double> pos(3 * static_cast<std::size_t>(n)), vel(pos.size());
    for (long i = 0; i < n; ++i) {
      pos[3 * i] = -0.04 + 0.08 * static_cast<double>((i * 7919) % 100003) / 100003.0;
      pos[3 * i + 1] = -0.03 + 0.06 * static_cast<double>((i * 104729) % 99991) / 99991.0;
      pos[3 * i + 2] = -0.001;
      vel[3 * i] = 0.05, vel[3 * i + 1] = 0.02, vel[3 * i + 2] = 0.0;
    }
    auto light_scene = [] {
      return hf::contact(
          hf::PlaneConstraint(hf::PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1500.0, 0.0}),
          Friction(FrictionConfig{0.4, 0.5, 0.0, 2e-3, true, glm::dvec3{0.0}}));
    };
    std::vector<double> out(pos.size());
    std::vector<double> seconds;
    auto time_once = [&](auto field) {
      const auto t0 = Clock::now();
      evaluate(field, pos, vel, out, n);
      seconds.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    };
    for (int r = 0; r < repeats; ++r) {
      if (light && erased)
        time_once(hf::AnyField(light_scene()));
      else if (light)
        time_once(light_scene());
      else if (erased)
        time_once(hf::AnyField(scene()));
      else
        time_once(scene());
    }
    double checksum = 0.0;
    for (double v : out)
      checksum += v;
    double mean = 0.0;
    for (double s : seconds)
      mean += s;
    mean /= static_cast<double>(seconds.size());
    std::printf("probes %ld repeats %d mean_s %.9g worst_s %.9g checksum %.17g\n", n, repeats, mean,
                *std::max_element(seconds.begin(), seconds.end()), checksum);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_vectorised: %s\n", e.what());
    return 1;
  }
  return 0;
}
