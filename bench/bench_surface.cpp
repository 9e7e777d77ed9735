// Cost of a proxy tick on meshes from 1k to 4M triangles, as ratios against
// baselines measured in the same run: the proxy on an analytic plane, and a
// brute-force scan of every triangle (where it finishes); MeshBvh build time
// per million triangles; the height-field tick against a tangible-image
// tick; a mesh's first pass on 2 MB against 4 KB pages; the look-ahead
// against none, back to back and paced at 1 kHz (--paced-ticks, default
// 10000: 10 s a row); a ball's region of the tree kept between sweeps
// against none; each tick cold against the same tick again warm, beside a
// load from memory that waits for the one before (a pointer chase); and the
// highest stiffness that stays passive at each servo rate.
//
//   bench_surface [--ticks N] [--max-triangles N] [--paced-ticks N] [--no-passivity]
#include <hapticfield/kernels.hpp>
#include <hapticfield/servo/pacer.hpp>
#include <hapticfield/surface.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include <sys/prctl.h>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "../tests/surface_energy.hpp"
#include "../tests/surface_meshes.hpp"
#include "../tests/tree_walk_shape.hpp"
#include "surface_path.hpp"
#include "tick_cost.hpp"

namespace hf = hapticfield;
using Clock = std::chrono::steady_clock;

namespace {

/// Every triangle tested for every query: the baseline a tree must beat.
class BruteShape {
 public:
  explicit BruteShape(const hf::TriangleMesh& mesh) : mesh_(mesh) {}

  [[nodiscard]] hf::Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    const glm::dvec3 d = to - from;
    hf::Hit best;
    double best_t = 1.0;
    for (std::uint32_t k = 0; k < mesh_.triangles.size(); ++k) {
      const auto& t = mesh_.triangles[k];
      const glm::dvec3 a = mesh_.positions[t[0]], e1 = mesh_.positions[t[1]] - a, e2 = mesh_.positions[t[2]] - a;
      const glm::dvec3 n = glm::cross(e1, e2);
      const double dn = glm::dot(d, n);
      if (!(dn < 0.0)) continue;  // back face or parallel
      const double s = glm::dot(a - from, n) / dn;
      if (!(s >= 0.0 && s < best_t)) continue;
      const glm::dvec3 p = from + s * d - a;
      const double b1 = glm::dot(glm::cross(p, e2), n) / glm::dot(n, n);
      const double b2 = glm::dot(glm::cross(e1, p), n) / glm::dot(n, n);
      if (b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0) continue;
      best_t = s;
      best = describe(k, from + s * d);
      best.t = s;
    }
    return best;
  }

  [[nodiscard]] hf::Hit closest(const glm::dvec3& p, double max_distance) const noexcept {
    hf::Hit best;
    double best_d = max_distance;
    for (std::uint32_t k = 0; k < mesh_.triangles.size(); ++k) {
      const auto& t = mesh_.triangles[k];
      const glm::dvec3 a = mesh_.positions[t[0]], b = mesh_.positions[t[1]], c = mesh_.positions[t[2]];
      // the face when the projection is inside, else the nearest edge point
      const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
      const glm::dvec3 q = p - glm::dot(p - a, n) * n;
      const auto side = [&](const glm::dvec3& x, const glm::dvec3& y) {
        return glm::dot(glm::cross(y - x, q - x), n) >= 0.0;
      };
      glm::dvec3 best_point = q;
      if (!(side(a, b) && side(b, c) && side(c, a))) {
        double nearest = std::numeric_limits<double>::max();
        for (const auto& [x, y] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
          const double s = std::clamp(glm::dot(p - x, y - x) / glm::dot(y - x, y - x), 0.0, 1.0);
          const glm::dvec3 e = x + s * (y - x);
          if (glm::length(e - p) < nearest) {
            nearest = glm::length(e - p);
            best_point = e;
          }
        }
      }
      const double dist = glm::length(best_point - p);
      if (dist <= best_d) {
        best_d = dist;
        best = describe(k, best_point);
        best.distance = dist;
      }
    }
    return best;
  }

 private:
  [[nodiscard]] hf::Hit describe(std::uint32_t k, const glm::dvec3& point) const noexcept {
    const auto& t = mesh_.triangles[k];
    const glm::dvec3 a = mesh_.positions[t[0]], b = mesh_.positions[t[1]], c = mesh_.positions[t[2]];
    hf::Hit h;
    h.point = point;
    h.face_normal = h.normal = glm::normalize(glm::cross(b - a, c - a));
    h.size = std::sqrt(std::fmax(glm::dot(b - a, b - a), std::fmax(glm::dot(c - a, c - a), glm::dot(c - b, c - b))));
    h.primitive = k;
    return h;
  }

  const hf::TriangleMesh& mesh_;
};

