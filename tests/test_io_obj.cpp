// Tests of the OBJ reader (io/obj.hpp, tinyobjloader): the hand-written cube
// (quads, and triangles with per-corner uvs and normals) against its closed
// form, vertex splitting where position/uv/normal combinations differ,
// materials, hostile files, and the real meshes of ../shared/data/meshes
// against the counts and bounds their README states (skipped when absent).
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "hapticfield/io/obj.hpp"
#include "io_test_util.hpp"

using namespace hapticfield;
using namespace hapticfield::io;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using io_test::expect_file_error;

namespace {

/// The cube of edge a as 8 positions and 6 quads (f v v v v).
std::string obj_cube_quads(double a) {
  std::string s = "# cube\no cube\n";
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 p = io_test::cube_corner(k, a);
    s += "v " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
  }
  for (const auto& q : io_test::cube_quads)
    s += "f " + std::to_string(q[0] + 1) + " " + std::to_string(q[1] + 1) + " " + std::to_string(q[2] + 1) + " " +
         std::to_string(q[3] + 1) + "\n";
  return s;
}

/// The cube with a uv square per face and a normal per face:
/// f v/vt/vn, so every corner of every face is its own vertex (24).
std::string obj_cube_full(double a) {
  std::string s = obj_cube_quads(a);
  s = s.substr(0, s.find("f "));
  s += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  for (const auto& n : io_test::cube_normals)
    s += "vn " + std::to_string(n.x) + " " + std::to_string(n.y) + " " + std::to_string(n.z) + "\n";
  for (std::size_t f = 0; f < 6; ++f) {
    const auto& q = io_test::cube_quads[f];
    for (const auto& [c0, c1, c2] : {std::array{0, 1, 2}, std::array{0, 2, 3}}) {
      s += "f";
      for (const int c : {c0, c1, c2})
        s.append(1, ' ')
            .append(std::to_string(q[static_cast<std::size_t>(c)] + 1))
            .append(1, '/')
            .append(std::to_string(c + 1))
            .append(1, '/')
            .append(std::to_string(f + 1));
      s += "\n";
    }
  }
  return s;
}

void check_cube_shape(const TriangleMesh& m, double a) {
  CHECK(m.triangle_count() == 12);
  CHECK_THAT(io_test::total_area(m), WithinRel(6.0 * a * a, 1e-9));
  CHECK_THAT(io_test::signed_volume(m), WithinRel(a * a * a, 1e-9));
  const auto b = io_test::bounds(m);
  CHECK_THAT(glm::length(b.lo), WithinAbs(0.0, 1e-12));
  CHECK_THAT(b.hi.x, WithinRel(a, 1e-9));
  CHECK_THAT(b.hi.y, WithinRel(a, 1e-9));
  CHECK_THAT(b.hi.z, WithinRel(a, 1e-9));
  CHECK(io_test::welded_edges(m).boundary == 0);
  CHECK(io_test::welded_edges(m).same_direction == 0);
}

}  // namespace

TEST_CASE("OBJ: the cube of quads gives the closed-form cube", "[io][obj]") {
  const auto dir = io_test::temp_dir("obj_cube");
  MeshReadConfig config;
  config.scale = 1e-3;  // written in mm
  const LoadedMesh m = load_obj(io_test::write(dir / "cube.obj", obj_cube_quads(40.0)), config);
  check_cube_shape(m.mesh, 0.04);
  CHECK(m.mesh.vertex_count() == 8);
  CHECK_FALSE(m.mesh.has_uvs());
  CHECK_FALSE(m.mesh.has_normals());
  CHECK(m.has_warning(MeshWarningKind::no_normals));
  CHECK(m.mesh.materials.empty());
}

