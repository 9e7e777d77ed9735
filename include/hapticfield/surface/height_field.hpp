#pragma once
/// @file height_field.hpp
/// HeightFieldShape: the surface z = h(x, y) over a regular grid of heights,
/// bilinear in each cell, solid below, as a Shape for the proxy.
///
/// The grid: width x height samples, heights[j * width + i] [m] at
/// x = i spacing_x, y = j spacing_y (row j = 0 first, x right, y up, z toward
/// the user); any type with those five members (io::HeightGrid, filled by the
/// height-map readers) can be handed over, surface/ never includes io/.
///
/// What the queries see: each cell is the bilinear patch through its four
/// corners, so a cliff between two samples is a steep wall the proxy cannot
/// pass, never a hole; first_hit() solves the segment against the patch
/// exactly (a quadratic in the segment's parameter), closest() takes the
/// nearest of the patch's four straight edges and a Newton step inside.
/// Cells are found through an implicit min-max quadtree (2 x 2 cells per
/// node, built once), so a query visits O(log n) nodes plus the cells next to
/// the surface it meets, within a node budget like MeshBvh's.
///
/// Edges: the surface covers only the grid's footprint [0, (width - 1)
/// spacing_x] x [0, (height - 1) spacing_y]. Beyond it there is nothing: a
/// proxy pressed onto the field slides off its border as off a table's edge
/// and the HIP is free there. The field has no sides and no underside (one-
/// sided, like an open mesh): a HIP that starts below it is not touching.
///
/// Normals: face_normal is the patch's own normal at the point; normal
/// blends the four corners' normals from central differences (one-sided at
/// the border) bilinearly (force shading, Morgenbesser & Srinivasan 1996),
/// so a sampled smooth function feels smooth. uv runs 0..1 over the
/// footprint (u along x, v along y); primitive is the cell, j (width - 1) + i.
///
/// A tool with a radius (sweep_sphere): the ball sees each cell as two flat
/// triangles split along its diagonal from (i, j) to (i + 1, j + 1), and
/// meets their faces, edges and corners as on a mesh (ball_sweep.hpp). They
/// share the samples with the bilinear patch and differ from it inside a
/// cell by at most a quarter of the cell's twist |h00 - h10 - h01 + h11|
/// (0 on a plane or a ramp); a ball rests r above the triangles.

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/surface/ball_sweep.hpp"
#include "hapticfield/surface/mesh_bvh.hpp"
#include "hapticfield/surface/shape.hpp"

namespace hapticfield {

/// The most samples a height field may hold (100 Mpx).
inline constexpr std::size_t height_field_max_samples = 100'000'000;

struct HeightFieldConfig {
  bool shade_normals{true};                        ///< blend the corners' normals (force shading)
  std::uint32_t max_nodes{bvh_default_max_nodes};  ///< node budget of one query (quadtree nodes and cells)
};

/// A grid of heights as the readers give it (io::HeightGrid and the like).
template <class G>
concept HeightGridLike = requires(const G& g) {
  { g.width } -> std::convertible_to<long long>;
  { g.height } -> std::convertible_to<long long>;
  { g.spacing_x } -> std::convertible_to<double>;
  { g.spacing_y } -> std::convertible_to<double>;
  {std::span<const double>(g.heights)};
};

class HeightFieldShape {
 public:
  /// closest() measures to the bilinear patches, sweep_sphere() meets the
  /// cells' two triangles: the two may disagree on whether a ball overlaps.
  static constexpr bool closest_matches_sweep = false;
  /// Its queries only read the grid, shared by copies (PureQueries).
  static constexpr bool pure_queries = true;