template <class Proxy>
hf::bench::Cost tick_cost(Proxy& proxy, const std::vector<hf::Probe>& path, double& mean_nodes,
                          std::uint32_t& worst_nodes) {
  // one pass first, so that every proxy is timed with the tree as warm as
  // the last one's (the first pass after a build runs cold); each pass
  // starts afresh (reset(): no jump from the path's end to its start)
  glm::dvec3 sink{0.0};
  for (const hf::Probe& p : path)
    sink += proxy.contact(p).force;
  double node_sum = 0.0;
  worst_nodes = 0;
  struct Tick {
    Proxy& proxy;
    glm::dvec3& sink;
    double& node_sum;
    std::uint32_t& worst_nodes;
    glm::dvec3 force(const hf::Probe& p) noexcept {
      const glm::dvec3 f = proxy.contact(p).force;
      sink += f;
      node_sum += proxy.last_tick().nodes;
      worst_nodes = std::max(worst_nodes, proxy.last_tick().nodes);
      return f;
    }
    void reset() noexcept { proxy.reset(); }
  } tick{proxy, sink, node_sum, worst_nodes};
  const hf::bench::Cost c = hf::offline::measure_tick_budget(tick, path, hf::bench::thread_cpu_budget());
  mean_nodes = node_sum / (2.0 * static_cast<double>(path.size()));  // two passes
  if (!hf::is_finite(sink)) std::printf("(non-finite force)\n");
  return c;
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Mean, p99, p99.9 and worst of per-tick times [ns].
hf::bench::Cost summary(std::vector<double> ns) {
  hf::bench::Cost c;
  if (ns.empty()) return c;
  std::sort(ns.begin(), ns.end());
  double sum = 0.0;
  for (const double v : ns)
    sum += v;
  const auto at = [&](double q) { return ns[std::min(ns.size() - 1, static_cast<std::size_t>(q * ns.size()))]; };
  c.ticks = ns.size();
  c.mean_ns = sum / static_cast<double>(ns.size());
  c.p50_ns = at(0.5);
  c.p99_ns = at(0.99);
  c.p999_ns = at(0.999);
  c.worst_ns = ns.back();
  return c;
}

/// The monotonic clock [ns]: read without a system call (the thread's CPU
/// clock is one, which costs more than a point's tick and disturbs the
/// caches it measures).
double monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return 1e9 * static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec);
}

/// One pass over the path by two proxies, their ticks alternated (the one
/// that goes first swaps every tick), each timed on the monotonic clock (a
/// preempted tick counts, as likely for either); with `look_ahead`, each
/// proxy anticipates its tick right before it (as the servo loop does in
/// the slack before the deadline). `nodes` receives each proxy's mean tree
/// nodes a tick.
template <class A, class B>
std::array<hf::bench::Cost, 2> alternated_pair(A& a, B& b, const std::vector<hf::Probe>& path, bool look_ahead,
                                               std::array<double, 2>& nodes) {
  std::vector<double> ta(path.size()), tb(path.size());
  glm::dvec3 sink{0.0};
  nodes = {0.0, 0.0};
  for (std::size_t i = 0; i < path.size(); ++i) {
    for (int k = 0; k < 2; ++k) {
      const bool a_now = (k == 0) == (i % 2 == 0);
      if (look_ahead) a_now ? a.anticipate(path[i]) : b.anticipate(path[i]);
      const double t0 = monotonic_ns();
      sink += a_now ? a.contact(path[i]).force : b.contact(path[i]).force;
      (a_now ? ta : tb)[i] = monotonic_ns() - t0;
      nodes[a_now ? 0 : 1] += a_now ? a.last_tick().nodes : b.last_tick().nodes;
    }
  }
  if (!hf::is_finite(sink)) std::printf("(non-finite force)\n");
  for (double& n : nodes)
    n /= static_cast<double>(std::max<std::size_t>(1, path.size()));
  return {summary(std::move(ta)), summary(std::move(tb))};
}

/// The first pass after the builds of two proxies' meshes, both cold, as a
/// hand's first pass over a part of a large mesh is.
template <class A, class B>
std::array<hf::bench::Cost, 2> first_pass_pair(A& a, B& b, const std::vector<hf::Probe>& path) {
  std::array<double, 2> nodes{};
  return alternated_pair(a, b, path, false, nodes);
}

/// The bench's wavy sheet, `side` [m] square, of about 1M triangles (707 x
/// 707 squares): what the 1M-triangle sections feel.
hf::TriangleMesh million_triangle_sheet(double side) {
  const int n = static_cast<int>(std::lround(std::sqrt(1'000'000.0 / 2.0)));
  return hf::test::wavy_sheet(side, n, 0.002, 0.03);
}