TEST_CASE("OBJ: per-corner uvs and normals split the vertices", "[io][obj]") {
  const LoadedMesh m = parse_obj(obj_cube_full(1.0), "full.obj");
  check_cube_shape(m.mesh, 1.0);
  REQUIRE(m.mesh.has_uvs());
  REQUIRE(m.mesh.has_normals());
  CHECK(m.mesh.vertex_count() == 24);  // 6 faces x 4 corners: no two share (v, vt, vn)
  CHECK(io_test::distinct_positions(m.mesh) == 8);
  CHECK(m.warnings.empty());
  // each triangle's vertex normals are its face's outward normal
  for (const auto& t : m.mesh.triangles) {
    const glm::dvec3 face = glm::normalize(
        glm::cross(m.mesh.positions[t[1]] - m.mesh.positions[t[0]], m.mesh.positions[t[2]] - m.mesh.positions[t[0]]));
    for (const auto k : t)
      CHECK_THAT(glm::dot(m.mesh.normals[k], face), WithinAbs(1.0, 1e-12));
  }
  // uvs span the unit square on every face
  for (const auto& uv : m.mesh.uvs) {
    CHECK((uv.x == 0.0 || uv.x == 1.0));
    CHECK((uv.y == 0.0 || uv.y == 1.0));
  }
}

TEST_CASE("OBJ: a shared position with one uv stays one vertex", "[io][obj]") {
  const std::string s =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
  const LoadedMesh m = parse_obj(s, "square.obj");
  CHECK(m.mesh.vertex_count() == 4);
  CHECK(m.mesh.triangle_count() == 2);
  CHECK(m.mesh.uvs[2] == glm::dvec2{1.0, 1.0});
  // the same position with another uv is another vertex
  const LoadedMesh seam = parse_obj(s + "vt 0.5 0.5\nf 1/5 2/2 3/3\n", "seam.obj");
  CHECK(seam.mesh.vertex_count() == 5);
}

TEST_CASE("OBJ: a non-convex polygon is split by ear clipping, inside its outline", "[io][obj]") {
  // an L of area 3 in the z = 0 plane, counter-clockwise from +z
  const std::string s = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n";
  const LoadedMesh m = parse_obj(s, "ell.obj");
  CHECK(m.mesh.triangle_count() == 4);
  CHECK_THAT(io_test::total_area(m.mesh), WithinRel(3.0, 1e-12));
  for (const auto& t : m.mesh.triangles)
    CHECK(
        glm::cross(m.mesh.positions[t[1]] - m.mesh.positions[t[0]], m.mesh.positions[t[2]] - m.mesh.positions[t[0]]).z >
        0.0);
}

TEST_CASE("OBJ: materials and warnings as data", "[io][obj]") {
  const auto dir = io_test::temp_dir("obj_materials");
  io_test::write(dir / "cube.mtl", "newmtl wood\nKd 0.6 0.4 0.2\nnewmtl steel\nKd 0.5 0.5 0.5\n");
  std::string s = obj_cube_quads(1.0);
  const auto f = s.find("f ");
  s = "mtllib cube.mtl\n" + s.substr(0, f) + "usemtl steel\n" + s.substr(f);
  s.insert(s.rfind("f "), "usemtl wood\n");  // the last face is wood
  const LoadedMesh m = load_obj(io_test::write(dir / "cube.obj", s));
  REQUIRE(m.material_names == std::vector<std::string>{"wood", "steel"});
  REQUIRE(m.mesh.materials.size() == 12);
  for (std::size_t t = 0; t < 10; ++t)
    CHECK(m.mesh.materials[t] == 1);
  CHECK(m.mesh.materials[10] == 0);
  CHECK(m.mesh.materials[11] == 0);

  SECTION("a face before any usemtl gets the default material, named last") {
    std::string d = s;
    d.erase(d.find("usemtl steel\n"), 13);
    const LoadedMesh md = load_obj(io_test::write(dir / "default.obj", d));
    CHECK(md.material_names.back() == "(default)");
    CHECK(md.mesh.materials[0] == 2);
  }
  SECTION("a material file outside the OBJ's folder is not read") {
    io_test::fs::create_directories(dir / "in");
    std::string o = s;
    o.replace(0, o.find('\n'), "mtllib ../cube.mtl");
    const LoadedMesh mo = load_obj(io_test::write(dir / "in" / "cube.obj", o));
    CHECK(mo.material_names.empty());
    CHECK(mo.mesh.materials.empty());
    bool said = false;
    for (const auto& w : mo.warnings)
      said = said || w.message.find("not inside the OBJ's folder") != std::string::npos;
    CHECK(said);
  }
  SECTION("lines are left out with a warning") {
    const LoadedMesh ml = parse_obj(obj_cube_quads(1.0) + "l 1 2\n", "lines.obj");
    CHECK(ml.has_warning(MeshWarningKind::skipped_primitives));
    CHECK(ml.mesh.triangle_count() == 12);
  }
  SECTION("corners without a normal among corners with one get a computed normal") {
    const std::string half = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 2 4 3\n";
    const LoadedMesh mh = parse_obj(half, "half.obj");
    REQUIRE(mh.mesh.has_normals());
    CHECK(mh.has_warning(MeshWarningKind::computed_normals));
    for (const auto& n : mh.mesh.normals)
      CHECK_THAT(n.z, WithinAbs(1.0, 1e-12));
  }
}

