// Tests of the STL reader (io/stl.hpp) and of what every mesh reader shares
// (io/mesh_read.hpp): the hand-written cube in binary and ASCII STL against
// its closed form (12 triangles, area 6 a^2, volume a^3, bounds [0, a]^3),
// and every hostile file as crafted bytes in a temporary folder.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/io/stl.hpp"
#include "io_test_util.hpp"

using namespace hapticfield;
using namespace hapticfield::io;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using io_test::expect_file_error;

namespace {

/// A binary STL of the cube of edge a, facets unwelded as STL stores them.
std::string binary_cube(double a, std::uint32_t declared = 12) {
  std::string s(80, ' ');
  s.replace(0, 11, "solid cube ");  // some exporters start binary files with "solid"
  io_test::put32(s, declared);
  for (const auto& t : io_test::cube_triangles()) {
    const glm::dvec3 p0 = io_test::cube_corner(t[0], a), p1 = io_test::cube_corner(t[1], a),
                     p2 = io_test::cube_corner(t[2], a);
    const glm::dvec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    for (const glm::dvec3& v : {n, p0, p1, p2}) {
      io_test::putf(s, static_cast<float>(v.x));
      io_test::putf(s, static_cast<float>(v.y));
      io_test::putf(s, static_cast<float>(v.z));
    }
    io_test::put16(s, 0);
  }
  return s;
}

std::string ascii_cube(double a) {
  std::string s = "solid cube\n";
  for (const auto& t : io_test::cube_triangles()) {
    const glm::dvec3 p0 = io_test::cube_corner(t[0], a), p1 = io_test::cube_corner(t[1], a),
                     p2 = io_test::cube_corner(t[2], a);
    const glm::dvec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    s += "  facet normal " + std::to_string(n.x) + " " + std::to_string(n.y) + " " + std::to_string(n.z) + "\n";
    s += "    outer loop\n";
    for (const glm::dvec3& p : {p0, p1, p2})
      s += "      vertex " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid cube\n";
}

/// The cube's closed form: 12 triangles on 8 welded corners, area 6 a^2,
/// volume a^3 (faces out), bounds [0, a]^3, no degenerate triangle.
void check_cube(const LoadedMesh& loaded, double a, std::size_t vertices = 8) {
  const TriangleMesh& m = loaded.mesh;
  CHECK(m.triangle_count() == 12);
  CHECK(m.vertex_count() == vertices);
  CHECK_THAT(io_test::total_area(m), WithinRel(6.0 * a * a, 1e-6));
  CHECK_THAT(io_test::signed_volume(m), WithinRel(a * a * a, 1e-6));
  const auto b = io_test::bounds(m);
  CHECK_THAT(b.lo.x, WithinAbs(0.0, 1e-9 * a));
  CHECK_THAT(b.hi.x, WithinRel(a, 1e-6));
  CHECK_THAT(b.hi.y, WithinRel(a, 1e-6));
  CHECK_THAT(b.hi.z, WithinRel(a, 1e-6));
  CHECK(io_test::welded_edges(m).boundary == 0);
  CHECK(io_test::welded_edges(m).same_direction == 0);
  CHECK_FALSE(loaded.has_warning(MeshWarningKind::degenerate_triangles));
  CHECK_NOTHROW(m.validate());
}

}  // namespace

TEST_CASE("STL: a binary and an ASCII cube give the closed-form cube", "[io][stl]") {
  const auto dir = io_test::temp_dir("stl_cube");
  const double a = 0.05;  // [m]
  const LoadedMesh bin = load_stl(io_test::write(dir / "cube.stl", binary_cube(a)));
  check_cube(bin, a);
  CHECK_FALSE(bin.mesh.has_normals());  // facet normals are face normals
  CHECK_FALSE(bin.mesh.has_uvs());
  CHECK(bin.mesh.materials.empty());
  CHECK(bin.warnings.empty());
  const LoadedMesh text = load_stl(io_test::write(dir / "cube_ascii.stl", ascii_cube(a)));
  check_cube(text, a);
  CHECK(text.warnings.empty());
  // the same triangles, the same welded corners
  CHECK(text.mesh.triangles == bin.mesh.triangles);
}

TEST_CASE("STL: the scale turns millimetres into metres", "[io][stl]") {
  MeshReadConfig config;
  config.scale = 1e-3;  // the file is in mm
  check_cube(parse_stl(ascii_cube(50.0), "mm.stl", config), 0.05);
  config.scale = 0.0;
  CHECK_THROWS_AS(parse_stl(ascii_cube(1.0), "x.stl", config), std::invalid_argument);
  config.scale = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(parse_stl(ascii_cube(1.0), "x.stl", config), std::invalid_argument);
}

TEST_CASE("STL: warnings come back as data", "[io][stl]") {
  SECTION("facet normals against the vertex order") {
    std::string s = ascii_cube(1.0);
    const auto at = s.find("facet normal ") + 13;
    s.replace(at, s.find('\n', at) - at, "0 0 1");  // the first facet faces -z
    const LoadedMesh m = parse_stl(s, "flipped.stl");
    REQUIRE(m.has_warning(MeshWarningKind::facet_normals));
    CHECK(m.mesh.triangle_count() == 12);
  }
  SECTION("a degenerate triangle") {
    std::string s = ascii_cube(1.0);
    s.insert(s.rfind("endsolid"),
             "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 2 0 0\nendloop\nendfacet\n");
    const LoadedMesh m = parse_stl(s, "sliver.stl");
    CHECK(m.has_warning(MeshWarningKind::degenerate_triangles));
    CHECK(m.mesh.triangle_count() == 13);
  }
  SECTION("bytes after the declared triangles") {
    const LoadedMesh m = parse_stl(binary_cube(1.0) + "garbage", "trailing.stl");
    CHECK(m.has_warning(MeshWarningKind::trailing_bytes));
    CHECK(m.mesh.triangle_count() == 12);
  }
}

TEST_CASE("STL: hostile files fail with one clear FileError", "[io][stl][hostile]") {
  const auto dir = io_test::temp_dir("stl_hostile");
  SECTION("a NaN vertex (binary)") {
    std::string s = binary_cube(1.0);
    s.replace(84 + 12, 4, "\x00\x00\xC0\x7F", 4);  // facet 0, vertex 0, x = NaN
    const auto p = io_test::write(dir / "nan.stl", s);
    expect_file_error([&] { (void)load_stl(p); }, p, "not finite");
  }
  SECTION("an infinite vertex (ASCII)") {
    std::string s = ascii_cube(1.0);
    s.replace(s.find("vertex ") + 7, 8, "inf     ");
    expect_file_error([&] { (void)parse_stl(s, "inf.stl"); }, "inf.stl", "not finite");
  }
  SECTION("a vertex that overflows at the scale") {
    std::string s = ascii_cube(1.0);
    s.replace(s.find("vertex ") + 7, 8, "1e300   ");
    MeshReadConfig config;
    config.scale = 1e10;
    expect_file_error([&] { (void)parse_stl(s, "big.stl", config); }, "big.stl", "overflows");
  }
  SECTION("truncated binary: the count needs more bytes than the file has") {
    const std::string s = binary_cube(1.0, 1000);
    expect_file_error([&] { (void)parse_stl(s, "short.stl"); }, "short.stl", "truncated");
  }
  SECTION("a 2^32 - 1 triangle claim in a 684-byte file allocates nothing and fails") {
    std::string s = binary_cube(1.0);
    s.replace(80, 4, "\xFF\xFF\xFF\xFF", 4);
    expect_file_error([&] { (void)parse_stl(s, "claim.stl"); }, "claim.stl", "declares 4294967295 triangles");
  }
  SECTION("a binary header alone declaring zero triangles") {
    std::string s(80, '\0');
    io_test::put32(s, 0);
    expect_file_error([&] { (void)parse_stl(s, "zero.stl"); }, "zero.stl", "no triangles");
  }
  SECTION("an empty file") {
    const auto p = io_test::write(dir / "empty.stl", "");
    expect_file_error([&] { (void)load_stl(p); }, p, "neither an ASCII STL");
  }
  SECTION("ASCII: a solid without facets") {
    expect_file_error([&] { (void)parse_stl("solid x\nendsolid x\n", "hollow.stl"); }, "hollow.stl", "no triangles");
  }
  SECTION("ASCII: truncated in the middle of a facet, with its line") {
    std::string s = ascii_cube(1.0);
    s.resize(s.find("endloop"));
    expect_file_error([&] { (void)parse_stl(s, "cut.stl"); }, "cut.stl", "line 7: expected 'endloop'");
  }
  SECTION("ASCII: a word that is not a number") {
    std::string s = ascii_cube(1.0);
    s.replace(s.find("vertex ") + 7, 3, "abc");
    expect_file_error([&] { (void)parse_stl(s, "word.stl"); }, "word.stl", "expected a number");
  }
  SECTION("'solid' and binary bytes whose count does not fit: binary, truncated") {
    std::string s = binary_cube(1.0);
    s.replace(80, 4, "\x10\x00\x00\x00", 4);  // 16 declared, 12 present
    expect_file_error([&] { (void)parse_stl(s, "mixed.stl"); }, "mixed.stl", "truncated");
  }
  SECTION("a file over the size limit is not read") {
    const auto p = io_test::write(dir / "large.stl", binary_cube(1.0));
    MeshReadConfig config;
    config.max_file_bytes = 100;
    expect_file_error([&] { (void)load_stl(p, config); }, p, "larger than the limit of 100 bytes");
  }
  SECTION("more triangles than the limit") {
    MeshReadConfig config;
    config.max_triangles = 10;
    expect_file_error([&] { (void)parse_stl(binary_cube(1.0), "many.stl", config); }, "many.stl", "limit of 10");
    expect_file_error([&] { (void)parse_stl(ascii_cube(1.0), "many.stl", config); }, "many.stl", "more than 10");
  }
  SECTION("a missing file") {
    const std::string p = (dir / "absent.stl").string();
    expect_file_error([&] { (void)load_stl(p); }, p, "no such file");
  }
}

TEST_CASE("mesh_read: paths a model may read", "[io]") {
  const auto dir = io_test::temp_dir("paths");
  io_test::write(dir / "a.bin", "x");
  io_test::fs::create_directories(dir / "sub");
  io_test::write(dir / "sub" / "b.bin", "y");
  const std::string d = dir.string();
  CHECK(detail::path_inside(d, "a.bin") == (dir / "a.bin").string());
  CHECK(!detail::path_inside(d, "sub/b.bin").empty());
  CHECK(!detail::path_inside(d, "sub/../a.bin").empty());
  CHECK(detail::path_inside(d, "../a.bin").empty());
  CHECK(detail::path_inside(d, "sub/../../a.bin").empty());
  CHECK(detail::path_inside(d, "/etc/passwd").empty());
  CHECK(detail::path_inside(d, "").empty());
  CHECK(detail::path_inside(d, ".").empty());
  CHECK(detail::path_inside("", "a.bin").empty());
}