/// A ball's region of the tree kept between its sweeps (MeshBvh::
/// Neighbourhood, what a ball proxy on a mesh does) against every sweep
/// walking the tree (test::TreeWalk), at 1M triangles: meshes built apart,
/// a warm-up pass each, then ticks alternated, back to back and with the
/// look-ahead right before each tick. Forces are the same bit for bit
/// (test_sphere_proxy).
void neighbourhood_section(double side, const std::vector<hf::Probe>& path, std::size_t max_triangles) {
  if (max_triangles < 1'000'000) return;
  std::printf(
      "## A ball's region of the tree kept between sweeps (MeshBvh::Neighbourhood, the default) against every "
      "sweep walking the tree, 1M triangles\n\n"
      "Meshes built apart, a pass each first, then ticks alternated (wall time per tick, monotonic clock); back to "
      "back, and with each tick anticipated right before it as the servo loop's look-ahead does.\n\n"
      "| radius [mm] | timing | kept: mean [ns] | p99 [ns] | p99.9 [ns] | worst [ns] | walked: mean [ns] | p99 [ns] | "
      "p99.9 [ns] | worst [ns] | walked / kept mean | walked / kept p99 | walked / kept p99.9 | tree nodes a tick, "
      "kept / walked |\n"
      "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  const hf::TriangleMesh mesh = million_triangle_sheet(side);
  const hf::MeshShape one(mesh), other(mesh);
  for (const double radius : {0.0005, 0.002}) {
    hf::ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
    config.radius = radius;
    for (const bool look_ahead : {false, true}) {
      hf::ProxyConstraint<hf::MeshShape> kept(one, config);
      hf::ProxyConstraint<hf::test::TreeWalk> walked(hf::test::TreeWalk{other}, config);
      std::array<double, 2> nodes{};
      (void)alternated_pair(kept, walked, path, false, nodes);  // the warm-up pass
      kept.reset();
      walked.reset();
      const auto [k, w] = alternated_pair(kept, walked, path, look_ahead, nodes);
      std::printf(
          "| %.1f | %s | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.2f | %.2f | %.2f | %.1f / %.1f |\n",
          radius * 1e3, look_ahead ? "look-ahead before each tick" : "back to back", k.mean_ns, k.p99_ns, k.p999_ns,
          k.worst_ns, w.mean_ns, w.p99_ns, w.p999_ns, w.worst_ns, w.mean_ns / k.mean_ns, w.p99_ns / k.p99_ns,
          w.p999_ns / k.p999_ns, nodes[0], nodes[1]);
    }
  }
  std::printf("\n");
}

/// The first pass over a large mesh on 2 MB pages (the default) against
/// 4 KB pages, for a point and two balls. Every pair of meshes is built
/// before any pass and kept to the end: the page hint stays on an address
/// range after it is freed (rt/huge_pages.hpp), so a 4 KB mesh built where
/// a freed 2 MB one was would get huge pages too.
void first_pass_section(double side, const std::vector<hf::Probe>& path, std::size_t max_triangles) {
  std::printf(
      "## The first pass over a large mesh: its tree and arrays on 2 MB pages (MeshShapeConfig::huge_pages, "
      "the default) against 4 KB pages\n\n"
      "Each pair of meshes built apart, then one pass with their ticks alternated (wall time per tick on the "
      "monotonic clock, read without a system call).\n\n"
      "| triangles | radius [mm] | mean [ns] | p99 [ns] | p99.9 [ns] | worst [ns] | 4 KB mean [ns] | 4 KB p99 [ns] | "
      "4 KB p99.9 [ns] | 4 KB worst [ns] | 4 KB / 2 MB mean | 4 KB / 2 MB p99 | 4 KB / 2 MB p99.9 |\n"
      "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  struct Pair {
    std::size_t triangles;
    double radius;  // [m]
    hf::MeshShape huge, plain;
  };
  std::vector<Pair> pairs;
  hf::MeshShapeConfig small_pages;
  small_pages.huge_pages = false;
  for (const std::size_t target : {250'000ul, 1'000'000ul}) {
    if (target > max_triangles) break;
    const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(target) / 2.0)));
    const hf::TriangleMesh mesh = hf::test::wavy_sheet(side, n, 0.002, 0.03);
    for (const double radius : {0.0, 0.0005, 0.002})
      pairs.push_back(Pair{mesh.triangles.size(), radius, hf::MeshShape(mesh), hf::MeshShape(mesh, small_pages)});
  }
  for (const Pair& pair : pairs) {
    hf::ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
    config.radius = pair.radius;
    hf::ProxyConstraint on_huge(pair.huge, config), on_plain(pair.plain, config);
    const auto [h, p] = first_pass_pair(on_huge, on_plain, path);
    std::printf("| %zu | %.1f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.2f | %.2f | %.2f |\n",
                pair.triangles, pair.radius * 1e3, h.mean_ns, h.p99_ns, h.p999_ns, h.worst_ns, p.mean_ns, p.p99_ns,
                p.p999_ns, p.worst_ns, p.mean_ns / h.mean_ns, p.p99_ns / h.p99_ns, p.p999_ns / h.p999_ns);
  }
  std::printf("\n");
}

