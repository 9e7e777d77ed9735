// Surfaces from Python: height fields (arrays, pictures, depth maps), meshes (STL, OBJ, glTF) and analytic
// shapes, felt through the proxy (god-object) and composed with the other fields by uv.
#include "field.hpp"
#include "material.hpp"

#include <hapticfield/io/height_map.hpp>
#include <hapticfield/io/stl.hpp>
#include <hapticfield/material/material_surface.hpp>
#include <hapticfield/scenes/picture_relief.hpp>
#include <hapticfield/surface.hpp>
#if HAPTICFIELD_PYTHON_IO
#include <hapticfield/io/load_mesh.hpp>
#endif
#include <hapticfield/io/mesh_shading.hpp>

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <mutex>
#include <new>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace hapticfield::python {

namespace {

/// Every shape placed by a pose (surface/posed_shape.hpp): queries in the shape's own frame, hits back in the
/// device frame.
using AnyShape = std::variant<Posed<HeightFieldShape>, Posed<MeshShape>, Posed<PlaneShape>, Posed<SphereShape>>;

/// A moving surface's poses (surface/moving_shape.hpp): each field made on it reads a PoseFeed of its own (one
/// reader each), and set_pose() publishes to every one still alive.
struct Motion {
  std::mutex mutex;  ///< the writers' (Python threads'); the loops never take it
  MovingPose pose;   ///< the newest
  std::vector<std::weak_ptr<PoseFeed>> feeds;

  std::shared_ptr<PoseFeed> feed() {
    const std::lock_guard<std::mutex> lock(mutex);
    auto f = std::make_shared<PoseFeed>(pose);
    feeds.push_back(f);
    return f;
  }
  void publish(const MovingPose& next) {
    next.validate();
    const std::lock_guard<std::mutex> lock(mutex);
    pose = next;
    std::erase_if(feeds, [](const std::weak_ptr<PoseFeed>& f) { return f.expired(); });
    for (const auto& weak : feeds)
      if (const auto f = weak.lock()) f->publish(next);
  }
};

/// A deforming mesh's vertices (surface/deforming_mesh.hpp): each field made on it reads a DeformingMeshFeed of
/// its own (its tree built once from the newest mesh), and set_vertices() refits every one still alive.
struct Deformation {
  std::mutex mutex;   ///< the writers' (Python threads'); the loops never take it
  TriangleMesh mesh;  ///< the newest positions (and normals)
  MeshShapeConfig config;
  bool normals_from_faces{false};  ///< vertex normals recomputed from the faces at each set_vertices()
  std::uint64_t frames{0};         ///< set_vertices() calls
  std::vector<std::weak_ptr<DeformingMeshFeed>> feeds;

