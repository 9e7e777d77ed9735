// Shapes that move and deform (surface/moving_shape.hpp,
// surface/deforming_mesh.hpp), as ratios against baselines measured in the
// same run: the proxy's tick on a moving mesh (Moving<MeshShape>: the sheet
// turning about its normal and bobbing, its pose published every 50 ticks)
// against the same mesh standing still, on the same sliding path; and
// MeshBvh::refit per million triangles against MeshBvh::build of the same
// deformed mesh, with DeformingMeshFeed::publish (a refit in place once
// three frames circulate) beside them.
//
//   bench_moving [--ticks N] [--max-triangles N]
#include <hapticfield/surface.hpp>
#include <hapticfield/surface/deforming_mesh.hpp>
#include <hapticfield/surface/moving_shape.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <vector>

#include "../tests/surface_meshes.hpp"
#include "surface_path.hpp"
#include "tick_cost.hpp"

namespace hf = hapticfield;

namespace {

/// The sheet's motion at time t [s]: turning about its normal at 0.5 rad/s
/// and bobbing 1 mm at 2 Hz.
hf::MovingPose motion(double t) {
  hf::MovingPose m;
  const double bob = 2.0 * 3.141592653589793 * 2.0;  // [rad/s]
  m.pose = hf::Pose::from_axis_angle({0, 0, 1}, 0.5 * t, {0.0, 0.0, 0.001 * std::sin(bob * t)});
  m.angular_velocity = {0.0, 0.0, 0.5};
  m.linear_velocity = {0.0, 0.0, 0.001 * bob * std::cos(bob * t)};
  m.time = t;
  return m;
}

template <class Proxy, class Before>
hf::bench::Cost tick_cost(Proxy& proxy, const std::vector<hf::Probe>& path, Before&& before) {
  glm::dvec3 sink{0.0};
  auto tick = [&](const hf::Probe& p) noexcept {
    before(p);
    const glm::dvec3 f = proxy.contact(p).force;
    sink += f;
    return f;
  };
  const hf::bench::Cost c = hf::offline::measure_tick_budget(tick, path, hf::bench::thread_cpu_budget());
  if (!hf::is_finite(sink)) std::printf("(non-finite force)\n");
  return c;
}

/// This thread's CPU time [s] (a loaded machine's other work left out).
double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// The shortest of `runs` timings of fn, on this thread's CPU time [s].
template <class Fn>
double best_of(int runs, Fn&& fn) {
  double best = 1e300;
  for (int r = 0; r < runs; ++r) {
    const double t0 = thread_seconds();
    fn();
    best = std::min(best, thread_seconds() - t0);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  long ticks = 20000;
  std::size_t max_triangles = 4'000'000;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--ticks") && a + 1 < argc)
      ticks = std::atol(argv[++a]);
    else if (!std::strcmp(argv[a], "--max-triangles") && a + 1 < argc)
      max_triangles = static_cast<std::size_t>(std::atoll(argv[++a]));
    else {
      std::fprintf(stderr, "usage: bench_moving [--ticks N] [--max-triangles N]\n");
      return 2;
    }
  }
  const double side = 0.1;  // [m]
  const std::vector<hf::Probe> path = hf::bench::sliding_path(ticks, side / 2);
  std::printf(
      "Times are this thread's CPU time: per call for ticks (tick-budget harness, servo/tick_budget.hpp), the\n"
      "best of 3 for build, refit and publish (DeformingMeshFeed::publish once three frames circulate: a refit in\n"
      "place plus the copy of the positions).\n\n");
  std::printf("## Proxy tick on a moving wavy mesh against the same mesh standing still (%ld ticks)\n\n", ticks);
  std::printf(
      "| triangles | still mean [ns] | still p99 [ns] | moving mean [ns] | moving p99 [ns] | moving worst [ns] | "
      "mean ratio | p99 ratio |\n|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<hf::TriangleMesh> meshes;
  for (const std::size_t target : {16'000ul, 250'000ul, 1'000'000ul, 4'000'000ul}) {
    if (target > max_triangles) break;
    const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(target) / 2.0)));
    meshes.push_back(hf::test::wavy_sheet(side, n, 0.002, 0.03));
    const hf::MeshShape shape(meshes.back());
    const hf::ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
    hf::ProxyConstraint still(shape, config);
    const hf::bench::Cost s = tick_cost(still, path, [](const hf::Probe&) noexcept {});
    hf::ProxyConstraint moving(hf::Moving<hf::MeshShape>(shape, motion(0.0)), config);
    const std::shared_ptr<hf::PoseFeed> feed = moving.shape().feed();
    long count = 0;
    const hf::bench::Cost m = tick_cost(moving, path, [&](const hf::Probe& p) noexcept {
      if (count++ % 50 == 0) feed->publish(motion(p.time));  // the writer's 20 Hz, here in line (never throws)
    });
    std::printf("| %zu | %.0f | %.0f | %.0f | %.0f | %.0f | %.2f | %.2f |\n", meshes.back().triangles.size(), s.mean_ns,
                s.p99_ns, m.mean_ns, m.p99_ns, m.worst_ns, m.mean_ns / s.mean_ns, m.p99_ns / s.p99_ns);
  }

  std::printf("\n## Refit against rebuild after a deformation (a travelling wave of 2 mm)\n\n");
  std::printf(
      "| triangles | build [ms] | refit [ms] | refit [ms per M] | build / refit | publish [ms] | "
      "closest() nodes refit / rebuilt |\n|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const hf::TriangleMesh& mesh : meshes) {
    hf::TriangleMesh moved = mesh;
    for (glm::dvec3& p : moved.positions)
      p.z += 0.002 * std::sin(60.0 * p.x + 20.0 * p.y + 1.0);
    hf::MeshBvh refit = hf::MeshBvh::build(mesh);
    hf::MeshBvh rebuilt;
    const double build_s = best_of(3, [&] { rebuilt = hf::MeshBvh::build(moved); });
    const double refit_s = best_of(3, [&] { refit.refit(moved); });
    hf::DeformingMeshFeed feed(mesh);
    for (int warm = 0; warm < 3; ++warm)  // three frames circulating: publish refits in place from here on
      feed.publish(moved.positions);
    const double publish_s = best_of(3, [&] { feed.publish(moved.positions); });
    // the work of a query on each tree: closest() at the path's points
    double nodes_refit = 0.0, nodes_rebuilt = 0.0;
    for (std::size_t i = 0; i < path.size(); i += 10) {
      hf::QueryStats a, b;
      (void)refit.closest(path[i].position, 0.005, &a);
      (void)rebuilt.closest(path[i].position, 0.005, &b);
      nodes_refit += a.nodes;
      nodes_rebuilt += b.nodes;
    }
    const double mtri = static_cast<double>(mesh.triangles.size()) / 1e6;
    std::printf("| %zu | %.1f | %.2f | %.1f | %.1f | %.1f | %.2f |\n", mesh.triangles.size(), build_s * 1e3,
                refit_s * 1e3, refit_s * 1e3 / mtri, build_s / refit_s, publish_s * 1e3,
                nodes_refit / std::max(1.0, nodes_rebuilt));
  }
  return 0;
}