/// The HIP of tick i as a loop anticipates it after tick i - 1: the last
/// one moved by the last step (the path's velocity field is a fixed damping
/// input, not its motion; a device's velocity is the same difference).
hf::Probe predicted(const std::vector<hf::Probe>& path, std::size_t i) {
  if (i < 2) return path[i > 0 ? i - 1 : 0];
  hf::Probe p = path[i - 1];
  p.position = 2.0 * path[i - 1].position - path[i - 2].position;
  p.time = path[i].time;
  return p;
}

/// The look-ahead (ProxyConstraint::anticipate, run by the servo loop in
/// the slack before each deadline) against none, at 1M triangles: two
/// proxies on meshes built apart, one pass each way with their ticks
/// alternated, (1) back to back as the table below times them, the
/// look-ahead right before its tick, and (2) paced at 1 kHz by the loop's
/// Pacer in sleep mode, the look-ahead through Pacer::wait(clock, ready) as
/// the loop runs it, the other proxy's tick half a period away.
/// Wall time on the monotonic clock from the tick's wake to its force; the
/// look-ahead's own cost apart, with how often it ran past the deadline.
void anticipation_section(double side, const std::vector<hf::Probe>& path, std::size_t max_triangles,
                          long paced_ticks) {
  if (max_triangles < 1'000'000) return;
  std::printf(
      "## The look-ahead (ProxyConstraint::anticipate in the slack before each deadline, LoopConfig::anticipate) "
      "against none, "
      "1M triangles\n\n"
      "Two proxies on equal meshes built apart, ticks alternated; back to back over the whole path (the look-ahead "
      "right before its tick), then paced at 1 kHz over its first %ld ticks by the loop's Pacer in sleep mode (the "
      "look-ahead through Pacer::wait(clock, ready), 100 us before the deadline; timer slack 1 ns, as the loop sets "
      "it). Wall time of the tick alone, from its wake to its force (monotonic clock); the look-ahead's own time "
      "apart.\n\n"
      "| radius [mm] | timing | mean [ns] | p99 [ns] | p99.9 [ns] | worst [ns] | look-ahead: mean [ns] | p99 [ns] | "
      "p99.9 [ns] | worst [ns] | none / look-ahead mean | none / look-ahead p99 | none / look-ahead p99.9 | "
      "look-ahead's own mean [ns] | its p99 [ns] | its p99.9 [ns] | look-aheads skipped / past the deadline |\n"
      "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
      paced_ticks);
  // the loop's timer slack (rt/realtime_thread.hpp): 1 ns, so each sleep
  // ends at its time, not up to 50 us later
  const int slack = prctl(PR_GET_TIMERSLACK, 0UL, 0UL, 0UL, 0UL);
  (void)prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  const hf::TriangleMesh mesh = million_triangle_sheet(side);
  const hf::MeshShape one(mesh), other(mesh);
  for (const double radius : {0.0, 0.0005}) {
    hf::ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
    config.radius = radius;
    for (const bool paced : {false, true}) {
      hf::ProxyConstraint plain(one, config), ahead(other, config);
      const std::size_t ticks = paced ? std::min(path.size(), static_cast<std::size_t>(paced_ticks)) : path.size();
      std::vector<double> tp(ticks), ta(ticks), own;
      own.reserve(ticks);
      glm::dvec3 sink{0.0};
      // paced: two Pacers (the loop's, in sleep mode), half a period apart;
      // the look-ahead proxy's waits run its look-ahead as the loop does
      const hf::SteadyClock clock;
      hf::Pacer pace_plain(1'000'000), pace_ahead(1'000'000);
      const std::int64_t start = clock.now() + 1'000'000;
      pace_plain.start(start);
      pace_ahead.start(start + 500'000);
      long late = 0, skipped = 0;  // look-aheads that ended past their tick's deadline; that the pacer skipped
      for (std::size_t i = 0; i < ticks; ++i) {
        for (int k = 0; k < 2; ++k) {
          const bool plain_now = paced ? k == 0 : (k == 0) == (i % 2 == 0);  // back to back: who goes first swaps
          const hf::Probe next = predicted(path, i);
          const auto look = [&ahead, &next, &own]() noexcept {
            const double t0 = monotonic_ns();
            ahead.anticipate(next);
            own.push_back(monotonic_ns() - t0);  // (reserved: no allocation)
          };
          if (paced && plain_now) {
            (void)pace_plain.wait(clock);
          } else if (paced) {
            (void)pace_ahead.wait(clock, look);
            skipped += pace_ahead.look_ahead().skipped ? 1 : 0;
            late += pace_ahead.look_ahead().late ? 1 : 0;
          } else if (!plain_now) {
            look();
          }
          const double t0 = monotonic_ns();
          sink += plain_now ? plain.contact(path[i]).force : ahead.contact(path[i]).force;
          const double t1 = monotonic_ns();
          (plain_now ? tp : ta)[i] = t1 - t0;
          if (paced) (void)(plain_now ? pace_plain : pace_ahead).finish(clock.now());
        }
      }
      if (!hf::is_finite(sink)) std::printf("(non-finite force)\n");
      const hf::bench::Cost p = summary(std::move(tp)), a = summary(std::move(ta)), o = summary(std::move(own));
      std::printf(
          "| %.1f | %s | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.2f | %.2f | %.2f | %.0f | %.0f | "
          "%.0f | %ld / %ld |\n",
          radius * 1e3, paced ? "paced at 1 kHz" : "back to back", p.mean_ns, p.p99_ns, p.p999_ns, p.worst_ns,
          a.mean_ns, a.p99_ns, a.p999_ns, a.worst_ns, p.mean_ns / a.mean_ns, p.p99_ns / a.p99_ns, p.p999_ns / a.p999_ns,
          o.mean_ns, o.p99_ns, o.p999_ns, skipped, late);
    }
  }
  std::printf("\n");
  (void)prctl(PR_SET_TIMERSLACK, static_cast<unsigned long>(slack), 0UL, 0UL, 0UL);
}

/// The machine's limit for what a cold tick meets: the time of a load that
/// depends on the one before and misses every cache [ns], timed as the
/// median of five passes of a chase through 256 MB (about the 1M-triangle
/// mesh's arrays, and more than this machine's share of its caches) in a
/// random order, one 64-byte line a step, on 2 MB pages as the mesh's
/// arrays are.
double dependent_load_ns() {
  constexpr std::size_t line = 8, lines = (std::size_t{256} << 20) / 64;  // 8 words a line
  std::vector<std::uint64_t> chase;
  hf::reserve_on_huge_pages(chase, lines * line);
  chase.resize(lines * line);
  std::vector<std::uint32_t> order(lines);
  for (std::size_t i = 0; i < lines; ++i)
    order[i] = static_cast<std::uint32_t>(i);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(1));
  for (std::size_t i = 0; i < lines; ++i)
    chase[order[i] * line] = std::uint64_t{order[(i + 1) % lines]} * line;
  constexpr int hops = 1'000'000;
  std::array<double, 5> pass{};
  std::uint64_t at = 0;
  for (double& ns : pass) {
    const double t0 = monotonic_ns();
    for (int h = 0; h < hops; ++h)
      at = chase[at];
    ns = (monotonic_ns() - t0) / hops;
  }
  if (at == 1) std::printf("(chase ended on word 1)\n");  // keeps the chase
  std::sort(pass.begin(), pass.end());
  return pass[2];
}

