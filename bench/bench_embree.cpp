// MeshBvh against Intel Embree 3 on the proxy's own queries: the swept
// first_hit() segments and closest() points a proxy tick asks for, recorded
// along the path of bench_surface on the same wavy meshes (1k to 4M
// triangles), then replayed tick by tick through each tree in the same run.
// Reports the cost of a tick's queries (mean, p99, worst), the mean cost of
// one query of each kind, the build time per million triangles (one
// thread), how often the two agree, and the allocations Embree's queries
// make (malloc, calloc, realloc and the aligned allocators are counted).
//
// Embree answers in single precision and sees both faces of a triangle;
// MeshBvh works in double and, like the proxy, sees front faces only. The
// agreement columns say how much that matters on these paths.
//
//   bench_embree [--ticks N] [--max-triangles N]
#include <hapticfield/servo/tick_budget.hpp>
#include <hapticfield/surface.hpp>

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <time.h>

#include "../tests/surface_meshes.hpp"
#include "surface_path.hpp"

// --- allocation counting: every malloc-family call while `counting` is set
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* p);
}

namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
void count() noexcept {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* malloc(std::size_t size) noexcept {
  count();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) noexcept {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) noexcept {
  count();
  return __libc_realloc(p, size);
}
void free(void* p) noexcept {
  __libc_free(p);
}
void* memalign(std::size_t alignment, std::size_t size) noexcept {
  count();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  count();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  count();
  void* p = __libc_memalign(alignment, size);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
}

namespace hf = hapticfield;
using Clock = std::chrono::steady_clock;

namespace {

/// One tree query a proxy tick made.
struct Query {
  bool sweep{false};  ///< first_hit(a, b); else closest(a, radius)
  glm::dvec3 a{0.0}, b{0.0};
  double radius{0.0};
};

/// A MeshShape that writes down the tree queries the proxy makes (not a
/// servo-path shape: it allocates; only used to record).
class RecordingShape {
 public:
  static constexpr bool flat_primitives = true;
  RecordingShape(const hf::MeshShape& shape, std::vector<Query>& log) : shape_(shape), log_(&log) {}
  [[nodiscard]] hf::Hit closest(const glm::dvec3& p, double r) const noexcept {
    log_->push_back(Query{false, p, p, r});
    return shape_.closest(p, r);
  }
  [[nodiscard]] hf::Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    log_->push_back(Query{true, from, to, 0.0});
    return shape_.first_hit(from, to);
  }
  [[nodiscard]] hf::Hit on_primitive(std::uint32_t primitive, const glm::dvec3& p, double r) const noexcept {
    return shape_.on_primitive(primitive, p, r);
  }

 private:
  hf::MeshShape shape_;
  std::vector<Query>* log_;
};

/// Embree's scene over the mesh (float vertices), built on the device's
/// one thread.
struct EmbreeScene {
  RTCScene scene{nullptr};
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
  EmbreeScene(RTCDevice device, const hf::TriangleMesh& mesh) {
    scene = rtcNewScene(device);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.positions.size()));
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
      for (int k = 0; k < 3; ++k)
        v[3 * i + static_cast<std::size_t>(k)] = static_cast<float>(mesh.positions[i][k]);
    auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), mesh.triangles.size()));
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (std::size_t k = 0; k < 3; ++k)
        t[3 * i + k] = mesh.triangles[i][k];
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene);
  }
  ~EmbreeScene() { rtcReleaseScene(scene); }
};

/// The closest-point search's state for Embree's per-triangle callback:
/// the exact (double) point of each candidate triangle, the radius shrunk
/// as better ones are found.
struct ClosestSearch {
  const hf::TriangleMesh* mesh{nullptr};
  glm::dvec3 p{0.0};
  double best_d2{0.0};
  unsigned triangle{RTC_INVALID_GEOMETRY_ID};
};

bool closest_callback(RTCPointQueryFunctionArguments* args) {
  auto* s = static_cast<ClosestSearch*>(args->userPtr);
  const auto& t = s->mesh->triangles[args->primID];
  const glm::dvec3 a = s->mesh->positions[t[0]];
  double b1 = 0.0, b2 = 0.0;
  const glm::dvec3 q =
      hf::detail::closest_on_triangle(s->p, a, s->mesh->positions[t[1]] - a, s->mesh->positions[t[2]] - a, b1, b2);
  const double d2 = glm::dot(q - s->p, q - s->p);
  if (!(d2 < s->best_d2)) return false;
  s->best_d2 = d2;
  s->triangle = args->primID;
  args->query->radius = std::nextafter(static_cast<float>(std::sqrt(d2)), std::numeric_limits<float>::infinity());
  return true;
}

struct EmbreeAnswer {
  unsigned triangle{RTC_INVALID_GEOMETRY_ID};
  double value{0.0};  ///< first_hit: t; closest: distance [m]
};

