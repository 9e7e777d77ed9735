#pragma once
/// @file deforming_mesh.hpp
/// A mesh whose vertices another thread moves while the loop runs:
/// DeformingMeshFeed (the writer's end: it keeps the mesh and its tree,
/// refits the tree to each new set of positions, MeshBvh::refit, never
/// rebuilds it, and publishes the result) and DeformingMesh (the Shape the
/// proxy holds: at the start of each tick, advance() swaps in the newest
/// frame without a lock; the queries are MeshShape's on it).
///
/// The topology is fixed: the same triangles, the same vertex count; each
/// frame brings the positions and, optionally, the vertex normals. Refit
/// keeps the tree's shape, so queries answer exactly as on a tree rebuilt
/// over the frame's mesh, while the deformation keeps every triangle's area
/// and moves vertices of equal positions alike (MeshBvh::refit); boxes
/// overlap more after large deformations and queries visit more nodes.
///
/// A deformation is not rigid, so the proxy is not carried with it: after a
/// new frame a touching proxy is put back in front of the face it touched
/// when that face has come up to it (surface/proxy.hpp); a free proxy is
/// not followed, so a surface that moves through the HIP within one tick
/// leaves it inside, felt as nothing until it comes out (as a HIP that
/// starts inside a solid). Rigid motion: Moving<S> (surface/moving_shape.hpp).
///
/// Threads: one writer (publish(): refits a frame the reader gave back in
/// place, with no allocation once three frames circulate; the first ones are
/// copies of the mesh and its tree; may throw); one reader, the servo
/// thread, owns the DeformingMesh (advance and the queries: no allocation,
/// no lock). Three frames: three copies of the mesh and its tree in memory.

#include <algorithm>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/core/live_field.hpp"
#include "hapticfield/surface/mesh_bvh.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/shape.hpp"
#include "hapticfield/surface/triangle_mesh.hpp"

namespace hapticfield {

/// One published state of a deforming mesh.
struct DeformedFrame {
  MeshShape shape;            ///< the mesh at this frame and its refit tree
  std::uint64_t sequence{0};  ///< 0 for the first frame, then one more per publish()
};

/// The writer's end of a deforming mesh.
class DeformingMeshFeed {
 public:
  /// Builds the tree once over `mesh` (allocates; about a second per million
  /// triangles) and makes it the first frame.
  /// @throws std::invalid_argument as MeshShape.
  explicit DeformingMeshFeed(TriangleMesh mesh, const MeshShapeConfig& config = {})
      : mesh_(std::move(mesh)),
        bvh_(MeshBvh::build(mesh_, MeshBvhConfig{config.max_nodes, config.huge_pages})),
        shade_normals_(config.shade_normals),
        buffer_(std::make_unique<DeformedFrame>(DeformedFrame{MeshShape(mesh_, bvh_, shade_normals_), 0})) {}
  DeformingMeshFeed(const DeformingMeshFeed&) = delete;
  DeformingMeshFeed& operator=(const DeformingMeshFeed&) = delete;

  /// Writer thread: the mesh with its vertices at `positions` [m] (one per
  /// vertex) and, when given, new vertex normals (one per vertex; empty: the
  /// last ones), its tree refit; the reader feels it from its next tick on.
  /// @throws std::invalid_argument for a wrong count, a non-finite value or
  ///         normals for a mesh without them (nothing is published then).
  void publish(std::span<const glm::dvec3> positions, std::span<const glm::dvec3> normals = {}) {
    if (positions.size() != mesh_.positions.size())
      throw std::invalid_argument("DeformingMeshFeed: " + std::to_string(positions.size()) + " positions for " +
                                  std::to_string(mesh_.positions.size()) + " vertices");
    if (!normals.empty() && !mesh_.has_normals())
      throw std::invalid_argument("DeformingMeshFeed: the mesh has no vertex normals to replace");
    if (!normals.empty() && normals.size() != mesh_.positions.size())
      throw std::invalid_argument("DeformingMeshFeed: " + std::to_string(normals.size()) + " normals for " +
                                  std::to_string(mesh_.positions.size()) + " vertices");
    for (const glm::dvec3& p : positions)
      if (!is_finite(p)) throw std::invalid_argument("DeformingMeshFeed: a position is not finite");
    for (const glm::dvec3& n : normals)
      if (!is_finite(n)) throw std::invalid_argument("DeformingMeshFeed: a normal is not finite");
    if (!normals.empty()) normals_.assign(normals.begin(), normals.end());
    // a frame the reader gave back, refit in place; else (the first two, or
    // one still shared) a new one from the first frame's mesh and tree
    std::unique_ptr<DeformedFrame> frame = std::move(spare_);
    if (!frame || !frame->shape.refit(positions, normals_)) {
      frame = std::make_unique<DeformedFrame>(DeformedFrame{MeshShape(mesh_, bvh_, shade_normals_), 0});
      (void)frame->shape.refit(positions, normals_);  // unshared: always refits
    }
    frame->sequence = ++sequence_;
    spare_ = buffer_.publish(std::move(frame));
  }