  std::shared_ptr<DeformingMeshFeed> feed() {
    const std::lock_guard<std::mutex> lock(mutex);
    auto f = std::make_shared<DeformingMeshFeed>(mesh, config);
    feeds.push_back(f);
    return f;
  }
};

/// A shape built in Python: never changes once built, so it needs no guard (each proxy made on it keeps its
/// own state). A moving or deforming one changes through its Motion or Deformation, which each proxy reads
/// from a feed of its own.
struct Surface {
  std::shared_ptr<const AnyShape> shape;
  std::string kind;  ///< height_field, mesh, plane, sphere
  std::string description;
  std::optional<std::pair<V3, V3>> bounds;          ///< lowest and highest corner of its box [m]
  std::optional<std::array<double, 2>> footprint;   ///< height field: extent along x and y [m]
  std::optional<std::array<long long, 2>> samples;  ///< height field: width x height
  std::optional<std::size_t> triangles;             ///< mesh
  std::vector<std::string> warnings;                ///< mesh: what the reader accepted but may surprise
  std::string normals;                              ///< mesh: the normals the proxy pushes along, in words
  Pose pose;                                        ///< where the shape's own frame is
  std::shared_ptr<Motion> motion;                   ///< moving_surface(): the poses that move it
  std::shared_ptr<Deformation> deformation;         ///< deforming_mesh(): the vertices that deform it
};

/// A pose argument: a Pose, or None and an optional origin (the older form: a translation alone).
Pose pose_of(const std::optional<Pose>& pose, const std::optional<V3>& origin) {
  if (pose && origin) throw py::value_error("give pose or origin, not both (origin is a pose's translation)");
  if (pose) return *pose;
  Pose p;
  if (origin) {
    if (!is_finite(glm3(*origin))) throw py::value_error("origin: must be finite [m]");
    p.translation = glm3(*origin);
  }
  return p;
}

/// A Pose from Python: rotation None, a 3 x 3 matrix or a unit quaternion (w, x, y, z); translation [m].
Pose make_pose(const py::object& rotation, const V3& translation) {
  if (!is_finite(glm3(translation))) throw py::value_error("Pose: translation must be finite [m]");
  if (rotation.is_none()) {
    Pose p;
    p.translation = glm3(translation);
    return p;
  }
  const py::array_t<double, py::array::c_style | py::array::forcecast> r =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(rotation);
  if (!r) throw py::type_error("Pose: rotation must be numbers (a 3 x 3 matrix or a quaternion w, x, y, z)");
  if (r.ndim() == 2 && r.shape(0) == 3 && r.shape(1) == 3) {
    std::array<std::array<double, 3>, 3> rows{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        rows[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = r.at(i, j);
    return Pose::from_rows(rows, glm3(translation));
  }
  if (r.ndim() == 1 && r.shape(0) == 4)
    return Pose::from_quaternion(r.at(0), r.at(1), r.at(2), r.at(3), glm3(translation));
  std::string shape = "(";
  for (py::ssize_t i = 0; i < r.ndim(); ++i)
    shape += (i ? ", " : "") + std::to_string(r.shape(i));
  throw py::value_error("Pose: rotation must be a 3 x 3 matrix or a quaternion (w, x, y, z), got shape " + shape +
                        (r.ndim() == 1 ? ",)" : ")"));
}

V3 v3(const glm::dvec3& v) {
  return V3{v.x, v.y, v.z};
}

std::pair<V3, V3> pair_of(const io::Bounds& b) {
  return {v3(b.lo), v3(b.hi)};
}

/// Refuses an array whose elements share memory (a broadcast, zero-stride array such as np.broadcast_to's, or an
/// overlapping as_strided view): its size says nothing of the memory a copy would take. Checked before anything
/// is allocated.
void check_own_memory(const py::array& a, const char* what) {
  py::ssize_t span = a.itemsize(), n = 1;
  for (py::ssize_t k = 0; k < a.ndim(); ++k) {
    if (a.shape(k) > 1 && a.strides(k) == 0)
      throw py::value_error(std::string(what) + ": a broadcast array (stride 0 along axis " + std::to_string(k) +
                            ") is refused: its " + std::to_string(a.size()) +
                            " elements share memory; pass np.ascontiguousarray(...) of what you mean");
    if (a.shape(k) > 0) span += (a.shape(k) - 1) * (a.strides(k) < 0 ? -a.strides(k) : a.strides(k));
    n *= a.shape(k);
  }
  if (n > 1 && span < n * a.itemsize())
    throw py::value_error(std::string(what) + ": its elements overlap in memory (a strided view over " +
                          std::to_string(span) + " bytes); pass np.ascontiguousarray(...) of what you mean");
}

/// The state of every probe of a trajectory evaluated on a surface contact, as numpy arrays.
struct ContactArrays {
  double* proxy = nullptr;            ///< N x 3 [m]
  double* normal = nullptr;           ///< N x 3
  double* uv = nullptr;               ///< N x 2
  double* depth = nullptr;            ///< N [m]
  double* contact_force = nullptr;    ///< N x 3, Fc alone [N]
  std::int64_t* primitive = nullptr;  ///< N, -1: none
  bool* touching = nullptr;           ///< N
  /// Optional: each tick's path (ProxyConstraint::last_path), its points one after another (x, y, z [m] each),
  /// where each tick's points end (a count of points), and whether memory ran out on the way.
  std::vector<double>* path = nullptr;
  std::vector<std::size_t>* path_ends = nullptr;
  bool* path_failed = nullptr;
};

/// A surface contact: F = Fc (the proxy on the shape) + the parts, which see |Fc|, the normal, uv, tangent
/// frame and primitive of the touched point.
template <Shape S>
using SurfaceContact = ContactField<ProxyConstraint<S>, FieldSum>;

/// A field made by surface_contact(): a Field that also tells where the proxy is (contacts()).
struct SurfaceField : Field {
  void (*trace)(AnyField&, const ProbeArrays&, const ContactArrays&) noexcept = nullptr;
};

/// Evaluates a contact field of type CF (a ContactField over a ProxyConstraint) and reports its contacts.
template <class CF>
void trace_as(AnyField& any, const ProbeArrays& a, const ContactArrays& c) noexcept {
  auto* field = any.target<CF>();
  if (!field) return;  // never: surface_contact() pairs the type and this function
  Probe probe;
  probe.period = a.period;
  const double *p = a.positions, *v = a.velocities;
  for (py::ssize_t i = 0; i < a.n; ++i) {
    probe.position = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    if (v) probe.velocity = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
    probe.time = a.start_time + static_cast<double>(i) * a.period;
    const glm::dvec3 f = field->force(probe);
    const Contact& k = field->last_contact();
    const glm::dvec3 x = field->constraint().proxy();
    for (int j = 0; j < 3; ++j) {
      a.forces[3 * i + j] = f[j];
      c.proxy[3 * i + j] = x[j];
      c.normal[3 * i + j] = k.normal[j];
      c.contact_force[3 * i + j] = k.force[j];
    }
    c.uv[2 * i] = k.surface_uv.x, c.uv[2 * i + 1] = k.surface_uv.y;
    c.depth[i] = k.depth;
    c.primitive[i] = k.primitive == no_primitive ? -1 : static_cast<std::int64_t>(k.primitive);
    c.touching[i] = k.touching;
    if (c.path && !*c.path_failed) {
      const ProxyPath& path = field->constraint().last_path();
      try {  // (not a servo tick: an offline run that grows its record)
        for (int q = 0; q < path.count; ++q)
          for (int j = 0; j < 3; ++j)
            c.path->push_back(path.points[static_cast<std::size_t>(q)][j]);
        c.path_ends->push_back(c.path->size() / 3);
      } catch (const std::bad_alloc&) {
        *c.path_failed = true;
      }
    }
  }
}

using Spacing = std::variant<double, std::array<double, 2>>;
std::array<double, 2> pair_of(const Spacing& s) {
  if (const double* d = std::get_if<double>(&s)) return {*d, *d};
  return std::get<std::array<double, 2>>(s);
}

std::string metres(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

HeightFieldConfig height_config(bool shade_normals, std::uint32_t max_nodes) {
  if (max_nodes == 0) throw py::value_error("max_nodes: must be > 0");
  return HeightFieldConfig{shade_normals, max_nodes};
}

/// A height field from a grid laid out as io::HeightGrid (row j = 0 at y = 0).
Surface surface_from_grid(const io::HeightGrid& grid, const HeightFieldConfig& config, const Pose& pose,
                          const std::string& what) {
  Surface s;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double h : grid.heights)
    lo = std::fmin(lo, h), hi = std::fmax(hi, h);
  {
    py::gil_scoped_release release;
    s.shape = std::make_shared<const AnyShape>(std::in_place_type<Posed<HeightFieldShape>>,
                                               HeightFieldShape(grid, config), pose);
  }
  const double ex = (grid.width - 1) * grid.spacing_x, ey = (grid.height - 1) * grid.spacing_y;
  s.kind = "height_field";
  s.description = what + " " + std::to_string(grid.width) + " x " + std::to_string(grid.height) + " samples, " +
                  metres(ex) + " x " + metres(ey) + " m";
  s.bounds = pair_of(io::placed_bounds({0.0, 0.0, lo}, {ex, ey, hi}, pose));
  s.pose = pose;
  s.footprint = std::array<double, 2>{ex, ey};
  s.samples = std::array<long long, 2>{grid.width, grid.height};
  return s;
}

Surface height_field(const py::array& heights, const Spacing& spacing, const std::optional<V3>& origin,
                     const std::optional<Pose>& pose, bool shade_normals, std::uint32_t max_nodes) {
  const Pose placed = pose_of(pose, origin);
  const auto [sx, sy] = pair_of(spacing);
  if (!(std::isfinite(sx) && std::isfinite(sy) && sx > 0.0 && sy > 0.0))
    throw py::value_error("spacing: must be finite and > 0 [m]");
  // checked before any conversion: a float32 array of 100 Mpx would take 800 MB as float64
  if (heights.ndim() != 2)
    throw py::value_error("heights: expected a 2-D array (rows along y, columns along x), got " +
                          std::to_string(heights.ndim()) + " dimensions");
  const py::ssize_t rows = heights.shape(0), cols = heights.shape(1);
  if (rows < 2 || cols < 2)
    throw py::value_error("heights: need at least 2 x 2 samples, got " + std::to_string(rows) + " x " +
                          std::to_string(cols));
  if (static_cast<std::size_t>(rows) > height_field_max_samples / static_cast<std::size_t>(cols))
    throw py::value_error("heights: " + std::to_string(rows) + " x " + std::to_string(cols) +
                          " samples is more than the limit of 100 Mpx");
  const py::dtype dt = heights.dtype();
  if (dt.kind() != 'f' && dt.kind() != 'i' && dt.kind() != 'u')
    throw py::type_error("heights: expected float64 or float32 heights [m] (or integers), got dtype " +
                         dt.attr("name").cast<std::string>());
  check_own_memory(heights, "heights");
  const Array a = Array::ensure(heights);
  if (!a) throw py::type_error("heights: cannot be read as float64");
  io::HeightGrid grid;
  grid.width = static_cast<int>(cols);
  grid.height = static_cast<int>(rows);
  grid.spacing_x = sx;
  grid.spacing_y = sy;
  grid.heights.assign(a.data(), a.data() + rows * cols);
  for (std::size_t k = 0; k < grid.heights.size(); ++k)
    if (!std::isfinite(grid.heights[k]))
      throw py::value_error("heights: the height at row " + std::to_string(k / std::size_t(cols)) + ", column " +
                            std::to_string(k % std::size_t(cols)) + " is not finite (NaN or infinite)");
  return surface_from_grid(grid, height_config(shade_normals, max_nodes), placed, "height field");
}

bool is_path(const py::object& o) {
  return py::isinstance<py::str>(o) || py::hasattr(o, "__fspath__");
}
std::string path_of(const py::object& o) {
  return py::str(py::module_::import("os").attr("fspath")(o));
}

Surface height_field_from_picture(const py::object& image, double pixel_size, double mm_per_level, double blur,
                                  bool dark_is_high, const std::string& gray, const std::string& channels,
                                  std::optional<double> levels, const std::optional<V3>& origin,
                                  const std::optional<Pose>& pose, bool shade_normals, std::uint32_t max_nodes) {
  const Pose placed = pose_of(pose, origin);
  io::PictureHeightConfig c;
  c.pixel_size = pixel_size;
  c.mm_per_level = mm_per_level;
  c.blur_sigma = blur;
  c.dark_is_high = dark_is_high;
  c.weights = gray_weights(gray);
  const HeightFieldConfig config = height_config(shade_normals, max_nodes);
  if (is_path(image)) {
    const std::string path = path_of(image);
    return surface_from_grid(io::load_height_picture(path, c), config, placed,
                             "relief of " + std::filesystem::path(path).filename().string());
  }
  return surface_from_grid(io::height_grid_from_gray(gray_from(image, c.weights, channels, levels), c), config, placed,
                           "relief of a picture");
}

Surface depth_map(const py::object& path, double pixel_size, double metres_per_unit, double blur,
                  const std::optional<V3>& origin, const std::optional<Pose>& pose, bool shade_normals,
                  std::uint32_t max_nodes) {
  const Pose placed = pose_of(pose, origin);
  if (!is_path(path)) throw py::type_error("depth_map: expected a path (16-bit PNG or TIFF, 32-bit float TIFF)");
  io::DepthMapConfig c;
  c.pixel_size = pixel_size;
  c.metres_per_unit = metres_per_unit;
  c.blur_sigma = blur;
  const std::string p = path_of(path);
  return surface_from_grid(io::load_depth_map(p, c), height_config(shade_normals, max_nodes), placed,
                           "depth map " + std::filesystem::path(p).filename().string());
}

/// A Surface from a mesh made as every tool makes it (io/mesh_shading.hpp: the same normals, the same refusal).
Surface surface_from_mesh(io::LoadedMesh& loaded, const std::string& name, const std::string& what, const Pose& pose,
                          bool shade_normals, std::uint32_t max_nodes, bool huge_pages) {
  Surface s;
  io::MeshShapeReport report;
  std::optional<MeshShape> shape;
  {
    py::gil_scoped_release release;
    shape.emplace(io::mesh_shape_from(loaded, name, shade_normals ? io::MeshShading::smooth : io::MeshShading::faceted,
                                      max_nodes, &report, huge_pages));
  }
  s.bounds = pair_of(io::placed_bounds(shape->mesh(), pose));
  s.shape = std::make_shared<const AnyShape>(std::in_place_type<Posed<MeshShape>>, std::move(*shape), pose);
  s.triangles = report.triangles;
  s.normals = report.normals;
  for (const io::MeshWarning& w : loaded.warnings)
    s.warnings.push_back(w.message);
  s.kind = "mesh";
  s.description = what + " (" + std::to_string(report.triangles) + " triangles)";
  s.pose = pose;
  return s;
}

Surface mesh_surface(const py::object& path, double scale, const std::optional<V3>& origin,
                     const std::optional<Pose>& pose, bool shade_normals, std::uint32_t max_nodes,
                     std::size_t max_triangles, bool huge_pages) {
  if (!is_path(path)) throw py::type_error("mesh_surface: expected a path (.stl, .obj, .gltf or .glb)");
  if (max_nodes == 0) throw py::value_error("max_nodes: must be > 0");
  const Pose placed = pose_of(pose, origin);
  const std::string p = path_of(path);
  io::MeshReadConfig c;
  c.scale = scale;
  c.max_triangles = max_triangles;
  io::LoadedMesh loaded;
  {
    py::gil_scoped_release release;
#if HAPTICFIELD_PYTHON_IO
    loaded = io::load_mesh(p, c);
#else
    std::string ext = std::filesystem::path(p).extension().string();
    for (char& ch : ext)
      ch = static_cast<char>(ch >= 'A' && ch <= 'Z' ? ch - 'A' + 'a' : ch);
    if (ext != ".stl")
      throw Error("cannot load '" + p + "': this build of the module reads .stl only (no tinygltf or tinyobjloader)");
    loaded = io::load_stl(p, c);
#endif
  }
  if (loaded.mesh.triangles.empty()) throw FileError("cannot load '" + p + "': the mesh has no triangles");
  return surface_from_mesh(loaded, p, "mesh " + std::filesystem::path(p).filename().string(), placed, shade_normals,
                           max_nodes, huge_pages);
}

/// An N x cols array of one kind ('f' real, 'i' integer) read as `T`, checked as described in
/// mesh_surface_from_arrays's docstring; the rows it has.
template <class T>
py::array_t<T, py::array::c_style | py::array::forcecast> rows_array(const py::array& a, py::ssize_t cols,
                                                                     const char* what, bool integer,
                                                                     std::size_t max_rows) {
  if (a.ndim() != 2 || a.shape(1) != cols) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i)
      shape += (i ? ", " : "") + std::to_string(a.shape(i));
    throw py::value_error(std::string(what) + ": expected an N x " + std::to_string(cols) + " array, got shape " +
                          shape + (a.ndim() == 1 ? ",)" : ")"));
  }
  const char kind = a.dtype().kind();
  if (integer ? (kind != 'i' && kind != 'u') : (kind != 'f' && kind != 'i' && kind != 'u'))
    throw py::value_error(std::string(what) + ": expected " + (integer ? "integer indices" : "real numbers") +
                          ", got dtype " + a.dtype().attr("name").cast<std::string>());
  if (static_cast<std::size_t>(a.shape(0)) > max_rows)
    throw py::value_error(std::string(what) + ": " + std::to_string(a.shape(0)) + " rows, more than the limit of " +
                          std::to_string(max_rows));
  check_own_memory(a, what);
  return py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
}

Surface mesh_surface_from_arrays(const py::array& vertices, const py::array& faces, const std::optional<py::array>& uvs,
                                 const std::optional<py::array>& normals, const std::optional<Pose>& pose,
                                 const std::optional<V3>& origin, bool shade_normals, std::uint32_t max_nodes,
                                 std::size_t max_triangles, bool huge_pages) {
  if (max_nodes == 0) throw py::value_error("max_nodes: must be > 0");
  if (max_triangles == 0 || max_triangles > io::default_max_mesh_triangles)
    throw py::value_error("max_triangles: must be in 1..." + std::to_string(io::default_max_mesh_triangles));
  const Pose placed = pose_of(pose, origin);
  const std::size_t max_vertices = 3 * max_triangles;
  const auto v = rows_array<double>(vertices, 3, "vertices", false, max_vertices);
  const auto f = rows_array<std::int64_t>(faces, 3, "faces", true, max_triangles);
  const py::ssize_t nv = v.shape(0), nf = f.shape(0);
  if (nf == 0) throw py::value_error("faces: no triangles (an M x 3 array with M >= 1)");
  std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>> t, n;
  if (uvs) {
    t = rows_array<double>(*uvs, 2, "uvs", false, max_vertices);
    if (t->shape(0) != nv) throw py::value_error("uvs: need one row per vertex (" + std::to_string(nv) + ")");
  }
  if (normals) {
    n = rows_array<double>(*normals, 3, "normals", false, max_vertices);
    if (n->shape(0) != nv) throw py::value_error("normals: need one row per vertex (" + std::to_string(nv) + ")");
  }
  io::LoadedMesh loaded;
  TriangleMesh& m = loaded.mesh;
  m.positions.resize(static_cast<std::size_t>(nv));
  const double* pv = v.data();
  for (py::ssize_t i = 0; i < nv; ++i) {
    m.positions[static_cast<std::size_t>(i)] = {pv[3 * i], pv[3 * i + 1], pv[3 * i + 2]};
    if (!is_finite(m.positions[static_cast<std::size_t>(i)]))
      throw py::value_error("vertices: row " + std::to_string(i) + " is not finite");
  }
  m.triangles.resize(static_cast<std::size_t>(nf));
  const std::int64_t* pf = f.data();
  for (py::ssize_t i = 0; i < nf; ++i)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t index = pf[3 * i + k];
      if (index < 0 || index >= nv)
        throw py::value_error("faces: row " + std::to_string(i) + " uses vertex " + std::to_string(index) + " of " +
                              std::to_string(nv) + " (indices run from 0 to " + std::to_string(nv - 1) + ")");
      m.triangles[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(index);
    }
  if (t) {
    m.uvs.resize(static_cast<std::size_t>(nv));
    const double* pt = t->data();
    for (py::ssize_t i = 0; i < nv; ++i) {
      m.uvs[static_cast<std::size_t>(i)] = {pt[2 * i], pt[2 * i + 1]};
      if (!std::isfinite(pt[2 * i]) || !std::isfinite(pt[2 * i + 1]))
        throw py::value_error("uvs: row " + std::to_string(i) + " is not finite");
    }
  }
  if (n) {
    m.normals.resize(static_cast<std::size_t>(nv));
    const double* pn = n->data();
    for (py::ssize_t i = 0; i < nv; ++i) {
      const glm::dvec3 x{pn[3 * i], pn[3 * i + 1], pn[3 * i + 2]};
      const double length = glm::length(x);
      if (!(length > 0.0) || !std::isfinite(length))
        throw py::value_error("normals: row " + std::to_string(i) + " is zero or not finite");
      m.normals[static_cast<std::size_t>(i)] = x / length;
    }
  }
  std::size_t degenerate = 0;
  for (const TriangleIndices& tri : m.triangles)
    if (io::detail::is_degenerate(m, tri)) ++degenerate;
  if (degenerate > 0 && degenerate < m.triangles.size())
    loaded.warnings.push_back({io::MeshWarningKind::degenerate_triangles,
                               std::to_string(degenerate) + " of " + std::to_string(m.triangles.size()) +
                                   " triangles have zero area (kept; the surface skips them)"});
  try {
    return surface_from_mesh(loaded, "the arrays", "mesh from arrays", placed, shade_normals, max_nodes, huge_pages);
  } catch (const FileError& e) {  // nothing to touch: the arrays are the caller's values, not a file
    throw py::value_error(
        std::string(e.what()).replace(0, std::string("cannot use 'the arrays'").size(), "vertices, faces"));
  }
}

/// The tool's radius [m] checked: in [0, proxy_max_radius].
void check_radius(double radius) {
  if (!(std::isfinite(radius) && radius >= 0.0 && radius <= proxy_max_radius))
    throw py::value_error("radius: the tool's radius must be in [0, " + metres(proxy_max_radius) +
                          "] m (0: a point), got " + metres(radius));
}

SurfaceField surface_contact(const Surface& surface, const std::vector<Field>& parts, double stiffness, double damping,
                             double static_friction, double dynamic_friction, double offset, double radius,
                             const std::optional<Material>& material, bool stick_first, std::int64_t tick_node_budget) {
  check_radius(radius);
  if (tick_node_budget < 0 || tick_node_budget > std::numeric_limits<std::uint32_t>::max())
    throw py::value_error("tick_node_budget: must be in [0, 4294967295] tree nodes, got " +
                          std::to_string(tick_node_budget));
  ProxyConfig config{stiffness, damping, static_friction, dynamic_friction, offset};
  config.radius = radius;
  config.stick_first = stick_first;
  config.tick_node_budget = static_cast<std::uint32_t>(tick_node_budget);
  FieldSum sum;
  std::string d = "surface(" + surface.description;
  std::vector<const Field*> shared;
  for (const Field& f : parts) {
    sum.parts.push_back({f.impl});
    d += " + " + f.description;
    shared.push_back(&f);
  }
  if (material) d += " with " + material->description;
  d += ")";
  // the proxy on the shape, or with a material the proxy's stiffness, damping and friction read at the touched uv
  const auto make = [&]<class S>(S shape) {
    SurfaceField out;
    if (material) {
      static_cast<Field&>(out) = make_field(
          material::material_surface(std::move(shape), config, material::MaterialMap(*material->map), std::move(sum)),
          d, shared);
      out.trace = &trace_as<material::MaterialSurface<S, FieldSum>>;
    } else {
      static_cast<Field&>(out) =
          make_field(contact(ProxyConstraint<S>(std::move(shape), config), std::move(sum)), d, shared);
      out.trace = &trace_as<SurfaceContact<S>>;
    }
    return out;
  };
  if (surface.deformation) return make(DeformingMesh(surface.deformation->feed()));
  return std::visit(
      [&]<class S>(const S& shape) {
        if (surface.motion) return make(Moving<S>(S(shape), surface.motion->feed()));
        return make(S(shape));
      },
      *surface.shape);
}

py::dict contacts(SurfaceField& self, const Array& positions, const std::optional<Array>& velocities, double period,
                  double start_time, bool paths) {
  if (!(std::isfinite(period) && period > 0.0)) throw py::value_error("contacts: period must be finite and > 0 [s]");
  const py::ssize_t n = rows_of(positions, 3, "positions");
  if (velocities && rows_of(*velocities, 3, "velocities") != n)
    throw py::value_error("velocities: must have as many rows as positions");
  auto force = matrix(n, 3), proxy = matrix(n, 3), normal = matrix(n, 3), contact_force = matrix(n, 3),
       uv = matrix(n, 2);
  py::array_t<double> depth(n);
  py::array_t<std::int64_t> primitive(n);
  py::array_t<bool> touching(n);
  ProbeArrays a;
  a.positions = positions.data();
  a.velocities = velocities ? velocities->data() : nullptr;
  a.forces = force.mutable_data();
  a.n = n;
  a.period = period;
  a.start_time = start_time;
  ContactArrays c{proxy.mutable_data(),         normal.mutable_data(),    uv.mutable_data(),      depth.mutable_data(),
                  contact_force.mutable_data(), primitive.mutable_data(), touching.mutable_data()};
  // each tick's path: its points one after another, cut into one array a tick below
  std::vector<double> path_points;
  std::vector<std::size_t> path_ends;
  bool path_failed = false;
  if (paths) {
    path_points.reserve(static_cast<std::size_t>(n) * 3 * 3);  // three points a tick; more grow it
    path_ends.reserve(static_cast<std::size_t>(n));
    c.path = &path_points;
    c.path_ends = &path_ends;
    c.path_failed = &path_failed;
  }
  std::shared_ptr<AnyField> field = self.impl;
  const FieldUse use(self);
  {
    py::gil_scoped_release release;
    self.trace(*field, a, c);
  }
  py::dict out;
  out["force"] = force;
  out["contact_force"] = contact_force;
  out["proxy"] = proxy;
  out["normal"] = normal;
  out["uv"] = uv;
  out["depth"] = depth;
  out["primitive"] = primitive;
  out["touching"] = touching;
  if (paths) {
    if (path_failed) throw std::bad_alloc();  // pybind11 raises MemoryError
    py::list list;
    std::size_t begin = 0;
    for (const std::size_t end : path_ends) {
      auto tick = matrix(static_cast<py::ssize_t>(end - begin), 3);
      std::copy(path_points.begin() + static_cast<std::ptrdiff_t>(3 * begin),
                path_points.begin() + static_cast<std::ptrdiff_t>(3 * end), tick.mutable_data());
      list.append(tick);
      begin = end;
    }
    out["path"] = list;
  }
  return out;
}

using Pair = std::variant<double, std::array<double, 2>>;

Field on_surface_of(const Field& field, const Pair& scale, const Pair& offset) {
  const auto s = pair_of(scale), o = pair_of(offset);
  const UvMapping mapping{glm::dvec2{s[0], s[1]}, glm::dvec2{o[0], o[1]}};
  if (!is_finite(mapping.scale) || !is_finite(mapping.offset))
    throw py::value_error("on_surface: scale [m per uv unit] and offset [m] must be finite");
  return make_field(OnSurface<SharedField>(SharedField{field.impl}, mapping), "on_surface(" + field.description + ")",
                    {&field});
}

SurfaceField picture_relief_of(const py::object& image, double mm_per_level, double width_m, double blur,
                               bool dark_is_high, double stiffness, double damping, double static_friction,
                               double dynamic_friction, double texture_gain, const std::string& mask,
                               std::optional<int> size, const std::string& border, double sigma,
                               const std::string& gray, const std::string& channels, std::optional<double> levels,
                               double radius) {
  check_radius(radius);
  PictureReliefConfig c;
  c.mm_per_level = mm_per_level;
  c.width_m = width_m;
  c.blur_sigma = blur;
  c.dark_is_high = dark_is_high;
  c.stiffness = stiffness;
  c.damping = damping;
  c.static_friction = static_friction;
  c.dynamic_friction = dynamic_friction;
  c.radius = radius;
  c.texture_gain = texture_gain;
  c.tangible = tangible_options(mask, size, border, sigma);
  c.weights = gray_weights(gray);
  std::optional<PictureRelief> relief;
  std::string name = "a picture";
  if (is_path(image)) {
    const std::string path = path_of(image);
    name = std::filesystem::path(path).filename().string();
    py::gil_scoped_release release;
    relief.emplace(picture_relief(path, c));
  } else {
    const GrayImage g = gray_from(image, c.weights, channels, levels);
    py::gil_scoped_release release;
    relief.emplace(picture_relief(g, c));
  }
  SurfaceField out;
  static_cast<Field&>(out) = make_field(std::move(*relief), "picture relief of " + name);
  out.trace = &trace_as<PictureRelief>;
  return out;
}

}  // namespace