/// What the slowest ticks cost in arithmetic against the rest, at 1M
/// triangles: each tick of one pass timed as the tables time it (cold: its
/// first touch of the triangles and tree nodes around a slip), then the
/// same tick again on a copy of the proxy taken before it, right after
/// (warm: its data, code and branches as that tick left them). The warm
/// tick is what the arithmetic costs; the difference is what a slip meets
/// first (memory, a branch history not seen before), which the look-ahead
/// takes off the tick by making the same queries in the slack before the
/// deadline. Wall time, monotonic clock; the copies outside the times;
/// answers equal (the copy makes the same tick).
void warm_section(double side, const std::vector<hf::Probe>& path, std::size_t max_triangles) {
  if (max_triangles < 1'000'000) return;
  const double load_ns = dependent_load_ns();
  std::printf(
      "## The slowest ticks: cold (as the tables time them) against the same tick again right after (warm), "
      "1M triangles\n\n"
      "One pass; before each tick a copy of the proxy, which makes the same tick again right after it with its "
      "data, code and branches warm. The warm time is the arithmetic; the rest of the cold time is what a slip "
      "meets first (tree nodes, triangles and vertices, a branch history not seen before), which the look-ahead "
      "takes off the tick. "
      "Wall time per tick (monotonic clock), copies untimed.\n\n"
      "The last column is the cold p99's excess over the warm one in loads from memory that each wait for the "
      "one before (the machine's limit: a chase through 256 MB in a random order, this run, %.0f ns a load).\n\n"
      "| radius [mm] | cold: mean [ns] | p99 [ns] | p99.9 [ns] | warm: mean [ns] | p99 [ns] | p99.9 [ns] | "
      "cold / warm mean | cold / warm p99 | cold / warm p99.9 | answers equal | cold - warm p99, in loads from "
      "memory |\n"
      "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|\n",
      load_ns);
  const hf::TriangleMesh mesh = million_triangle_sheet(side);
  const hf::MeshShape shape(mesh);
  for (const double radius : {0.0, 0.0005}) {
    hf::ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
    config.radius = radius;
    hf::ProxyConstraint proxy(shape, config);
    std::vector<double> cold(path.size()), warm(path.size());
    bool equal = true;
    for (std::size_t i = 0; i < path.size(); ++i) {
      hf::ProxyConstraint again(proxy);
      double t0 = monotonic_ns();
      const glm::dvec3 f = proxy.contact(path[i]).force;
      cold[i] = monotonic_ns() - t0;
      t0 = monotonic_ns();
      const glm::dvec3 g = again.contact(path[i]).force;
      warm[i] = monotonic_ns() - t0;
      equal = equal && f == g;
    }
    const hf::bench::Cost c = summary(std::move(cold)), w = summary(std::move(warm));
    std::printf("| %.1f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.2f | %.2f | %.2f | %s | %.1f |\n", radius * 1e3,
                c.mean_ns, c.p99_ns, c.p999_ns, w.mean_ns, w.p99_ns, w.p999_ns, c.mean_ns / w.mean_ns,
                c.p99_ns / w.p99_ns, c.p999_ns / w.p999_ns, equal ? "yes" : "NO", (c.p99_ns - w.p99_ns) / load_ns);
  }
  std::printf("\n");
}

