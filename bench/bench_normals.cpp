// bench_normals: per-tick cost of the normal field (Kim & Kwon) with 1, 10
// and 1000 faces, with force shading and with the gradient variant, against
// a baseline field measured in the same run (the plane mapping alone, the
// least any image field does). Mean over a batch, and the worst and 99.9th
// percentile of single ticks each timed with steady_clock (the timer's own
// cost is printed too). Target: <= 200 ns per tick with 1000 faces.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hapticfield/normals.hpp"

using namespace hapticfield;
using Clock = std::chrono::steady_clock;

namespace {

volatile double sink = 0.0;

std::vector<ImageFace> tiles(int n) {
  const int per_row = static_cast<int>(std::ceil(std::sqrt(double(n))));
  const double side = 640.0 / per_row;
  std::vector<ImageFace> faces;
  for (int k = 0; k < n; ++k) {
    const double x0 = (k % per_row) * side;
    const double y0 = (k / per_row) * side;
    const double slant = (10.0 + k % 50) * 3.14159265358979 / 180.0;
    const double az = 0.7 * k;
    faces.push_back({{{x0, y0}, {x0 + side, y0}, {x0 + side, y0 + side}, {x0, y0 + side}},
                     {std::sin(slant) * std::cos(az), std::sin(slant) * std::sin(az), -std::cos(slant)}});
  }
  return faces;
}

/// The baseline: map the probe to the image, as every image field must.
struct MappingOnly {
  PlaneMapping mapping = PlaneMapping::kim_kwon(640, 640);
  glm::dvec3 force(const Probe& p) const noexcept {
    const glm::dvec2 px = mapping.to_image(p.position);
    const glm::dvec2 v = mapping.velocity_to_image(p.velocity);
    return glm::dvec3{px.x * 1e-6, v.y * 1e-6, 0.0};
  }
};

std::vector<Probe> trajectory(std::size_t n) {
  // a Lissajous sweep over the 100 x 100 mm workspace at hand speeds
  std::vector<Probe> probes(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = i * servo_period;
    Probe& p = probes[i];
    p.position = glm::dvec3{0.048 * std::sin(3.1 * t), 0.048 * std::sin(2.3 * t + 0.5), 0.0};
    p.velocity = glm::dvec3{0.048 * 3.1 * std::cos(3.1 * t), 0.048 * 2.3 * std::cos(2.3 * t + 0.5), 0.0};
    p.time = t;
  }
  return probes;
}

struct Result {
  double mean_ns, p999_ns, worst_ns;
};

template <class Field>
Result measure(Field& field, const std::vector<Probe>& probes) {
  constexpr int batches = 60;
  double acc = 0.0;
  for (const auto& p : probes)
    acc += field.force(p).x;  // warm-up
  const auto t0 = Clock::now();
  for (int b = 0; b < batches; ++b)
    for (const auto& p : probes)
      acc += field.force(p).x;
  const auto t1 = Clock::now();
  std::vector<double> single;
  single.reserve(probes.size() * 4);
  for (int b = 0; b < 4; ++b)
    for (const auto& p : probes) {
      const auto a = Clock::now();
      acc += field.force(p).y;
      const auto z = Clock::now();
      single.push_back(std::chrono::duration<double, std::nano>(z - a).count());
    }
  sink = sink + acc;
  std::sort(single.begin(), single.end());
  const double mean = std::chrono::duration<double, std::nano>(t1 - t0).count() / (batches * double(probes.size()));
  return {mean, single[static_cast<std::size_t>(0.999 * (single.size() - 1))], single.back()};
}

}  // namespace

int main() {
  const auto probes = trajectory(20000);
  MappingOnly baseline;
  const Result base = measure(baseline, probes);
  std::vector<double> timer;
  for (int i = 0; i < 20000; ++i) {
    const auto a = Clock::now();
    const auto z = Clock::now();
    timer.push_back(std::chrono::duration<double, std::nano>(z - a).count());
  }
  std::sort(timer.begin(), timer.end());

  std::printf("Normal field per-tick cost, 640 x 640 px picture (100 mm at 6.4 px/mm), %zu-tick sweep\n",
              probes.size());
  std::printf("timer overhead per single-tick measurement: median %.0f ns, worst %.0f ns\n\n", timer[timer.size() / 2],
              timer.back());
  std::printf("%-38s %8s %7s %9s %7s %9s %7s\n", "field", "mean ns", "x base", "p99.9 ns", "x base", "worst ns",
              "x base");
  const auto row = [&](const std::string& name, const Result& r) {
    std::printf("%-38s %8.1f %7.2f %9.0f %7.2f %9.0f %7.2f\n", name.c_str(), r.mean_ns, r.mean_ns / base.mean_ns,
                r.p999_ns, r.p999_ns / base.p999_ns, r.worst_ns, r.worst_ns / base.worst_ns);
  };
  row("baseline: plane mapping only", base);
  for (int n : {1, 10, 1000}) {
    NormalField field(640, 640, tiles(n));
    row("along motion, " + std::to_string(n) + " face" + (n > 1 ? "s" : ""), measure(field, probes));
  }
  for (int n : {1, 1000}) {
    NormalFieldConfig o;
    o.shading_cell_px = 8.0;
    NormalField field(640, 640, tiles(n), o);
    row("along motion + shading, " + std::to_string(n) + (n > 1 ? " faces" : " face"), measure(field, probes));
  }
  {
    NormalFieldConfig o;
    o.mode = NormalForceMode::gradient;
    NormalField field(640, 640, tiles(1000), o);
    row("gradient, 1000 faces", measure(field, probes));
  }
  {
    AnyField erased = NormalField(640, 640, tiles(1000));
    row("along motion, 1000 faces, AnyField", measure(erased, probes));
  }
  std::printf(
      "\nsingle-tick figures include the timer; the worst case also includes preemption by the "
      "OS.\n");
  std::printf("budget: 1 kHz servo = 1000000 ns per tick; target <= 200 ns with 1000 faces\n");
  return 0;
}