namespace {

/// moving_surface()'s result: a Surface whose pose set_pose() changes while loops run.
struct MovingSurface : Surface {};
/// deforming_mesh()'s result: a mesh whose vertices set_vertices() moves while loops run.
struct DeformingSurface : Surface {};

MovingPose moving_pose(const std::optional<Pose>& pose, const V3& velocity, const V3& angular_velocity, double time) {
  MovingPose p;
  p.pose = pose.value_or(Pose{});
  p.linear_velocity = glm3(velocity);
  p.angular_velocity = glm3(angular_velocity);
  p.time = time;
  p.validate();  // std::invalid_argument: a ValueError
  return p;
}

MovingSurface moving_surface(const Surface& surface, const std::optional<Pose>& pose, const V3& velocity,
                             const V3& angular_velocity, double time) {
  if (surface.motion || surface.deformation)
    throw py::value_error("moving_surface: the surface already moves or deforms");
  MovingSurface out;
  static_cast<Surface&>(out) = surface;
  out.motion = std::make_shared<Motion>();
  out.motion->pose = moving_pose(pose, velocity, angular_velocity, time);
  out.description = "moving " + surface.description;
  out.bounds.reset();  // it moves
  return out;
}

/// N x 3 rows of real numbers, one per vertex of the mesh, all finite.
std::vector<glm::dvec3> vertex_rows(const py::array& a, std::size_t count, const char* what) {
  const auto v = rows_array<double>(a, 3, what, false, 3 * io::default_max_mesh_triangles);
  if (static_cast<std::size_t>(v.shape(0)) != count)
    throw py::value_error(std::string(what) + ": need one row per vertex (" + std::to_string(count) + "), got " +
                          std::to_string(v.shape(0)));
  std::vector<glm::dvec3> out(count);
  const double* p = v.data();
  for (std::size_t i = 0; i < count; ++i) {
    out[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    if (!is_finite(out[i])) throw py::value_error(std::string(what) + ": row " + std::to_string(i) + " is not finite");
  }
  return out;
}

DeformingSurface deforming_mesh(const py::array& vertices, const py::array& faces, const std::optional<py::array>& uvs,
                                const std::optional<py::array>& normals, bool shade_normals, std::uint32_t max_nodes,
                                bool huge_pages) {
  const Surface made = mesh_surface_from_arrays(vertices, faces, uvs, normals, std::nullopt, std::nullopt,
                                                shade_normals, max_nodes, io::default_max_mesh_triangles, huge_pages);
  DeformingSurface out;
  static_cast<Surface&>(out) = made;
  auto d = std::make_shared<Deformation>();
  d->mesh = std::get<Posed<MeshShape>>(*made.shape).shape().mesh();
  d->config = MeshShapeConfig{shade_normals, max_nodes, huge_pages};
  d->normals_from_faces = shade_normals && !normals;
  out.deformation = std::move(d);
  out.kind = "mesh";
  out.description = "deforming " + made.description;
  out.bounds.reset();  // it deforms
  return out;
}

void set_vertices(DeformingSurface& self, const py::array& vertices, const std::optional<py::array>& normals) {
  Deformation& d = *self.deformation;
  const std::size_t count = d.mesh.positions.size();
  std::vector<glm::dvec3> positions = vertex_rows(vertices, count, "vertices");
  std::vector<glm::dvec3> shading;
  if (normals && d.mesh.normals.empty())
    throw py::value_error(
        "normals: the mesh has no vertex normals to replace (built with shade_normals=False and none)");
  if (normals) {
    shading = vertex_rows(*normals, count, "normals");
    for (std::size_t i = 0; i < count; ++i) {
      const double length = glm::length(shading[i]);
      if (!(length > 0.0)) throw py::value_error("normals: row " + std::to_string(i) + " is zero");
      shading[i] /= length;
    }
  }
  py::gil_scoped_release release;
  const std::lock_guard<std::mutex> lock(d.mutex);
  if (!normals && d.normals_from_faces) {  // as a mesh built on these vertices would have them
    TriangleMesh moved;
    moved.positions = positions;
    moved.triangles = d.mesh.triangles;
    shading = with_vertex_normals(std::move(moved)).normals;
  }
  std::erase_if(d.feeds, [](const std::weak_ptr<DeformingMeshFeed>& f) { return f.expired(); });
  for (const auto& weak : d.feeds)
    if (const auto f = weak.lock()) f->publish(positions, shading);  // refits the feed's own tree
  d.mesh.positions = std::move(positions);
  if (!shading.empty()) d.mesh.normals = std::move(shading);
  ++d.frames;
}

}  // namespace

void bind_surface(py::module_& m) {
  py::class_<Pose>(m, "Pose",
                   "Where a shape's own frame goes: world = rotation @ local + translation. Every shape constructor "
                   "takes pose= (origin= is a pose without rotation).")
      .def(py::init(&make_pose), py::arg("rotation") = py::none(), py::arg("translation") = V3{0.0, 0.0, 0.0},
           "rotation: None (none), a 3 x 3 rotation matrix (its columns are the shape's x, y, z axes in the world; "
           "orthonormal with det +1 within 1e-6, then made exactly so) or a unit quaternion (w, x, y, z), scalar "
           "first (scipy's Rotation.as_quat() is scalar last: use as_matrix()); translation (x, y, z) [m]. "
           "ValueError for a reflection, a scale, a non-unit quaternion or anything not finite.")
      .def_static(
          "about",
          [](const V3& axis, double degrees, const V3& translation) {
            return Pose::from_axis_angle(glm3(axis), degrees * std::numbers::pi / 180.0, glm3(translation));
          },
          py::arg("axis"), py::arg("degrees"), py::arg("translation") = V3{0.0, 0.0, 0.0},
          "A turn of degrees about axis (right-handed, through the shape's own origin), then translation [m].")
      .def_property_readonly(
          "rotation",
          [](const Pose& p) {
            auto r = matrix(3, 3);
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j)
                r.mutable_at(i, j) = p.rotation[j][i];
            return r;
          },
          "The 3 x 3 rotation matrix (a new array).")
      .def_property_readonly(
          "translation", [](const Pose& p) { return v3(p.translation); }, "(x, y, z) [m].")
      .def("__repr__", [](const Pose& p) {
        char b[300];
        std::snprintf(b, sizeof b,
                      "Pose(rotation=[[%.6g, %.6g, %.6g], [%.6g, %.6g, %.6g], [%.6g, %.6g, %.6g]], "
                      "translation=(%.6g, %.6g, %.6g))",
                      p.rotation[0][0], p.rotation[1][0], p.rotation[2][0], p.rotation[0][1], p.rotation[1][1],
                      p.rotation[2][1], p.rotation[0][2], p.rotation[1][2], p.rotation[2][2], p.translation.x,
                      p.translation.y, p.translation.z);
        return std::string(b);
      });