TEST_CASE("OBJ: hostile files fail with one clear FileError", "[io][obj][hostile]") {
  const auto dir = io_test::temp_dir("obj_hostile");
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  SECTION("NaN, infinite, overflowing and non-numeric coordinates (tinyobjloader reads them as 0)") {
    expect_file_error([&] { (void)parse_obj("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "nan.obj"); }, "nan.obj",
                      "line 1: 'nan' is not finite");
    expect_file_error([&] { (void)parse_obj("v 0 0 0\nv -inf 0 0\nv 0 1 0\nf 1 2 3\n", "inf.obj"); }, "inf.obj",
                      "line 2: '-inf' is not finite");
    expect_file_error([&] { (void)parse_obj(tri + "vn 0 0 1e999\nf 1//1 2//1 3//1\n", "big.obj"); }, "big.obj",
                      "line 4: '1e999' is not finite");
    expect_file_error([&] { (void)parse_obj("v 0 zero 0\n", "word.obj"); }, "word.obj", "'zero' is not a number");
    CHECK_NOTHROW(parse_obj(tri + "v 1e-400 0 1\nf 1 2 3\n", "tiny.obj"));  // underflow reads as 0
  }
  SECTION("an index past the last vertex") {
    expect_file_error([&] { (void)parse_obj(tri + "f 1 2 4\n", "range.obj"); }, "range.obj",
                      "face 1 corner 3 uses vertex 4 of 3");
  }
  SECTION("a relative index before the first vertex") {
    expect_file_error([&] { (void)parse_obj(tri + "f -1 -2 -9\n", "relative.obj"); }, "relative.obj",
                      "line 4: relative vertex index -9 reaches before the first vertex (3 above it)");
    // relative indices count back from where the face is, not from the end of the file
    expect_file_error([&] { (void)parse_obj("v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n", "early.obj"); }, "early.obj",
                      "line 2: relative vertex index -2 reaches before the first vertex (1 above it)");
    const LoadedMesh m = parse_obj(tri + "vn 0 0 1\nf -3//-1 -2//-1 -1//-1\n", "back.obj");
    CHECK(m.mesh.triangle_count() == 1);
    CHECK(m.mesh.normals.size() == 3);
  }
  SECTION("indices that do not fit an int (tinyobjloader's atoi wraps 4294967299 to 3)") {
    expect_file_error([&] { (void)parse_obj(tri + "f 1 2 4294967299\n", "wrap.obj"); }, "wrap.obj",
                      "line 4: vertex index 4294967299 is out of range");
    expect_file_error([&] { (void)parse_obj(tri + "f 1 2 -4294967293\n", "wrap_neg.obj"); }, "wrap_neg.obj",
                      "line 4: vertex index -4294967293 is out of range");
    expect_file_error([&] { (void)parse_obj(tri + "vt 0 0\nf 1/1 2/1 3/18446744073709551617\n", "wrap_vt.obj"); },
                      "wrap_vt.obj", "line 5: texture coordinate index 18446744073709551617 is out of range");
    expect_file_error([&] { (void)parse_obj(tri + "vn 0 0 1\nf 1//1 2//1 3//4294967297\n", "wrap_vn.obj"); },
                      "wrap_vn.obj", "line 5: normal index 4294967297 is out of range");
  }
  SECTION("relative uv and normal indices before the first one (tinyobjloader takes them for none)") {
    expect_file_error([&] { (void)parse_obj(tri + "vn 0 0 1\nf 1//-1 2//-1 3//-2\n", "neg_vn.obj"); }, "neg_vn.obj",
                      "line 5: relative normal index -2 reaches before the first normal (1 above it)");
    expect_file_error([&] { (void)parse_obj(tri + "vt 0 0\nf 1/-1 2/-1 3/-3\n", "neg_vt.obj"); }, "neg_vt.obj",
                      "line 5: relative texture coordinate index -3 reaches before the first texture coordinate (1 "
                      "above it)");
    expect_file_error([&] { (void)parse_obj(tri + "f 1//-1 2//-1 3//-1\n", "no_vn.obj"); }, "no_vn.obj",
                      "relative normal index -1 reaches before the first normal (0 above it)");
  }
  SECTION("corners that are not indices, and faces of fewer than 3 corners") {
    expect_file_error([&] { (void)parse_obj(tri + "f 1 2 3x\n", "x.obj"); }, "x.obj",
                      "line 4: face corner '3x' is not v, v/vt, v//vn or v/vt/vn indices");
    expect_file_error([&] { (void)parse_obj(tri + "f 1/1/1/1 2 3\n", "four.obj"); }, "four.obj",
                      "line 4: face corner '1/1/1/1' has more than three indices");
    expect_file_error([&] { (void)parse_obj(tri + "f 1 2\n", "two.obj"); }, "two.obj",
                      "line 4: a face needs 3 corners, this one has 2");
    expect_file_error([&] { (void)parse_obj(tri + "f 1 2 0\n", "zero_line.obj"); }, "zero_line.obj",
                      "line 4: vertex index 0: OBJ indices start at 1");
    CHECK(parse_obj(tri + "f +1 +2 +3\r\n", "plus.obj").mesh.triangle_count() == 1);
  }
  SECTION("an out-of-range index in a polygon (tinyobjloader's triangulation would read past its array)") {
    expect_file_error([&] { (void)parse_obj(tri + "f 1 2 3 1 2 99999\n", "poly.obj"); }, "poly.obj",
                      "uses vertex 99999 of 3");
  }
  SECTION("texture coordinate and normal indices out of range") {
    expect_file_error([&] { (void)parse_obj(tri + "vt 0 0\nf 1/1 2/2 3/1\n", "vt.obj"); }, "vt.obj",
                      "uses texture coordinate 2 of 1");
    expect_file_error([&] { (void)parse_obj(tri + "vn 0 0 1\nf 1//1 2//1 3//7\n", "vn.obj"); }, "vn.obj",
                      "uses normal 7 of 1");
  }
  SECTION("index zero (tinyobjloader's error)") {
    expect_file_error([&] { (void)parse_obj(tri + "f 0 1 2\n", "zero.obj"); }, "zero.obj", "zero.obj");
  }
  SECTION("a face of more than 255 corners") {
    std::string s;
    std::string f = "f";
    for (int i = 0; i < 300; ++i) {
      const double angle = 2.0 * 3.141592653589793 * i / 300.0;
      s += "v " + std::to_string(std::cos(angle)) + " " + std::to_string(std::sin(angle)) + " 0\n";
      f.append(1, ' ').append(std::to_string(i + 1));
    }
    expect_file_error([&] { (void)parse_obj(s + f + "\n", "wide.obj"); }, "wide.obj",
                      "line 301: a face of 300 corners: more than 255 corners");
  }
  SECTION("no faces") {
    expect_file_error([&] { (void)parse_obj(tri, "nofaces.obj"); }, "nofaces.obj", "no triangles");
    expect_file_error([&] { (void)parse_obj("", "empty.obj"); }, "empty.obj", "no triangles");
  }
  SECTION("over the size limit") {
    const auto p = io_test::write(dir / "large.obj", obj_cube_quads(1.0));
    MeshReadConfig config;
    config.max_file_bytes = 64;
    expect_file_error([&] { (void)load_obj(p, config); }, p, "larger than the limit of 64 bytes");
  }
  SECTION("more triangles than the limit") {
    MeshReadConfig config;
    config.max_triangles = 11;
    expect_file_error([&] { (void)parse_obj(obj_cube_quads(1.0), "many.obj", config); }, "many.obj", "more than 11");
  }
  SECTION("the triangles of large polygons are counted from the text, before anything is read") {
    // 255-corner faces make 253 triangles each: the limit is passed on the face that passes it, by its line
    std::string s = tri;
    std::string f = "f";
    for (int i = 0; i < 255; ++i)
      f.append(1, ' ').append(std::to_string(i % 3 + 1));
    for (int k = 0; k < 4; ++k)
      s += f + "\n";
    MeshReadConfig config;
    config.max_triangles = 3 * 253;
    expect_file_error([&] { (void)parse_obj(s, "fans.obj", config); }, "fans.obj",
                      "more than 759 triangles by line 7 (raise MeshReadConfig::max_triangles)");
    CHECK(detail::scan_obj_faces(s, "fans.obj", 4 * 253) == 4 * 253);
  }
}

// --- real meshes: ../shared/data/meshes, figures from its README.txt -----------------
namespace {
/// v lines, and distinct positions the faces use, counted from the text
/// here (independently of tinyobjloader): the README counts v lines.
std::pair<std::size_t, std::size_t> count_obj(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<glm::dvec3> v;
  std::set<io_test::Key> used;
  std::vector<std::size_t> face;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "v") {
      glm::dvec3 p{0.0};
      words >> p.x >> p.y >> p.z;
      v.push_back(p);
    } else if (key == "f") {
      for (std::string corner; words >> corner;) {
        const auto k = static_cast<std::size_t>(std::stol(corner.substr(0, corner.find('/')))) - 1;
        used.emplace(v.at(k).x, v.at(k).y, v.at(k).z);
      }
    }
  }
  return {v.size(), used.size()};
}

struct RealObj {
  const char* file;
  std::size_t positions;  ///< v lines (the README counts them welded by exact position)
  std::size_t distinct;   ///< distinct positions the README states where v lines repeat some (0: none stated)
  std::size_t triangles;
  glm::dvec3 size;       ///< bounding box
  std::size_t boundary;  ///< welded boundary edges (0: closed)
  bool uvs;
  bool outward;  ///< closed and stated outward: positive volume
};
}  // namespace

