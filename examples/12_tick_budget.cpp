// tick_budget [--field wall|friction|hatt|allocating] [--hatt FILE] [--ticks N] [--speed M/S]
//
// Does a field fit in a servo tick? Runs the field over the scripted probe
// path of servo/tick_budget.hpp (a circle of 20 mm pressed 2 mm into the
// plane z = 0, 0.1 m/s by default) and prints its tick cost (mean, p50,
// p99, p99.9, worst), allocations per tick, exceptions, and whether it fits
// the 1 kHz and 10 kHz budgets (p99 at most a quarter of the period, no
// allocation, no exception). Exit status: 0 when it fits at 1 kHz, 1 when
// it does not, 2 for bad usage. Copy the pattern to measure your own field:
//
//   auto report = hapticfield::offline::measure_tick_budget(my_field);
//   std::puts(report.summary().c_str());
#define HAPTICFIELD_TICK_BUDGET_COUNT_NEW  // this program counts operator new
#include "hapticfield/servo/tick_budget.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "hapticfield/core.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"

using namespace hapticfield;

namespace {

/// A field that allocates every tick: what the harness must catch.
struct Allocating {
  std::vector<double> history;
  glm::dvec3 force(const Probe& p) noexcept {
    std::vector<double> copy(16, p.position.x);  // allocates
    history.swap(copy);
    return glm::dvec3{0.0};
  }
};

int usage(const char* why) {
  if (why) std::fprintf(stderr, "tick_budget: %s\n", why);
  std::fprintf(why ? stderr : stdout,
               "usage: tick_budget [--field wall|friction|hatt|allocating] [--hatt FILE] [--ticks N] [--speed M/S]\n"
               "  --field   the field to measure (default friction: plane + Coulomb and viscous friction)\n"
               "  --hatt    a HaTT modelSet file for --field hatt (at most 16 MB, <SampleRate> in\n"
               "            100..100000 Hz)\n"
               "  --ticks   timed ticks (default 20000)\n"
               "  --speed   speed along the scripted circle [m/s] (default 0.1)\n");
  return why ? 2 : 0;
}

template <class F>
int report(const char* name, F& field, const offline::TickBudgetConfig& config) {
  const offline::TickBudgetReport r = offline::measure_tick_budget(field, config);
  std::printf("field: %s\n%s", name, r.summary().c_str());
  return r.fits_1khz ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string which = "friction", hatt_file;
  offline::TickBudgetConfig config;
  for (int i = 1; i < argc; ++i) {
    const bool more = i + 1 < argc;
    if (std::strcmp(argv[i], "--field") == 0 && more) {
      which = argv[++i];
    } else if (std::strcmp(argv[i], "--hatt") == 0 && more) {
      hatt_file = argv[++i];
    } else if (std::strcmp(argv[i], "--ticks") == 0 && more) {
      const long n = std::atol(argv[++i]);
      if (n < 100 || n > 100'000'000) return usage("--ticks must be within 100..1e8");
      config.ticks = static_cast<std::uint64_t>(n);
    } else if (std::strcmp(argv[i], "--speed") == 0 && more) {
      config.path.speed = std::atof(argv[++i]);
      if (!(config.path.speed >= 0.0 && config.path.speed <= 10.0)) return usage("--speed must be within [0, 10] m/s");
    } else if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      return usage(nullptr);
    } else {
      return usage((std::string("unknown or incomplete option '") + argv[i] + "'").c_str());
    }
  }
  try {
    const PlaneConstraint plane({.stiffness = 1500.0});
    if (which == "wall") {
      auto field = contact(plane);
      return report("contact(plane)", field, config);
    }
    if (which == "friction") {
      auto field = contact(plane, texture::Friction({.coulomb = 0.3, .viscous = 2.0, .scale_with_normal_force = true}));
      return report("contact(plane, friction)", field, config);
    }
    if (which == "hatt") {
      if (hatt_file.empty()) return usage("--field hatt needs --hatt FILE");
      auto field = contact(plane, texture::HattTexture<64>(texture::load_hatt_model_set(hatt_file), {}));
      return report(("contact(plane, HaTT " + hatt_file + ")").c_str(), field, config);
    }
    if (which == "allocating") {
      Allocating field;
      return report("allocating (a field that allocates every tick)", field, config);
    }
    return usage(("unknown field '" + which + "'").c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tick_budget: %s\n", e.what());
    return 2;
  }
}