  py::class_<Surface>(
      m, "Surface",
      "A shape to touch (a height field, a mesh, a plane or a sphere), built once. surface_contact() makes it a "
      "field felt through a proxy; one surface may serve several fields (each proxy keeps its own state).")
      .def_property_readonly(
          "kind", [](const Surface& s) { return s.kind; }, "height_field, mesh, plane or sphere.")
      .def_property_readonly("description", [](const Surface& s) { return s.description; })
      .def_property_readonly(
          "bounds", [](const Surface& s) { return s.bounds; },
          "((x, y, z) lowest, (x, y, z) highest) corners of its box [m]; None for a plane.")
      .def_property_readonly(
          "footprint", [](const Surface& s) { return s.footprint; },
          "Height field: its extent ((width - 1) spacing_x, (height - 1) spacing_y) [m], from "
          "its origin; the scale that lays a field 1:1 on it by uv (uv runs 0..1 over it). None "
          "otherwise.")
      .def_property_readonly(
          "samples", [](const Surface& s) { return s.samples; },
          "Height field: (width, height) samples. None otherwise.")
      .def_property_readonly(
          "triangles", [](const Surface& s) { return s.triangles; }, "Mesh: its number of triangles. None otherwise.")
      .def_property_readonly(
          "warnings", [](const Surface& s) { return s.warnings; },
          "Mesh: what the reader accepted but may surprise (no normals, degenerate triangles...), saying what the "
          "surface does about it.")
      .def_property_readonly(
          "normals", [](const Surface& s) { return s.normals.empty() ? py::object(py::none()) : py::str(s.normals); },
          "Mesh: the normals the proxy pushes along, in words (force shading from the file's vertex normals, "
          "from the faces, or face normals). None otherwise.")
      .def_property_readonly(
          "pose", [](const Surface& s) { return s.pose; }, "Where the shape's own frame is (a Pose).")
      .def("__repr__", [](const Surface& s) { return "<hapticfield.Surface " + s.description + ">"; });