  /// @throws std::invalid_argument for fewer than 2 x 2 samples (0 x 0
  ///         included), more than height_field_max_samples (checked before
  ///         anything is allocated), spacings that are not finite and > 0,
  ///         a heights size that is not width x height, or a non-finite
  ///         height; std::bad_alloc when memory runs out.
  HeightFieldShape(long long width, long long height, double spacing_x, double spacing_y,
                   std::span<const double> heights, const HeightFieldConfig& config = {})
      : config_(config) {
    if (width < 2 || height < 2)
      throw std::invalid_argument("HeightFieldShape: need at least 2 x 2 samples, got " + std::to_string(width) +
                                  " x " + std::to_string(height));
    if (static_cast<unsigned long long>(width) > height_field_max_samples / static_cast<unsigned long long>(height))
      throw std::invalid_argument("HeightFieldShape: " + std::to_string(width) + " x " + std::to_string(height) +
                                  " samples is more than the limit of 100 Mpx");
    if (!std::isfinite(spacing_x) || !std::isfinite(spacing_y) || spacing_x <= 0.0 || spacing_y <= 0.0)
      throw std::invalid_argument("HeightFieldShape: spacings must be finite and > 0 [m]");
    const auto n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (heights.size() != n)
      throw std::invalid_argument("HeightFieldShape: " + std::to_string(heights.size()) + " heights for " +
                                  std::to_string(width) + " x " + std::to_string(height) + " samples");
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(heights[k]))
        throw std::invalid_argument("HeightFieldShape: height " + std::to_string(k) + " is not finite");
    if (config.max_nodes == 0) throw std::invalid_argument("HeightFieldShape: max_nodes must be > 0");
    auto data = std::make_shared<Data>();
    data->width = static_cast<std::uint32_t>(width);
    data->height = static_cast<std::uint32_t>(height);
    data->spacing = glm::dvec2{spacing_x, spacing_y};
    data->heights.assign(heights.begin(), heights.end());
    build_pyramid(*data);
    data_ = std::move(data);
  }