  /// Reader thread: the newest frame (wait-free, no allocation).
  [[nodiscard]] const DeformedFrame& newest() noexcept { return *buffer_.acquire(); }

 private:
  TriangleMesh mesh_;  ///< the first frame's mesh and tree: the topology new frames start from
  MeshBvh bvh_;
  bool shade_normals_;
  std::vector<glm::dvec3> normals_;  ///< the last normals published (empty: the mesh's own)
  std::uint64_t sequence_{0};
  TripleBuffer<DeformedFrame> buffer_;
  std::unique_ptr<DeformedFrame> spare_;  ///< a frame the reader gave back, for the next publish
};

/// The Shape of a deforming mesh: MeshShape's answers on the frame taken at
/// the last advance(). Move-only: one reader.
class DeformingMesh {
 public:
  static constexpr bool flat_primitives = true;

  /// A deforming mesh with its own feed (feed() for the writer).
  /// @throws std::invalid_argument as MeshShape.
  explicit DeformingMesh(TriangleMesh mesh, const MeshShapeConfig& config = {})
      : DeformingMesh(std::make_shared<DeformingMeshFeed>(std::move(mesh), config)) {}
  /// @throws std::invalid_argument for a null feed.
  explicit DeformingMesh(std::shared_ptr<DeformingMeshFeed> feed) : feed_(std::move(feed)) {
    if (!feed_) throw std::invalid_argument("DeformingMesh: the feed must not be null");
    frame_ = &feed_->newest();
  }
  DeformingMesh(const DeformingMesh&) = delete;
  DeformingMesh& operator=(const DeformingMesh&) = delete;
  DeformingMesh(DeformingMesh&&) noexcept = default;
  DeformingMesh& operator=(DeformingMesh&&) noexcept = default;

  /// Servo thread, at the start of a tick: the newest frame. True when it
  /// is a new one.
  bool advance(double /*time*/) noexcept {
    const std::uint64_t before = frame_->sequence;
    frame_ = &feed_->newest();
    return frame_->sequence != before;
  }

  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance) const noexcept {
    return frame_->shape.closest(p, max_distance);
  }
  [[nodiscard]] Hit closest(const glm::dvec3& p, double max_distance, QueryStats* stats) const noexcept {
    return frame_->shape.closest(p, max_distance, stats);
  }
  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to) const noexcept {
    return frame_->shape.first_hit(from, to);
  }
  [[nodiscard]] Hit first_hit(const glm::dvec3& from, const glm::dvec3& to, QueryStats* stats) const noexcept {
    return frame_->shape.first_hit(from, to, stats);
  }
  [[nodiscard]] Hit sweep_sphere(const glm::dvec3& from, const glm::dvec3& to, double radius,
                                 QueryStats* stats = nullptr) const noexcept {
    return frame_->shape.sweep_sphere(from, to, radius, stats);
  }
  [[nodiscard]] Hit on_primitive(std::uint32_t primitive, const glm::dvec3& p, double max_distance) const noexcept {
    return frame_->shape.on_primitive(primitive, p, max_distance);
  }

  /// The frame of the last advance().
  [[nodiscard]] const DeformedFrame& frame() const noexcept { return *frame_; }
  /// The writer's end.
  [[nodiscard]] const std::shared_ptr<DeformingMeshFeed>& feed() const noexcept { return feed_; }

 private:
  std::shared_ptr<DeformingMeshFeed> feed_;
  const DeformedFrame* frame_{nullptr};
};

static_assert(Shape<DeformingMesh>);

}  // namespace hapticfield