  py::class_<MovingSurface, Surface>(
      m, "MovingSurface",
      "A surface that moves while loops run (moving_surface()): each field made on it with surface_contact() "
      "takes the newest pose at every tick without a lock, the proxy carried with it (a shape moving into a still "
      "probe pushes it out, one moving away leaves it free) and the damping on the velocity relative to the "
      "touched surface's.")
      .def(
          "set_pose",
          [](MovingSurface& self, const std::optional<Pose>& pose, const V3& velocity, const V3& angular_velocity,
             double time) {
            const MovingPose next = moving_pose(pose, velocity, angular_velocity, time);
            py::gil_scoped_release release;
            self.motion->publish(next);
          },
          py::arg("pose") = py::none(), py::arg("velocity") = V3{0.0, 0.0, 0.0},
          py::arg("angular_velocity") = V3{0.0, 0.0, 0.0}, py::arg("time") = 0.0,
          "Where the surface's frame is (a Pose; None: where it was built) at time [s] on the loop's clock "
          "(Probe time: run_servo's from 0, forces()'s start_time + i period), moving at velocity [m/s] (of the "
          "frame's origin) and angular_velocity [rad/s] (about it), both in the device frame: each field's next "
          "tick takes it, extrapolated by the velocities from time for at most 0.1 s. Any thread; ValueError for "
          "an invalid pose or a value not finite.")
      .def_property_readonly(
          "moving_pose",
          [](MovingSurface& self) {
            const std::lock_guard<std::mutex> lock(self.motion->mutex);
            const MovingPose& p = self.motion->pose;
            return py::make_tuple(p.pose, v3(p.linear_velocity), v3(p.angular_velocity), p.time);
          },
          "The newest (pose, velocity, angular_velocity, time) set.");