EmbreeAnswer embree_first_hit(RTCScene scene, const Query& q) noexcept {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit r{};
  const glm::dvec3 d = q.b - q.a;
  r.ray.org_x = static_cast<float>(q.a.x);
  r.ray.org_y = static_cast<float>(q.a.y);
  r.ray.org_z = static_cast<float>(q.a.z);
  r.ray.dir_x = static_cast<float>(d.x);
  r.ray.dir_y = static_cast<float>(d.y);
  r.ray.dir_z = static_cast<float>(d.z);
  r.ray.tnear = 0.0f;
  r.ray.tfar = 1.0f;
  r.ray.mask = 0xFFFFFFFFu;
  r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  r.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &context, &r);
  EmbreeAnswer out;
  if (r.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    out.triangle = r.hit.primID;
    out.value = r.ray.tfar;
  }
  return out;
}

EmbreeAnswer embree_closest(RTCScene scene, const hf::TriangleMesh& mesh, const Query& q) noexcept {
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  RTCPointQuery query{};
  query.x = static_cast<float>(q.a.x);
  query.y = static_cast<float>(q.a.y);
  query.z = static_cast<float>(q.a.z);
  query.time = 0.0f;
  query.radius = std::nextafter(static_cast<float>(q.radius), std::numeric_limits<float>::infinity());
  ClosestSearch search{&mesh, q.a, q.radius * q.radius, RTC_INVALID_GEOMETRY_ID};
  rtcPointQuery(scene, &query, &context, closest_callback, &search);
  EmbreeAnswer out;
  out.triangle = search.triangle;
  out.value = std::sqrt(search.best_d2);
  return out;
}