/// The highest stiffness [N/m] that stays passive at `rate` [Hz] (bisection
/// on the energy check of tests/surface_energy.hpp), on a mesh surface.
double highest_passive(const hf::TriangleMesh& mesh, double rate) {
  double lo = 100.0, hi = 100000.0;
  for (int step = 0; step < 14; ++step) {
    const double k = std::sqrt(lo * hi);
    hf::ProxyConstraint proxy(hf::MeshShape(mesh), hf::ProxyConfig{k});
    const auto run = hf::test::tap_and_slide(proxy, rate, 10.0);
    (run.excess <= 1e-9 * run.dissipated + 1e-12 ? lo : hi) = k;
  }
  return lo;
}

}  // namespace

int main(int argc, char** argv) {
  long ticks = 20000;
  std::size_t max_triangles = 4'000'000;
  bool passivity = true;
  long paced_ticks = 10000;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--ticks") && a + 1 < argc)
      ticks = std::atol(argv[++a]);
    else if (!std::strcmp(argv[a], "--max-triangles") && a + 1 < argc)
      max_triangles = static_cast<std::size_t>(std::atoll(argv[++a]));
    else if (!std::strcmp(argv[a], "--no-passivity"))
      passivity = false;
    else if (!std::strcmp(argv[a], "--paced-ticks") && a + 1 < argc)
      paced_ticks = std::atol(argv[++a]);
    else if (!std::strcmp(argv[a], "--help")) {
      std::printf("usage: bench_surface [--ticks N] [--max-triangles N] [--paced-ticks N] [--no-passivity]\n");
      return 0;
    } else {
      std::fprintf(stderr, "usage: bench_surface [--ticks N] [--max-triangles N] [--paced-ticks N] [--no-passivity]\n");
      return 2;
    }
  }
  const double side = 0.1;  // [m]
  const std::vector<hf::Probe> path = hf::bench::sliding_path(ticks, side / 2);

  // --- first, before any mesh is freed: 2 MB pages against 4 KB pages ---
  first_pass_section(side, path, max_triangles);
  // --- the look-ahead against none, back to back and paced at 1 kHz ---
  anticipation_section(side, path, max_triangles, paced_ticks);
  // --- a ball's region of the tree kept between sweeps against none ---
  neighbourhood_section(side, path, max_triangles);
  // --- the slowest ticks cold against warm: the arithmetic against the rest ---
  warm_section(side, path, max_triangles);

  // --- baseline: the proxy on an analytic plane ---
  hf::ProxyConstraint plane(hf::PlaneShape(hf::PlaneShapeConfig{}), hf::ProxyConfig{1500.0, 1.0, 0.5, 0.4});
  double plane_nodes = 0.0;
  std::uint32_t plane_worst_nodes = 0;
  const hf::bench::Cost base = tick_cost(plane, path, plane_nodes, plane_worst_nodes);
  std::printf(
      "Times are this thread's CPU time per call, measured by the tick-budget harness (servo/tick_budget.hpp;\n"
      "the clock read pair's median cost, %.0f ns, subtracted). Baseline verdict: %s.\n\n",
      base.clock_overhead_ns, base.fits_1khz ? "fits 1 kHz" : "does NOT fit 1 kHz");
  std::printf("## Proxy tick on a wavy mesh (sliding 2 mm deep with friction, %ld ticks)\n\n", ticks);
  std::printf("Baseline: the proxy on an analytic plane, mean %.0f ns, p99 %.0f ns, worst %.0f ns.\n\n", base.mean_ns,
              base.p99_ns, base.worst_ns);
  std::printf(
      "| triangles | build [ms] | build [s per M] | depth | mean [ns] | p99 [ns] | worst [ns] | "
      "mean / plane | p99 / plane | nodes mean | nodes worst | brute mean / tree mean | full tick mean [ns] | "
      "full tick p99 [ns] | full tick worst [ns] | ball 0.5 mm mean [ns] | ball 0.5 mm p99 [ns] | "
      "ball 0.5 mm worst [ns] | ball 2 mm mean [ns] | ball 2 mm p99 [ns] | ball 2 mm worst [ns] |\n");
  std::printf(
      "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  // per size: the 0.5 and 2 mm balls by default, then with the full tick
  std::vector<std::pair<std::size_t, std::array<hf::bench::Cost, 4>>> balls;
  // per size: the 0.5 and 2 mm balls on the tree without its nodes' slabs
  std::vector<std::pair<std::size_t, std::array<hf::bench::Cost, 2>>> slabs;
  for (const std::size_t target : {1'000ul, 16'000ul, 250'000ul, 1'000'000ul, 4'000'000ul}) {
    if (target > max_triangles) break;
    const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(target) / 2.0)));
    hf::TriangleMesh mesh = hf::test::wavy_sheet(side, n, 0.002, 0.03);
    const auto t0 = Clock::now();
    hf::MeshShape shape(mesh);
    const double build_s = seconds_since(t0);
    hf::ProxyConstraint proxy(shape, hf::ProxyConfig{1500.0, 1.0, 0.5, 0.4});
    double nodes = 0.0;
    std::uint32_t worst_nodes = 0;
    const hf::bench::Cost c = tick_cost(proxy, path, nodes, worst_nodes);
    std::string brute = "-";
    if (mesh.triangles.size() <= 20'000) {  // a brute-force tick at 250k triangles takes milliseconds
      hf::ProxyConstraint slow(BruteShape(mesh), hf::ProxyConfig{1500.0, 1.0, 0.5, 0.4});
      const std::vector<hf::Probe> few(path.begin(), path.begin() + std::min<long>(ticks, 2000));
      double unused = 0.0;
      std::uint32_t unused_worst = 0;
      const hf::bench::Cost b = tick_cost(slow, few, unused, unused_worst);
      brute = std::to_string(static_cast<int>(std::lround(b.mean_ns / c.mean_ns))) + " x";
    }
    // the same proxy with the full tick (ProxyConfig::stick_first off: the
    // frictionless proxy first, then the friction move back)
    hf::ProxyConfig whole{1500.0, 1.0, 0.5, 0.4};
    whole.stick_first = false;
    hf::ProxyConstraint full(shape, whole);
    double full_nodes = 0.0;
    std::uint32_t full_worst_nodes = 0;
    const hf::bench::Cost q = tick_cost(full, path, full_nodes, full_worst_nodes);
    // a ball-shaped tool (ProxyConfig::radius) of 0.5 and 2 mm on the same
    // path, by default and with the full tick
    const auto ball_cost = [&](const hf::MeshShape& on, double radius, bool stick_first) {
      hf::ProxyConfig round{1500.0, 1.0, 0.5, 0.4};
      round.radius = radius;
      round.stick_first = stick_first;
      hf::ProxyConstraint tool(on, round);
      double ball_nodes = 0.0;
      std::uint32_t ball_worst_nodes = 0;
      return tick_cost(tool, path, ball_nodes, ball_worst_nodes);
    };
    std::array<hf::bench::Cost, 4> ball{};
    for (std::size_t b = 0; b < 4; ++b)
      ball[b] = ball_cost(shape, b % 2 == 0 ? 0.0005 : 0.002, b < 2);
    balls.emplace_back(mesh.triangles.size(), ball);
    // the same balls on the same tree without its nodes' slabs
    // (MeshBvh::NodeBounds): a second build, refit to the same vertices,
    // which drops them
    hf::MeshShape plain(mesh);
    (void)plain.refit(mesh.positions);
    const std::array<hf::bench::Cost, 2> boxes_only{ball_cost(plain, 0.0005, true), ball_cost(plain, 0.002, true)};
    slabs.emplace_back(mesh.triangles.size(), boxes_only);
    const double mtri = static_cast<double>(mesh.triangles.size()) / 1e6;
    std::printf(
        "| %zu | %.1f | %.2f | %zu | %.0f | %.0f | %.0f | %.1f | %.1f | %.1f | %u | %s | %.0f | %.0f | %.0f | %.0f | "
        "%.0f "
        "| %.0f | %.0f | %.0f | %.0f |\n",
        mesh.triangles.size(), build_s * 1e3, build_s / mtri, shape.bvh().depth(), c.mean_ns, c.p99_ns, c.worst_ns,
        c.mean_ns / base.mean_ns, c.p99_ns / base.p99_ns, nodes, worst_nodes, brute.c_str(), q.mean_ns, q.p99_ns,
        q.worst_ns, ball[0].mean_ns, ball[0].p99_ns, ball[0].worst_ns, ball[1].mean_ns, ball[1].p99_ns,
        ball[1].worst_ns);
  }
  std::printf(
      "\n## Ball-shaped tools: the friction cone first (the default) against the full tick\n\n"
      "| triangles | radius [mm] | mean [ns] | p99 [ns] | worst [ns] | full tick mean [ns] | full tick p99 [ns] | "
      "full tick worst [ns] | full / default mean | full / default p99 |\n"
      "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [triangles, ball] : balls)
    for (std::size_t b = 0; b < 2; ++b) {
      const hf::bench::Cost& d = ball[b];
      const hf::bench::Cost& f = ball[b + 2];
      std::printf("| %zu | %.1f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.1f | %.1f |\n", triangles,
                  b == 0 ? 0.5 : 2.0, d.mean_ns, d.p99_ns, d.worst_ns, f.mean_ns, f.p99_ns, f.worst_ns,
                  f.mean_ns / d.mean_ns, f.p99_ns / d.p99_ns);
    }
  std::printf(
      "\n## Ball-shaped tools: each node's slab kept (MeshBvh::NodeBounds, built by default) against the same "
      "tree without them (refit, which drops them)\n\n"
      "| triangles | radius [mm] | mean [ns] | p99 [ns] | worst [ns] | boxes only mean [ns] | boxes only p99 [ns] | "
      "boxes only worst [ns] | boxes / slabs mean | boxes / slabs p99 | boxes / slabs worst |\n"
      "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (std::size_t i = 0; i < slabs.size(); ++i)
    for (std::size_t b = 0; b < 2; ++b) {
      const hf::bench::Cost& d = balls[i].second[b];
      const hf::bench::Cost& o = slabs[i].second[b];
      std::printf("| %zu | %.1f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.2f | %.2f | %.2f |\n", slabs[i].first,
                  b == 0 ? 0.5 : 2.0, d.mean_ns, d.p99_ns, d.worst_ns, o.mean_ns, o.p99_ns, o.worst_ns,
                  o.mean_ns / d.mean_ns, o.p99_ns / d.p99_ns, o.worst_ns / d.worst_ns);
    }

  // --- height field vs tangible image, on a picture-sized grid ---
  {
    const int w = 1504, h = 1000;
    const double spacing = 1.0 / 6400.0 * 1.0;  // 6.4 px/mm [m]
    struct Grid {
      int width, height;
      double spacing_x, spacing_y;
      std::vector<double> heights;
    } grid{w, h, spacing, spacing, {}};
    hf::GrayImage gray(w, h);
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        const double level = 127.5 + 127.5 * std::sin(i * 0.05) * std::cos(j * 0.04);
        gray.at(i, j) = level;
        grid.heights.push_back(level * 1e-5);  // 0 .. 2.55 mm
      }
    const auto t0 = Clock::now();
    hf::HeightFieldShape field(grid);
    const double build_s = seconds_since(t0);
    hf::ProxyConstraint proxy(field, hf::ProxyConfig{1500.0, 1.0, 0.5, 0.4});
    std::vector<hf::Probe> over = hf::bench::sliding_path(ticks, w * spacing / 2);
    for (auto& p : over) {
      p.position.x += w * spacing / 2;
      p.position.y += h * spacing / 2;
      p.position.z += 0.0013;
    }
    double nodes = 0.0;
    std::uint32_t worst_nodes = 0;
    const hf::bench::Cost c = tick_cost(proxy, over, nodes, worst_nodes);
    const hf::TangibleImageField image(hf::TangibleImage(gray, hf::TangibleConfig{}),
                                       hf::PlaneMapping(6.4, glm::dvec2{w / 2.0, h / 2.0}), 1.0);
    const hf::bench::Cost t = hf::offline::measure_tick_budget(image, over, hf::bench::thread_cpu_budget());
    std::printf("\n## Height field (%d x %d, build %.0f ms) against the tangible image of the same picture\n\n", w, h,
                build_s * 1e3);
    std::printf(
        "| field | mean [ns] | p99 [ns] | worst [ns] | nodes mean | nodes worst |\n|---|---:|---:|---:|---:|---:|\n");
    std::printf("| tangible image (17 px Prewitt) | %.0f | %.0f | %.0f | - | - |\n", t.mean_ns, t.p99_ns, t.worst_ns);
    std::printf("| proxy on the height field | %.0f | %.0f | %.0f | %.1f | %u |\n", c.mean_ns, c.p99_ns, c.worst_ns,
                nodes, worst_nodes);
    std::printf("\nHeight field / tangible image: mean %.1f x, p99 %.1f x, worst %.1f x.\n", c.mean_ns / t.mean_ns,
                c.p99_ns / t.p99_ns, c.worst_ns / t.worst_ns);
  }

  // --- passivity: the highest stable stiffness against the servo rate ---
  if (passivity) {
    const hf::TriangleMesh mesh = hf::with_vertex_normals(hf::test::wavy_sheet(0.1, 60, 0.001, 0.03));
    std::printf("\n## Highest passive stiffness (0.1 kg arm with 1 N s/m damping, 10 s of tapping and sliding)\n\n");
    std::printf("| rate [Hz] | highest passive k [N/m] | 2 b / T [N/m] | k T / (2 b) |\n|---:|---:|---:|---:|\n");
    for (const double rate : {500.0, 1000.0, 2000.0, 4000.0}) {
      const double k = highest_passive(mesh, rate);
      std::printf("| %.0f | %.0f | %.0f | %.2f |\n", rate, k, 2.0 * rate, k / (2.0 * rate));
    }
  }
  return 0;
}
