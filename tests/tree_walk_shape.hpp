#pragma once
// A MeshShape whose ball sweeps all walk the tree: it passes on every query
// but the sweeps' cache (MeshShape::SweepCache), so a proxy on it keeps no
// region of the tree between sweeps. The baseline the Neighbourhood is held
// to, bit for bit in the tests and in time in bench_surface.
#include <cstdint>

#include <glm/vec3.hpp>

#include "hapticfield/surface/mesh_shape.hpp"

namespace hapticfield::test {

struct TreeWalk {
  static constexpr bool flat_primitives = true;
  static constexpr bool pure_queries = true;
  MeshShape mesh;
  [[nodiscard]] Hit closest(const glm::dvec3& p, double d) const noexcept { return mesh.closest(p, d); }
  [[nodiscard]] Hit closest(const glm::dvec3& p, double d, QueryStats* q) const noexcept {
    return mesh.closest(p, d, q);
  }
  [[nodiscard]] Hit first_hit(const glm::dvec3& a, const glm::dvec3& b) const noexcept { return mesh.first_hit(a, b); }
  [[nodiscard]] Hit first_hit(const glm::dvec3& a, const glm::dvec3& b, QueryStats* q) const noexcept {
    return mesh.first_hit(a, b, q);
  }
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& a, const glm::dvec3& b, double r, QueryStats* q = nullptr,
                                 std::uint32_t hint = no_primitive) const noexcept {
    return mesh.sweep_sphere(a, b, r, q, hint);
  }
  [[nodiscard]] Hit on_primitive(std::uint32_t primitive, const glm::dvec3& p, double d) const noexcept {
    return mesh.on_primitive(primitive, p, d);
  }
};

}  // namespace hapticfield::test