/// This thread's CPU time [s].
double cpu_seconds() noexcept {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  long ticks = 20000;
  std::size_t max_triangles = 4'000'000;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--help")) {
      std::printf("usage: bench_embree [--ticks N] [--max-triangles N]\n");
      return 0;
    }
    if (!std::strcmp(argv[a], "--ticks") && a + 1 < argc) {
      ticks = std::atol(argv[++a]);
    } else if (!std::strcmp(argv[a], "--max-triangles") && a + 1 < argc) {
      max_triangles = static_cast<std::size_t>(std::atoll(argv[++a]));
    } else {
      std::fprintf(stderr, "usage: bench_embree [--ticks N] [--max-triangles N]\n");
      return 2;
    }
  }
  if (ticks < 1) {
    std::fprintf(stderr, "bench_embree: --ticks must be >= 1\n");
    return 2;
  }
  const double side = 0.1;  // [m]
  const std::vector<hf::Probe> path = hf::bench::sliding_path(ticks, side / 2);
  std::printf("## MeshBvh against Embree %d.%d.%d on the proxy's queries (%ld ticks of the bench_surface path)\n\n",
              RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH, ticks);
  std::printf(
      "Per tick: that tick's recorded first_hit() and closest() queries, replayed; this thread's CPU time, the\n"
      "clock read pair's median cost subtracted. Build: one thread.\n\n");
  std::printf(
      "| triangles | tree | build [s per M] | tick mean [ns] | tick p99 [ns] | tick worst [ns] | first_hit mean [ns] "
      "| closest mean [ns] | allocations |\n");
  std::printf("|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<std::string> agreement;
  RTCDevice device = rtcNewDevice("threads=1");
  for (const std::size_t target : {1'000ul, 16'000ul, 250'000ul, 1'000'000ul, 4'000'000ul}) {
    if (target > max_triangles) break;
    const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(target) / 2.0)));
    const hf::TriangleMesh mesh = hf::test::wavy_sheet(side, n, 0.002, 0.03);
    const double mtri = static_cast<double>(mesh.triangles.size()) / 1e6;

    auto t0 = Clock::now();
    const hf::MeshShape shape(mesh);
    const double ours_build = seconds_since(t0);
    t0 = Clock::now();
    const EmbreeScene embree(device, mesh);
    const double embree_build = seconds_since(t0);
    const hf::MeshBvh& bvh = shape.bvh();

    // record the queries of each tick
    std::vector<Query> log;
    std::vector<std::size_t> begin{0};
    {
      hf::ProxyConstraint proxy(RecordingShape(shape, log), hf::ProxyConfig{1500.0, 1.0, 0.5, 0.4});
      for (const hf::Probe& p : path) {
        (void)proxy.contact(p);
        begin.push_back(log.size());
      }
    }
    const std::size_t groups = begin.size() - 1;

    // agreement: same triangle found (or none) on each query
    std::size_t sweeps = 0, closests = 0, sweep_same = 0, closest_same = 0;
    std::size_t embree_missed = 0, embree_extra = 0;  // first_hit: found by one tree only
    double worst_gap = 0.0;                           // closest: |distance difference| [m]
    for (const Query& q : log) {
      if (q.sweep) {
        ++sweeps;
        const hf::BvhHit ours = bvh.first_hit(q.a, q.b);
        const EmbreeAnswer theirs = embree_first_hit(embree.scene, q);
        const bool theirs_found = theirs.triangle != RTC_INVALID_GEOMETRY_ID;
        sweep_same += ours.found() ? ours.triangle == theirs.triangle : !theirs_found;
        embree_missed += ours.found() && !theirs_found;
        embree_extra += !ours.found() && theirs_found;
      } else {
        ++closests;
        const hf::BvhHit ours = bvh.closest(q.a, q.radius);
        const EmbreeAnswer theirs = embree_closest(embree.scene, mesh, q);
        const bool same = ours.found() == (theirs.triangle != RTC_INVALID_GEOMETRY_ID);
        closest_same += same;
        if (same && ours.found()) worst_gap = std::fmax(worst_gap, std::fabs(ours.distance - theirs.value));
      }
    }

    // per-tick cost of the recorded queries, each tree in turn, in the same run
    double sink = 0.0;
    std::size_t next = 0;
    auto ours_tick = [&]() noexcept {
      const std::size_t g = next++ % groups;
      for (std::size_t i = begin[g]; i < begin[g + 1]; ++i) {
        const Query& q = log[i];
        sink += q.sweep ? bvh.first_hit(q.a, q.b).t : bvh.closest(q.a, q.radius).b1;
      }
    };
    auto embree_tick = [&]() noexcept {
      const std::size_t g = next++ % groups;
      for (std::size_t i = begin[g]; i < begin[g + 1]; ++i) {
        const Query& q = log[i];
        sink += q.sweep ? embree_first_hit(embree.scene, q).value
                        : static_cast<double>(embree_closest(embree.scene, mesh, q).triangle);
      }
    };
    struct Row {
      hf::offline::TickBudgetReport cost;
      double sweep_ns, closest_ns;
      long allocations;
    };
    const auto kind_mean = [&](bool sweep, auto&& one) {
      const double a = cpu_seconds();
      std::size_t k = 0;
      for (int repeat = 0; repeat < 3; ++repeat)
        for (const Query& q : log)
          if (q.sweep == sweep) {
            sink += one(q);
            ++k;
          }
      return k ? (cpu_seconds() - a) * 1e9 / static_cast<double>(k) : 0.0;
    };
    const auto measure = [&](auto&& tick, auto&& sweep_one, auto&& closest_one) {
      Row r{};
      next = 0;
      allocations = 0;
      counting = true;  // one plain pass over every tick: the harness's own buffers are not counted
      for (std::size_t g = 0; g < groups; ++g)
        tick();
      counting = false;
      r.allocations = allocations;
      next = 0;
      r.cost = hf::offline::measure_tick_cost(groups, tick, hf::bench::thread_cpu_budget());
      r.sweep_ns = kind_mean(true, sweep_one);
      r.closest_ns = kind_mean(false, closest_one);
      return r;
    };
    const Row ours = measure(
        ours_tick, [&](const Query& q) { return bvh.first_hit(q.a, q.b).t; },
        [&](const Query& q) { return bvh.closest(q.a, q.radius).b1; });
    const Row theirs = measure(
        embree_tick, [&](const Query& q) { return embree_first_hit(embree.scene, q).value; },
        [&](const Query& q) { return static_cast<double>(embree_closest(embree.scene, mesh, q).triangle); });
    std::printf("| %zu | MeshBvh | %.2f | %.0f | %.0f | %.0f | %.0f | %.0f | %ld |\n", mesh.triangles.size(),
                ours_build / mtri, ours.cost.mean_ns, ours.cost.p99_ns, ours.cost.worst_ns, ours.sweep_ns,
                ours.closest_ns, ours.allocations);
    std::printf("| %zu | Embree | %.2f | %.0f | %.0f | %.0f | %.0f | %.0f | %ld |\n", mesh.triangles.size(),
                embree_build / mtri, theirs.cost.mean_ns, theirs.cost.p99_ns, theirs.cost.worst_ns, theirs.sweep_ns,
                theirs.closest_ns, theirs.allocations);
    std::printf("| | Embree / MeshBvh | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | |\n", embree_build / ours_build,
                theirs.cost.mean_ns / ours.cost.mean_ns, theirs.cost.p99_ns / ours.cost.p99_ns,
                theirs.cost.worst_ns / ours.cost.worst_ns, theirs.sweep_ns / ours.sweep_ns,
                theirs.closest_ns / ours.closest_ns);
    char line[256];
    std::snprintf(line, sizeof line, "| %zu | %.1f | %zu | %.2f%% | %zu | %zu | %zu | %.2f%% | %.2g |",
                  mesh.triangles.size(), static_cast<double>(log.size()) / static_cast<double>(groups), sweeps,
                  100.0 * static_cast<double>(sweep_same) / static_cast<double>(std::max<std::size_t>(1, sweeps)),
                  embree_missed, embree_extra, closests,
                  100.0 * static_cast<double>(closest_same) / static_cast<double>(std::max<std::size_t>(1, closests)),
                  worst_gap);
    agreement.emplace_back(line);
    if (!std::isfinite(sink)) std::printf("(non-finite)\n");
  }
  rtcReleaseDevice(device);
  std::printf("\n### Agreement (same triangle, or none, on each recorded query)\n\n");
  std::printf(
      "| triangles | queries per tick | first_hit queries | same answer | hit by MeshBvh only | hit by Embree only | "
      "closest queries | same answer | worst distance gap [m] |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& l : agreement)
    std::printf("%s\n", l.c_str());
  return 0;
}