  /// From a grid type with width, height, spacing_x, spacing_y and heights.
  template <HeightGridLike G>
  explicit HeightFieldShape(const G& grid, const HeightFieldConfig& config = {})
      : HeightFieldShape(static_cast<long long>(grid.width), static_cast<long long>(grid.height),
                         static_cast<double>(grid.spacing_x), static_cast<double>(grid.spacing_y),
                         std::span<const double>(grid.heights), config) {}

  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    return first_hit(from, to, nullptr);
  }

  /// The first cell met from above going from `from` to `to`.
  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to, QueryStats* stats) const noexcept {
    QueryStats work;
    Hit best;
    const glm::dvec3 d = to - from;
    if (!is_finite(from) || !is_finite(d)) return best;
    const Data& g = *data_;
    double best_t = 1.0;
    std::uint32_t best_cell = no_primitive;
    glm::dvec2 best_st{0.0};
    const bool complete =
        traverse(from, to, 0.0, best_t, work, [&](std::uint32_t i, std::uint32_t j, double entry, double exit) {
          intersect_cell(g, i, j, from, d, entry, exit, best_t, best_cell, best_st);
        });
    if (stats) *stats = work;
    if (!complete) {
      best.complete = false;
      best.t = 0.0;
      return best;
    }
    if (best_cell == no_primitive) return best;
    best = describe(best_cell, best_st);
    best.t = best_t;
    best.distance = best_t * glm::length(d);
    return best;
  }

  /// The first contact of a ball of `radius` [m] whose centre moves from
  /// `from` to `to` (the tool's radius; see the file comment: cells are two
  /// flat triangles for a ball). Hit::point is the touched point of the
  /// field, face_normal the contact normal (unit, from it to the centre at
  /// contact), normal the shaded normal where the ball touches a cell's
  /// inside, else the contact normal; t the fraction of the move. A centre
  /// that starts below the field (inside the solid) meets nothing, as a point
  /// does. radius > 0 and finite.
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius,
                                 QueryStats* stats = nullptr) const noexcept {
    QueryStats work;
    if (stats) *stats = work;
    Hit best;
    const glm::dvec3 d = to - from;
    if (!(radius > 0.0) || !std::isfinite(radius) || !is_finite(from) || !is_finite(d)) return best;
    const Data& g = *data_;
    if (below_triangles(g, from)) return best;
    double best_t = 1.0;
    std::uint32_t best_cell = no_primitive;
    glm::dvec3 best_contact{0.0};
    const bool complete =
        traverse(from, to, radius, best_t, work, [&](std::uint32_t i, std::uint32_t j, double, double) {
          for (int half = 0; half < 2; ++half) {
            const Triangle tri = cell_triangle(g, i, j, half);
            if (detail::sweep_ball_triangle(tri.a, tri.e1, tri.e2, from, d, radius, best_t, best_contact))
              best_cell = j * (g.width - 1) + i;
          }
        });
    if (stats) *stats = work;
    if (!complete) {
      best.complete = false;
      best.t = 0.0;
      return best;
    }
    if (best_cell == no_primitive) return best;
    const std::uint32_t i = best_cell % (g.width - 1), j = best_cell / (g.width - 1);
    const glm::dvec2 st{std::clamp(best_contact.x / g.spacing.x - i, 0.0, 1.0),
                        std::clamp(best_contact.y / g.spacing.y - j, 0.0, 1.0)};
    best = describe(best_cell, st);
    const glm::dvec3 centre = from + best_t * d;
    const glm::dvec3 towards = centre - best_contact;
    const double length = glm::length(towards);
    const Triangle tri = cell_triangle(g, i, j, st.x >= st.y ? 0 : 1);
    const glm::dvec3 flat = glm::normalize(glm::cross(tri.e1, tri.e2));  // the touched half's normal
    const glm::dvec3 n = length > 0.0 ? towards / length : flat;
    if (!(glm::dot(n, flat) > 1.0 - 1e-12)) best.normal = n;  // an edge or a corner: no shading
    best.face_normal = n;
    best.point = best_contact;
    best.t = best_t;
    best.distance = best_t * glm::length(d);
    return best;
  }

  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance) const noexcept {
    return closest(p, max_distance, nullptr);
  }

  /// The nearest point of the surface within max_distance [m].
  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance, QueryStats* stats) const noexcept {
    QueryStats work;
    Hit best;
    if (!is_finite(p) || !(max_distance >= 0.0)) return best;
    const Data& g = *data_;
    double best_d2 = std::isfinite(max_distance) ? max_distance * max_distance : std::numeric_limits<double>::max();
    std::uint32_t best_cell = no_primitive;
    glm::dvec2 best_st{0.0};
    const double reach = std::isfinite(max_distance) ? max_distance : 1e300;
    const bool complete = walk(
        smallest_node(g, p - glm::dvec3{reach}, p + glm::dvec3{reach}), work,
        [&](const NodeRef& node, Span& span) {
          span.key = box_distance2(box_of(g, node), p);
          return span.key <= best_d2;
        },
        [&](const NodeRef& node, const Span&) {
          glm::dvec2 st{0.0};
          const double d2 = closest_in_cell(g, node.i, node.j, p, st);
          if (d2 <= best_d2) {
            best_d2 = d2;
            best_cell = node.j * (g.width - 1) + node.i;
            best_st = st;
          }
        });
    if (stats) *stats = work;
    if (best_cell == no_primitive) {
      best.complete = complete;
      return best;
    }
    best = describe(best_cell, best_st);
    best.distance = std::sqrt(best_d2);
    best.complete = complete;
    return best;
  }

  /// The point of one cell nearest to p, if within max_distance [m] (no
  /// tree traversal: the proxy's check that it is still on a cell).
  [[nodiscard]] Hit on_primitive(std::uint32_t primitive, const glm::dvec3& p, double max_distance) const noexcept {
    const Data& g = *data_;
    if (primitive >= (g.width - 1) * (g.height - 1) || !is_finite(p)) return Hit{};
    glm::dvec2 st{0.0};
    const double d2 = closest_in_cell(g, primitive % (g.width - 1), primitive / (g.width - 1), p, st);
    if (!(d2 <= max_distance * max_distance)) return Hit{};
    Hit h = describe(primitive, st);
    h.distance = std::sqrt(d2);
    return h;
  }

  /// The bilinear height at (x, y) [m]; NaN outside the footprint.
  [[nodiscard]] double height_at(double x, double y) const noexcept {
    const Data& g = *data_;
    const double fx = x / g.spacing.x, fy = y / g.spacing.y;
    if (!(fx >= 0.0 && fy >= 0.0 && fx <= g.width - 1.0 && fy <= g.height - 1.0))
      return std::numeric_limits<double>::quiet_NaN();
    const auto i = std::min(static_cast<std::uint32_t>(fx), g.width - 2);
    const auto j = std::min(static_cast<std::uint32_t>(fy), g.height - 2);
    return bilinear(g, i, j, fx - i, fy - j);
  }

  [[nodiscard]] std::uint32_t width() const noexcept { return data_->width; }
  [[nodiscard]] std::uint32_t height() const noexcept { return data_->height; }
  [[nodiscard]] glm::dvec2 spacing() const noexcept { return data_->spacing; }
  /// Quadtree levels above the cells.
  [[nodiscard]] std::size_t levels() const noexcept { return data_->levels.size(); }
  [[nodiscard]] const HeightFieldConfig& config() const noexcept { return config_; }

 private:
  /// A quadtree node: level 0 is a cell, level L covers 2^L x 2^L cells.
  struct NodeRef {
    std::uint32_t level{0}, i{0}, j{0};
  };
  /// One level's node count and the min-max heights of its nodes.
  struct Level {
    std::uint32_t nx{0}, ny{0};
    std::vector<std::array<float, 2>> range;  ///< [min, max] height [m], rounded outward
  };
  struct Data {
    std::uint32_t width{0}, height{0};
    glm::dvec2 spacing{0.0};
    std::vector<double> heights;
    std::vector<Level> levels;  ///< levels[L - 1] is level L (L >= 1); the last one is the root
  };
  struct Box {
    glm::dvec3 lo{0.0}, hi{0.0};
  };

  /// Levels stay below 32 (width and height < 2^27), each pushes at most
  /// four children: a fixed stack of this size always suffices.
  static constexpr std::size_t stack_size = 4 * 32 + 1;

  using Kids = std::array<std::pair<double, NodeRef>, 4>;

  /// The smallest quadtree node holding every cell under the box [lo, hi]
  /// (x and y only; cells outside the grid do not exist): a short query
  /// starts there instead of at the root.
  static NodeRef smallest_node(const Data& g, const glm::dvec3& lo, const glm::dvec3& hi) noexcept {
    const auto top_level = static_cast<std::uint32_t>(g.levels.size());
    const auto cell = [](double v, double spacing, std::uint32_t cells) {
      const double c = std::floor(v / spacing);
      if (!(c >= 0.0)) return std::uint32_t{0};  // also NaN
      if (!(c < static_cast<double>(cells))) return cells - 1;
      return static_cast<std::uint32_t>(c);
    };
    const std::uint32_t i0 = cell(lo.x, g.spacing.x, g.width - 1), i1 = cell(hi.x, g.spacing.x, g.width - 1);
    const std::uint32_t j0 = cell(lo.y, g.spacing.y, g.height - 1), j1 = cell(hi.y, g.spacing.y, g.height - 1);
    std::uint32_t level = 0;
    while (level < top_level && ((i0 >> level) != (i1 >> level) || (j0 >> level) != (j1 >> level)))
      ++level;
    return NodeRef{level, i0 >> level, j0 >> level};
  }

  /// Pushes the children farthest first (largest key), so the nearest is
  /// popped next (an insertion sort of at most four).
  static void push_nearest_last(Kids& kids, int count, std::array<NodeRef, stack_size>& stack,
                                std::size_t& top) noexcept {
    for (int a = 1; a < count; ++a)
      for (int b = a; b > 0 && kids[static_cast<std::size_t>(b - 1)].first < kids[static_cast<std::size_t>(b)].first;
           --b)
        std::swap(kids[static_cast<std::size_t>(b - 1)], kids[static_cast<std::size_t>(b)]);
    for (int k = 0; k < count; ++k)
      stack[top++] = kids[static_cast<std::size_t>(k)].second;
  }

  static void build_pyramid(Data& g) {
    std::uint32_t nx = g.width - 1, ny = g.height - 1;
    std::vector<std::array<float, 2>> below;  // the level under the one being built
    for (std::uint32_t level = 1; nx > 1 || ny > 1 || level == 1; ++level) {
      const std::uint32_t mx = (nx + 1) / 2, my = (ny + 1) / 2;
      Level out;
      out.nx = mx;
      out.ny = my;
      out.range.assign(static_cast<std::size_t>(mx) * my,
                       {std::numeric_limits<float>::max(), -std::numeric_limits<float>::max()});
      for (std::uint32_t j = 0; j < ny; ++j)
        for (std::uint32_t i = 0; i < nx; ++i) {
          std::array<float, 2> r{};
          if (level == 1) {
            double lo = std::numeric_limits<double>::max(), hi = -lo;
            for (std::uint32_t c = 0; c < 4; ++c) {
              const double h = g.heights[static_cast<std::size_t>(j + c / 2) * g.width + i + c % 2];
              lo = std::fmin(lo, h);
              hi = std::fmax(hi, h);
            }
            r = {round_down(lo), round_up(hi)};
          } else {
            r = below[static_cast<std::size_t>(j) * nx + i];
          }
          auto& dst = out.range[static_cast<std::size_t>(j / 2) * mx + i / 2];
          dst[0] = std::min(dst[0], r[0]);
          dst[1] = std::max(dst[1], r[1]);
        }
      below = out.range;
      g.levels.push_back(std::move(out));
      nx = mx;
      ny = my;
    }
  }

  static float round_down(double v) noexcept {
    auto f = static_cast<float>(v);
    if (static_cast<double>(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
  }
  static float round_up(double v) noexcept {
    auto f = static_cast<float>(v);
    if (static_cast<double>(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
  }

  static bool exists(const Data& g, const NodeRef& n) noexcept {
    if (n.level == 0) return n.i < g.width - 1 && n.j < g.height - 1;
    const Level& l = g.levels[n.level - 1];
    return n.i < l.nx && n.j < l.ny;
  }

  [[nodiscard]] static double at(const Data& g, std::uint32_t i, std::uint32_t j) noexcept {
    return g.heights[static_cast<std::size_t>(j) * g.width + i];
  }

  static Box box_of(const Data& g, const NodeRef& n) noexcept {
    const auto cells = static_cast<double>(std::uint64_t{1} << n.level);
    Box b;
    b.lo.x = n.i * cells * g.spacing.x;
    b.lo.y = n.j * cells * g.spacing.y;
    b.hi.x = detail::smaller((n.i + 1) * cells, g.width - 1.0) * g.spacing.x;
    b.hi.y = detail::smaller((n.j + 1) * cells, g.height - 1.0) * g.spacing.y;
    if (n.level == 0) {
      const double a = at(g, n.i, n.j), b1 = at(g, n.i + 1, n.j), c = at(g, n.i, n.j + 1), e = at(g, n.i + 1, n.j + 1);
      b.lo.z = detail::smaller(detail::smaller(a, b1), detail::smaller(c, e));
      b.hi.z = detail::larger(detail::larger(a, b1), detail::larger(c, e));
    } else {
      const Level& l = g.levels[n.level - 1];
      const auto& r = l.range[static_cast<std::size_t>(n.j) * l.nx + n.i];
      b.lo.z = r[0];
      b.hi.z = r[1];
    }
    return b;
  }

  /// The segment queries' traversal (first_hit, sweep_sphere): the nodes
  /// whose boxes, grown by `grow` [m] on every side, the segment from -> to
  /// meets before best_t, nearest first, within the node budget; each cell
  /// goes to cell(i, j, entry, exit) with the segment's parameters in its
  /// box, which may lower best_t. False when the budget ran out.
  template <class Cell>
  bool traverse(const glm::dvec3& from, const glm::dvec3& to, double grow, const double& best_t, QueryStats& work,
                Cell&& cell) const noexcept {
    const Data& g = *data_;
    const glm::dvec3 d = to - from;
    const glm::dvec3 inv{1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
    const glm::dvec3 margin{grow};
    const auto box = [&](const NodeRef& node) {
      Box b = box_of(g, node);
      b.lo -= margin;
      b.hi += margin;
      return b;
    };
    return walk(
        smallest_node(g, glm::min(from, to) - margin, glm::max(from, to) + margin), work,
        [&](const NodeRef& node, Span& span) { return segment_box(box(node), from, inv, best_t, span.key, span.end); },
        [&](const NodeRef& node, const Span& span) { cell(node.i, node.j, span.key, span.end); });
  }

  /// What a node's test gives the walk: the key that orders it (a squared
  /// distance or an entry parameter) and, for a segment, its exit.
  struct Span {
    double key{0.0}, end{0.0};
  };

  /// The quadtree walk both kinds of query share: from `start`, every node
  /// that test(node, span) accepts (tested again when popped, as the best
  /// answer so far may have shrunk), children nearest first (smallest key),
  /// each cell (level 0) to leaf(node, span). False when the node budget
  /// ran out.
  template <class Test, class Leaf>
  bool walk(const NodeRef& start, QueryStats& work, Test&& test, Leaf&& leaf) const noexcept {
    const Data& g = *data_;
    std::array<NodeRef, stack_size> stack{};
    std::size_t top = 0;
    stack[top++] = start;
    while (top > 0) {
      const NodeRef node = stack[--top];
      Span span;
      if (!test(node, span)) continue;
      if (++work.nodes > config_.max_nodes) return false;
      if (node.level == 0) {
        ++work.primitives;
        leaf(node, span);
        continue;
      }
      Kids kids{};
      int count = 0;
      for (std::uint32_t dj = 0; dj < 2; ++dj)
        for (std::uint32_t di = 0; di < 2; ++di) {
          const NodeRef child{node.level - 1, 2 * node.i + di, 2 * node.j + dj};
          if (!exists(g, child)) continue;
          Span c;
          if (test(child, c)) kids[static_cast<std::size_t>(count++)] = {c.key, child};
        }
      push_nearest_last(kids, count, stack, top);
    }
    return true;
  }

  /// One flat half of cell (i, j) as a ball sees it: half 0 is (i, j),
  /// (i + 1, j), (i + 1, j + 1) (s >= t), half 1 is (i, j), (i + 1, j + 1),
  /// (i, j + 1); both face up (+z).
  struct Triangle {
    glm::dvec3 a{0.0}, e1{0.0}, e2{0.0};
  };
  static Triangle cell_triangle(const Data& g, std::uint32_t i, std::uint32_t j, int half) noexcept {
    const glm::dvec3 p00{i * g.spacing.x, j * g.spacing.y, at(g, i, j)};
    const glm::dvec3 p11{(i + 1) * g.spacing.x, (j + 1) * g.spacing.y, at(g, i + 1, j + 1)};
    const glm::dvec3 other = half == 0 ? glm::dvec3{(i + 1) * g.spacing.x, j * g.spacing.y, at(g, i + 1, j)}
                                       : glm::dvec3{i * g.spacing.x, (j + 1) * g.spacing.y, at(g, i, j + 1)};
    return half == 0 ? Triangle{p00, other - p00, p11 - p00} : Triangle{p00, p11 - p00, other - p00};
  }

  /// True when p lies under the two-triangle surface a ball sees (inside the
  /// footprint only: beyond it there is no solid).
  static bool below_triangles(const Data& g, const glm::dvec3& p) noexcept {
    const double fx = p.x / g.spacing.x, fy = p.y / g.spacing.y;
    if (!(fx >= 0.0 && fy >= 0.0 && fx <= g.width - 1.0 && fy <= g.height - 1.0)) return false;
    const auto i = std::min(static_cast<std::uint32_t>(fx), g.width - 2);
    const auto j = std::min(static_cast<std::uint32_t>(fy), g.height - 2);
    const double s = fx - i, t = fy - j;
    const double h00 = at(g, i, j), h11 = at(g, i + 1, j + 1);
    const double h = s >= t ? h00 + (at(g, i + 1, j) - h00) * s + (h11 - at(g, i + 1, j)) * t
                            : h00 + (h11 - at(g, i, j + 1)) * s + (at(g, i, j + 1) - h00) * t;
    return p.z < h;
  }

  /// Slabs, as MeshBvh's (an axis without motion: inside or rejected);
  /// entry and exit receive the segment's parameters in the box.
  static bool segment_box(const Box& box, const glm::dvec3& from, const glm::dvec3& inv, double t_max, double& entry,
                          double& exit) noexcept {
    double t0 = 0.0, t1 = t_max;
    for (int k = 0; k < 3; ++k) {
      const double tol = 1e-12 * (std::fabs(box.lo[k]) + std::fabs(box.hi[k]));
      const double lo = box.lo[k] - tol, hi = box.hi[k] + tol;
      if (!std::isfinite(inv[k])) {
        if (from[k] < lo || from[k] > hi) return false;
        continue;
      }
      const double a = (lo - from[k]) * inv[k];
      const double b = (hi - from[k]) * inv[k];
      t0 = detail::larger(t0, detail::smaller(a, b));
      t1 = detail::smaller(t1, detail::larger(a, b));
    }
    entry = t0;
    exit = t1;
    return t0 <= t1;
  }

  static double box_distance2(const Box& b, const glm::dvec3& p) noexcept {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double out = detail::larger(0.0, detail::larger(b.lo[k] - p[k], p[k] - b.hi[k]));
      d2 += out * out;
    }
    return d2;
  }

  /// h(s, t) on cell (i, j), s and t in [0, 1].
  static double bilinear(const Data& g, std::uint32_t i, std::uint32_t j, double s, double t) noexcept {
    const double a = at(g, i, j), b = at(g, i + 1, j), c = at(g, i, j + 1), e = at(g, i + 1, j + 1);
    return a + (b - a) * s + (c - a) * t + (a - b - c + e) * s * t;
  }

  /// The segment from + tau d, tau in [entry, exit] (inside the cell's
  /// footprint), against the cell's patch: the first root of
  /// z(tau) - h(tau) = 0 where it goes from above to below.
  static void intersect_cell(const Data& g, std::uint32_t i, std::uint32_t j, const glm::dvec3& from,
                             const glm::dvec3& d, double entry, double exit, double& best_t, std::uint32_t& best_cell,
                             glm::dvec2& best_st) noexcept {
    const double a = at(g, i, j), b = at(g, i + 1, j) - a, c = at(g, i, j + 1) - a;
    const double e = a - at(g, i + 1, j) - at(g, i, j + 1) + at(g, i + 1, j + 1);
    const double s0 = from.x / g.spacing.x - i, t0 = from.y / g.spacing.y - j;
    const double ds = d.x / g.spacing.x, dt = d.y / g.spacing.y;
    // f(tau) = C + B tau + A tau^2 = z - h
    const double C = from.z - (a + b * s0 + c * t0 + e * s0 * t0);
    const double B = d.z - (b * ds + c * dt + e * (s0 * dt + t0 * ds));
    const double A = -e * ds * dt;
    std::array<double, 2> roots{2.0, 2.0};
    if (std::fabs(A) <= 1e-14 * (std::fabs(B) + std::fabs(C))) {
      if (B != 0.0) roots[0] = -C / B;
    } else {
      const double disc = B * B - 4.0 * A * C;
      if (disc >= 0.0) {
        const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
        roots = {q / A, q != 0.0 ? C / q : 2.0};
        if (roots[1] < roots[0]) std::swap(roots[0], roots[1]);
      }
    }
    // the box's entry and exit may round one ulp apart from the root (a flat cell's box has no height)
    const double slack = 1e-12;  // [-] of the segment
    for (const double tau : roots) {
      if (!(tau >= entry - slack && tau <= exit + slack && tau < best_t)) continue;
      if (!(B + 2.0 * A * tau <= 0.0)) continue;  // must go down through it (from behind: passes)
      best_t = std::clamp(tau, entry, exit);
      best_cell = j * (g.width - 1) + i;
      best_st = glm::dvec2{std::clamp(s0 + ds * tau, 0.0, 1.0), std::clamp(t0 + dt * tau, 0.0, 1.0)};
      return;
    }
  }

  /// Squared distance from p to cell (i, j)'s patch; st receives the
  /// nearest point's cell coordinates.
  static double closest_in_cell(const Data& g, std::uint32_t i, std::uint32_t j, const glm::dvec3& p,
                                glm::dvec2& st) noexcept {
    const double sx = g.spacing.x, sy = g.spacing.y;
    const double a = at(g, i, j), b = at(g, i + 1, j) - a, c = at(g, i, j + 1) - a;
    const double e = a - at(g, i + 1, j) - at(g, i, j + 1) + at(g, i + 1, j + 1);
    const glm::dvec3 origin{i * sx, j * sy, 0.0};
    const auto point = [&](double s, double t) {
      return origin + glm::dvec3{s * sx, t * sy, a + b * s + c * t + e * s * t};
    };
    double best = std::numeric_limits<double>::max();
    // the four edges are straight segments
    const std::array<std::array<double, 4>, 4> edges{{{0, 0, 1, 0}, {0, 1, 1, 1}, {0, 0, 0, 1}, {1, 0, 1, 1}}};
    for (const auto& edge : edges) {
      const glm::dvec3 p0 = point(edge[0], edge[1]), p1 = point(edge[2], edge[3]);
      const glm::dvec3 v = p1 - p0;
      const double w = std::clamp(glm::dot(p - p0, v) / glm::dot(v, v), 0.0, 1.0);
      const glm::dvec3 q = p0 + w * v - p;
      const double d2 = glm::dot(q, q);
      if (d2 < best) {
        best = d2;
        st = glm::dvec2{edge[0] + w * (edge[2] - edge[0]), edge[1] + w * (edge[3] - edge[1])};
      }
    }
    // inside: Newton on the squared distance from the point straight below
    double s = std::clamp((p.x - origin.x) / sx, 0.0, 1.0), t = std::clamp((p.y - origin.y) / sy, 0.0, 1.0);
    for (int k = 0; k < 6; ++k) {
      const glm::dvec3 F = point(s, t) - p;
      const glm::dvec3 Ps{sx, 0.0, b + e * t}, Pt{0.0, sy, c + e * s};
      const double gs = glm::dot(Ps, F), gt = glm::dot(Pt, F);
      const double hss = glm::dot(Ps, Ps), htt = glm::dot(Pt, Pt), hst = glm::dot(Ps, Pt) + e * F.z;
      const double det = hss * htt - hst * hst;
      if (!(det > 0.0)) break;
      s -= (htt * gs - hst * gt) / det;
      t -= (hss * gt - hst * gs) / det;
      if (!(s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0)) break;
    }
    if (s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0) {
      const glm::dvec3 q = point(s, t) - p;
      const double d2 = glm::dot(q, q);
      if (d2 < best) {
        best = d2;
        st = glm::dvec2{s, t};
      }
    }
    return best;
  }

  /// The normal from central differences at sample (i, j) (one-sided at the
  /// border), unit.
  static glm::dvec3 sample_normal(const Data& g, std::uint32_t i, std::uint32_t j) noexcept {
    const std::uint32_t i0 = i > 0 ? i - 1 : i, i1 = i + 1 < g.width ? i + 1 : i;
    const std::uint32_t j0 = j > 0 ? j - 1 : j, j1 = j + 1 < g.height ? j + 1 : j;
    const double hx = (at(g, i1, j) - at(g, i0, j)) / ((i1 - i0) * g.spacing.x);
    const double hy = (at(g, i, j1) - at(g, i, j0)) / ((j1 - j0) * g.spacing.y);
    return glm::normalize(glm::dvec3{-hx, -hy, 1.0});
  }

  [[nodiscard]] Hit describe(std::uint32_t cell, const glm::dvec2& st) const noexcept {
    const Data& g = *data_;
    const std::uint32_t i = cell % (g.width - 1), j = cell / (g.width - 1);
    const double s = st.x, t = st.y;
    const double a = at(g, i, j), b = at(g, i + 1, j) - a, c = at(g, i, j + 1) - a;
    const double e = a - at(g, i + 1, j) - at(g, i, j + 1) + at(g, i + 1, j + 1);
    const double hx = (b + e * t) / g.spacing.x, hy = (c + e * s) / g.spacing.y;  // slopes [-]
    Hit h;
    h.point = glm::dvec3{(i + s) * g.spacing.x, (j + t) * g.spacing.y, a + b * s + c * t + e * s * t};
    h.face_normal = glm::normalize(glm::dvec3{-hx, -hy, 1.0});
    h.normal = h.face_normal;
    if (config_.shade_normals) {
      const glm::dvec3 blend = (1 - s) * (1 - t) * sample_normal(g, i, j) + s * (1 - t) * sample_normal(g, i + 1, j) +
                               (1 - s) * t * sample_normal(g, i, j + 1) + s * t * sample_normal(g, i + 1, j + 1);
      const double length = glm::length(blend);
      if (length > 0.0 && glm::dot(blend, h.face_normal) > 0.0) h.normal = blend / length;
    }
    const double extent_x = (g.width - 1.0) * g.spacing.x, extent_y = (g.height - 1.0) * g.spacing.y;
    h.uv = glm::dvec2{(i + s) / (g.width - 1.0), (j + t) / (g.height - 1.0)};
    detail::tangent_frame(h.normal, glm::dvec3{extent_x, 0.0, extent_x * hx}, glm::dvec3{0.0, extent_y, extent_y * hy},
                          h.tangent, h.bitangent);
    const double rise = std::fmax(std::fmax(std::fabs(b), std::fabs(c)), std::fabs(b + c + e));
    h.size = std::sqrt(g.spacing.x * g.spacing.x + g.spacing.y * g.spacing.y + rise * rise);
    h.primitive = cell;
    return h;
  }

  std::shared_ptr<const Data> data_;
  HeightFieldConfig config_;
};

static_assert(Shape<HeightFieldShape>);

}  // namespace hapticfield