  py::class_<DeformingSurface, Surface>(
      m, "DeformingSurface",
      "A triangle mesh whose vertices move while loops run (deforming_mesh()): the same triangles, new positions "
      "each set_vertices(); each field made on it has its own copy of the tree, refitted (not rebuilt) and swapped "
      "in without a lock at its next tick.")
      .def("set_vertices", &set_vertices, py::arg("vertices"), py::arg("normals") = py::none(),
           "New positions N x 3 [m] (one per vertex, finite) and optionally vertex normals N x 3; without them a "
           "mesh built with shade_normals and no normals gets new normals from its faces (as a mesh rebuilt on "
           "these vertices), otherwise keeps its normals. Refits every field's tree on the calling thread (the GIL "
           "released); ValueError for a wrong shape, a value not finite, or normals for a mesh without them.")
      .def_property_readonly(
          "frames",
          [](DeformingSurface& self) {
            const std::lock_guard<std::mutex> lock(self.deformation->mutex);
            return self.deformation->frames;
          },
          "set_vertices() calls so far.");

  m.def("moving_surface", &moving_surface, py::arg("surface"), py::arg("pose") = py::none(),
        py::arg("velocity") = V3{0.0, 0.0, 0.0}, py::arg("angular_velocity") = V3{0.0, 0.0, 0.0}, py::arg("time") = 0.0,
        "A MovingSurface: surface (placed by its own pose within the moving frame) moved by pose (a Pose; None: "
        "the identity) at velocity [m/s] and angular_velocity [rad/s] from time [s] on the loop's clock; "
        "set_pose() moves it while loops run.");
  m.def("deforming_mesh", &deforming_mesh, py::arg("vertices"), py::arg("faces"), py::arg("uvs") = py::none(),
        py::arg("normals") = py::none(), py::arg("shade_normals") = true, py::arg("max_nodes") = bvh_default_max_nodes,
        py::arg("huge_pages") = true,
        "A DeformingSurface: a triangle mesh from arrays as mesh_surface_from_arrays (vertices N x 3 [m] in the "
        "device frame, faces M x 3, optional uvs and normals), whose vertices set_vertices() moves while loops "
        "run. A deformation is not rigid: a touching proxy is put back in front of the face it touched; a "
        "surface that passes through the HIP within one tick leaves it inside, felt as nothing until it comes "
        "out. huge_pages as mesh_surface.");