TEST_CASE("OBJ: real meshes match their README's counts and bounds", "[io][obj][real]") {
  const auto data = io_test::shared_data();
  if (data.empty() || !io_test::fs::is_directory(data / "meshes")) {
    WARN("skipped: no shared data folder (set HAPTICFIELD_SHARED_DATA)");
    return;
  }
  const RealObj files[] = {
      {"stanford-bunny.obj", 35947, 0, 69451, {0.1557, 0.1543, 0.1207}, 223, false, false},
      {"spot.obj", 2930, 0, 5856, {0.9431, 1.6904, 1.7179}, 0, true, true},
      {"fandisk.obj", 6475, 0, 12946, {4.8279, 5.2445, 2.6803}, 0, false, true},
      {"teapot.obj", 3644, 3241, 6320, {6.434, 3.15, 4.0}, 160, false, false},
      {"rocker-arm.obj", 10044, 0, 20088, {0.3035, 0.5149, 1.0}, 0, false, true},
  };
  for (const RealObj& r : files) {
    INFO(r.file);
    const LoadedMesh m = load_obj((data / "meshes" / r.file).string());
    CHECK(m.mesh.triangle_count() == r.triangles);
    const auto [v_lines, used] = count_obj((data / "meshes" / r.file).string());
    CHECK(v_lines == r.positions);
    CHECK(io_test::distinct_positions(m.mesh) == used);  // only the vertices faces use are kept
    if (r.distinct > 0) CHECK(io_test::distinct_positions(m.mesh) == r.distinct);
    const glm::dvec3 size = io_test::bounds(m.mesh).size();
    for (int k = 0; k < 3; ++k)
      CHECK_THAT(size[k], WithinAbs(r.size[k], 0.00051 * std::max(1.0, r.size[k])));  // README's 4 digits
    const auto edges = io_test::welded_edges(m.mesh);
    CHECK(edges.boundary == r.boundary);
    CHECK(edges.same_direction == 0);  // consistently oriented
    CHECK(m.mesh.has_uvs() == r.uvs);
    CHECK_FALSE(m.mesh.has_normals());  // no vn lines
    if (r.outward) CHECK(io_test::signed_volume(m.mesh) > 0.0);
    std::cout << r.file << ": " << m.mesh.triangle_count() << " triangles, " << m.mesh.vertex_count() << " vertices ("
              << io_test::distinct_positions(m.mesh) << " positions), " << edges.boundary << " boundary edges, size "
              << size.x << " x " << size.y << " x " << size.z << "\n";
  }
}