  py::class_<SurfaceField, Field>(
      m, "SurfaceField",
      "A surface felt through a proxy (surface_contact()): a Field (forces, force, reset, run_servo, sums) that "
      "also tells, with contacts(), where the proxy is at each probe.")
      .def("contacts", &contacts, py::arg("positions"), py::arg("velocities") = py::none(),
           py::arg("period") = servo_period, py::arg("start_time") = 0.0, py::arg("paths") = false,
           "Evaluates the field at N probes in order as consecutive ticks (like forces()) and returns a dict of "
           "arrays: force N x 3 [N] (Fc + parts), contact_force N x 3 [N] (Fc alone), proxy N x 3 [m], normal "
           "N x 3 (unit, toward the user; zero when not touching), uv N x 2, depth N [m], primitive N (triangle "
           "or grid cell j (width - 1) + i; -1: none) and touching N (bool). paths=True adds path: a list of N "
           "arrays, each K x 3 [m], the way the proxy went in that tick (where it started, then the end of each "
           "straight piece, the last row where it stays; every piece swept against the shape), so a move that "
           "looks like a jump can be checked piece by piece. The GIL is released.");

  m.def("height_field", &height_field, py::arg("heights"), py::arg("spacing") = 1e-4, py::arg("origin") = py::none(),
        py::arg("pose") = py::none(), py::arg("shade_normals") = true, py::arg("max_nodes") = bvh_default_max_nodes,
        "A height field z = h(x, y) [m] from a 2-D numpy array (float64 or float32 [m]): heights[j, i] is the "
        "height at x = i spacing_x, y = j spacing_y (np.meshgrid's 'xy' layout), spacing [m] one number or "
        "(spacing_x, spacing_y). Bilinear cells, solid below, felt from above (+z); covers [0, (W - 1) sx] x "
        "[0, (H - 1) sy] placed by pose (a Pose) or moved by origin (x, y, z) [m], and nothing beyond. At least "
        "2 x 2 and at most 100 M samples (800 MB as float64, and about as much again for its tree), all finite "
        "(ValueError otherwise). A broadcast array (np.broadcast_to, zero strides) or one whose elements overlap "
        "in memory is refused before anything is allocated (its size says nothing of the memory a copy takes). "
        "shade_normals: blend the corners' normals (force shading); max_nodes: the budget of one "
        "query.");
  m.def(
      "height_field_from_picture", &height_field_from_picture, py::arg("image"), py::arg("pixel_size") = 1e-4,
      py::arg("mm_per_level") = 0.01, py::arg("blur") = 0.0, py::arg("dark_is_high") = false, py::arg("gray") = "paper",
      py::arg("channels") = "rgb", py::arg("levels") = py::none(), py::arg("origin") = py::none(),
      py::arg("pose") = py::none(), py::arg("shade_normals") = true, py::arg("max_nodes") = bvh_default_max_nodes,
      (std::string(
           "A relief from a picture (see below): height = gray level x "
           "mm_per_level [mm] (dark_is_high: 255 - level), after a Gaussian blur of blur [px]; pixel_size [m] between "
           "pixel centres; origin [m]: where its bottom-left corner (level 0) goes (or pose: a Pose). The picture's "
           "top row is at the "
           "largest y (x right, y up), so it reads as it is seen. "
           "A missing or undecodable file raises FileError (an OSError).\n\n") +
       picture_argument_doc)
          .c_str());
  m.def("depth_map", &depth_map, py::arg("path"), py::arg("pixel_size") = 1e-4, py::arg("metres_per_unit") = 1e-6,
        py::arg("blur") = 0.0, py::arg("origin") = py::none(), py::arg("pose") = py::none(),
        py::arg("shade_normals") = true, py::arg("max_nodes") = bvh_default_max_nodes,
        "A height field from a depth map: a one-channel 16-bit PNG or TIFF, or a 32-bit float TIFF; height = value "
        "x metres_per_unit [m] (16-bit in um: 1e-6; float in m: 1.0); pixel_size [m]; blur [px]; origin [m] or pose "
        "as for height_field. OpenEXR, 8-bit "
        "and colour files, NaN values and missing files raise FileError naming the file.");
  m.def("mesh_surface", &mesh_surface, py::arg("path"), py::arg("scale") = 1.0, py::arg("origin") = py::none(),
        py::arg("pose") = py::none(), py::arg("shade_normals") = true, py::arg("max_nodes") = bvh_default_max_nodes,
        py::arg("max_triangles") = io::default_max_mesh_triangles, py::arg("huge_pages") = true,
        "A triangle mesh from a file (.stl, .obj, .gltf, .glb by extension); scale: the file's unit in metres "
        "(0.001 for millimetres; glTF is in metres), then placed by pose (a Pose) or moved by origin [m]. "
        "shade_normals (default, as in feel_shape, servo_demo and the viewer): force shading with the file's vertex "
        "normals, or normals computed from the faces where it has none; False: face normals (flat facets). Each "
        "triangle is felt from the side its normal points to. A mesh with no triangle of any area raises FileError. A "
        "missing, malformed or oversized "
        "file raises FileError naming it; Surface.warnings lists what was accepted but may surprise. huge_pages "
        "(default): the mesh's tree and arrays on 2 MB pages where the kernel allows (a hand's first pass over a part "
        "of a large mesh is faster); False: the system's own pages. The forces are the same either way.");
  m.def("mesh_surface_from_arrays", &mesh_surface_from_arrays, py::arg("vertices"), py::arg("faces"),
        py::arg("uvs") = py::none(), py::arg("normals") = py::none(), py::arg("pose") = py::none(),
        py::arg("origin") = py::none(), py::arg("shade_normals") = true, py::arg("max_nodes") = bvh_default_max_nodes,
        py::arg("max_triangles") = io::default_max_mesh_triangles, py::arg("huge_pages") = true,
        "A triangle mesh from numpy arrays: vertices N x 3 [m] (real), faces M x 3 vertex indices from 0 (integer "
        "dtype; each triangle felt from the side its counter-clockwise winding faces), optional uvs N x 2 and "
        "normals N x 3 (per vertex; normalised). Placed by pose (a Pose) or origin [m]. shade_normals as "
        "mesh_surface: the given normals, else normals from the faces; False: face normals. At most max_triangles "
        "faces (default and limit 20 M) and 3 x max_triangles vertices. ValueError naming the array and row for a "
        "wrong shape or dtype, an index out of range, a value not finite, a zero normal, no face, or faces that all "
        "have zero area; a broadcast (zero-stride) or overlapping array is refused before anything is allocated. "
        "huge_pages as mesh_surface.");
  m.def(
      "plane_surface",
      [](const V3& point, const V3& normal, double size, const std::optional<Pose>& pose) {
        Surface s;
        s.pose = pose.value_or(Pose{});
        s.shape =
            std::make_shared<const AnyShape>(std::in_place_type<Posed<PlaneShape>>,
                                             PlaneShape(PlaneShapeConfig{glm3(point), glm3(normal), size}), s.pose);
        s.kind = "plane";
        s.description = "plane";
        return s;
      },
      py::arg("point") = V3{0.0, 0.0, 0.0}, py::arg("normal") = V3{0.0, 0.0, 1.0}, py::arg("size") = 0.01,
      py::arg("pose") = py::none(),
      "The solid half-space behind a plane through point [m] with unit normal (toward the user), both in the "
      "frame that pose (a Pose; default none) places; uv are metres along the plane; size [m]: the length its "
      "tolerances scale with.");
  m.def(
      "sphere_surface",
      [](const V3& centre, double radius, const std::optional<Pose>& pose) {
        Surface s;
        s.pose = pose.value_or(Pose{});
        s.shape = std::make_shared<const AnyShape>(std::in_place_type<Posed<SphereShape>>,
                                                   SphereShape(SphereShapeConfig{glm3(centre), radius}), s.pose);
        s.kind = "sphere";
        s.description = "sphere r " + metres(radius) + " m";
        const glm::dvec3 c = s.pose.point_to_world(glm3(centre));
        s.bounds = std::pair<V3, V3>{v3(c - radius), v3(c + radius)};
        return s;
      },
      py::arg("centre") = V3{0.0, 0.0, 0.0}, py::arg("radius") = 0.02, py::arg("pose") = py::none(),
      "A solid ball: centre [m] (in the frame that pose places; default none), radius [m]. uv: u = longitude / "
      "2 pi + 1/2, v = latitude / pi + 1/2, about the ball's own z axis (turned by pose).");
  m.def("surface_contact", &surface_contact, py::arg("surface"), py::arg("parts") = std::vector<Field>{},
        py::arg("stiffness") = 1500.0, py::arg("damping") = 0.0, py::arg("static_friction") = 0.0,
        py::arg("dynamic_friction") = 0.0, py::arg("offset") = 1e-6, py::arg("radius") = 0.0,
        py::arg("material") = py::none(), py::arg("stick_first") = true,
        py::arg("tick_node_budget") = static_cast<std::int64_t>(proxy_default_tick_node_budget),
        "F = Fc + parts on a surface, felt through a proxy (god-object, Zilles & Salisbury 1995): Fc = max(0, k d "
        "- b v.n) n + friction, stiffness k [N/m], damping b [N s/m] on the normal velocity, the friction cone "
        "static_friction >= dynamic_friction >= 0; offset: the proxy's lift relative to a primitive's size. "
        "radius [m], in [0, 0.05]: the tool's radius; 0 (default) a point, > 0 a ball centred on the HIP, swept "
        "against the shape: it rests radius above a face (proxy = the ball's centre, d = radius - the HIP's "
        "height) and does not enter a crack narrower than 2 radius. Every surface takes a ball (a height field's "
        "cells are two flat triangles each for it). While "
        "touching, the parts see |Fc| [N], the normal, and the touched point's uv and tangent frame: lay a field "
        "on the surface with on_surface(). material (a Material: material(), load_haptic_material()): the stiffness, "
        "damping and friction read at the touched uv every tick instead of the numbers, the parts scaled by its "
        "texture gain there. stick_first (default True): with friction, the friction cone is tested first on last "
        "tick's planes, so a stuck proxy makes no swept query (False: the full tick, the frictionless proxy found "
        "first; the two agree on a flat face and differ a little near the cone's edge on a curved one). "
        "tick_node_budget: the most tree nodes all of one tick's queries may visit together; past it the proxy "
        "stays where it has got to that tick (0: it never moves, so it never touches). Returns a SurfaceField "
        "(contacts() tells where the proxy is).");
  m.def(
      "picture_relief", &picture_relief_of, py::arg("image"), py::arg("mm_per_level") = 0.01, py::arg("width_m") = 0.1,
      py::arg("blur") = 0.0, py::arg("dark_is_high") = false, py::arg("stiffness") = 1500.0, py::arg("damping") = 0.0,
      py::arg("static_friction") = 0.0, py::arg("dynamic_friction") = 0.0, py::arg("texture_gain") = 1.0,
      py::arg("mask") = "prewitt", py::arg("size") = py::none(), py::arg("border") = "suspend", py::arg("sigma") = 0.0,
      py::arg("gray") = "paper", py::arg("channels") = "rgb", py::arg("levels") = py::none(), py::arg("radius") = 0.0,
      (std::string(
           "A picture felt as a relief in one line (see below): its gray "
           "levels are heights (level x mm_per_level [mm], dark_is_high: 255 - level; blur [px] on the heights only) "
           "under the proxy (stiffness [N/m], damping [N s/m], static/dynamic friction), and its tangible-image "
           "forces (texture_gain [N] at a black/white edge; 0: the relief alone; mask, size, border, sigma as "
           "tangible_field) are laid on the relief in its tangent plane. The picture spans width_m [m] from the first "
           "to the last pixel centre, its bottom-left pixel at the origin, x right, y up the picture, z toward the "
           "user. radius: the tool's radius [m] in [0, 0.05] (0: a point; > 0 a ball, resting radius above the relief "
           "whose cells are two flat triangles each for it). Returns a SurfaceField.\n\n") +
       picture_argument_doc)
          .c_str());
  m.def("on_surface", &on_surface_of, py::arg("field"), py::arg("scale") = 1.0, py::arg("offset") = 0.0,
        "A field laid on the touched surface by uv (a part of surface_contact()): evaluated at the flat position "
        "offset + scale * uv [m] (scale [m per uv unit] and offset [m], each one number or a pair), with the "
        "velocity in the tangent frame; its force comes back along the surface's tangent, bitangent and normal. "
        "A tangible image, a texture, friction or a normals field so pushes along a curved surface. No force "
        "without a tangent frame. The field is shared, not copied.");
}

}  // namespace hapticfield::python
