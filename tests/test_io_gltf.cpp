// Tests of the glTF reader (io/gltf.hpp, tinygltf): the hand-written cube as
// .gltf (embedded and external buffer) and .glb against its closed form,
// node transforms (matrix, TRS, parents, mirrors), normals and uvs,
// hostile files, load_mesh(), and the real sample models of
// ../shared/data/gltf against the figures their README states (skipped
// when absent).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <iostream>
#include <string>

#include "hapticfield/io/gltf.hpp"
#include "io_test_util.hpp"
#ifdef HAPTICFIELD_TEST_LOAD_MESH
#include "hapticfield/io/load_mesh.hpp"
#endif

using namespace hapticfield;
using namespace hapticfield::io;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using io_test::expect_file_error;

namespace {

/// The unit cube's buffer: 8 float positions (96 bytes), 36 uint16 indices (72).
std::string cube_bin(double a = 1.0) {
  std::string b;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 p = io_test::cube_corner(k, a);
    io_test::putf(b, static_cast<float>(p.x));
    io_test::putf(b, static_cast<float>(p.y));
    io_test::putf(b, static_cast<float>(p.z));
  }
  for (const auto& t : io_test::cube_triangles())
    for (const int k : t)
      io_test::put16(b, static_cast<std::uint16_t>(k));
  return b;
}

const std::string embedded_uri = "@URI@";

/// The cube's JSON; "@URI@" stands for the buffer's uri ("" for a .glb).
std::string cube_json(const std::string& node = R"({"mesh": 0})", const std::string& extra = "") {
  return R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [)" +
         node +
         R"(],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
  "materials": [{"name": "steel"}],
  "buffers": [{"byteLength": 168@URI@}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96},
                  {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3"},
                {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}])" +
         extra + "\n}\n";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  REQUIRE(at != std::string::npos);
  return s.replace(at, from.size(), to);
}

/// A .gltf with the buffer as a base64 data uri.
std::string embed(const std::string& json, const std::string& bin) {
  return replace(json, embedded_uri,
                 R"(, "uri": "data:application/octet-stream;base64,)" + io_test::base64(bin) + "\"");
}

/// A .glb: header, JSON chunk (space-padded), BIN chunk (zero-padded).
std::string glb(std::string json, std::string bin) {
  json = replace(json, embedded_uri, "");
  while (json.size() % 4 != 0)
    json.push_back(' ');
  while (bin.size() % 4 != 0)
    bin.push_back('\0');
  std::string s = "glTF";
  io_test::put32(s, 2);
  io_test::put32(s, static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  io_test::put32(s, static_cast<std::uint32_t>(json.size()));
  s += "JSON";
  s += json;
  io_test::put32(s, static_cast<std::uint32_t>(bin.size()));
  s += std::string("BIN\0", 4);
  return s + bin;
}

void check_cube(const LoadedMesh& m, const glm::dvec3& lo, double a) {
  CHECK(m.mesh.triangle_count() == 12);
  CHECK(m.mesh.vertex_count() == 8);
  CHECK_THAT(io_test::total_area(m.mesh), WithinRel(6.0 * a * a, 1e-6));
  CHECK_THAT(io_test::signed_volume(m.mesh), WithinRel(a * a * a, 1e-6));
  const auto b = io_test::bounds(m.mesh);
  for (int k = 0; k < 3; ++k) {
    CHECK_THAT(b.lo[k], WithinAbs(lo[k], 1e-6));
    CHECK_THAT(b.hi[k], WithinAbs(lo[k] + a, 1e-6));
  }
  CHECK(io_test::welded_edges(m.mesh).boundary == 0);
  CHECK(io_test::welded_edges(m.mesh).same_direction == 0);
}

}  // namespace

TEST_CASE("glTF: the cube as .gltf and .glb gives the closed-form cube", "[io][gltf]") {
  const auto dir = io_test::temp_dir("gltf_cube");
  const std::string bin = cube_bin();
  const LoadedMesh text = load_gltf(io_test::write(dir / "cube.gltf", embed(cube_json(), bin)));
  check_cube(text, glm::dvec3{0.0}, 1.0);
  CHECK(text.material_names == std::vector<std::string>{"steel"});
  CHECK(text.mesh.materials == std::vector<std::uint32_t>(12, 0));
  CHECK(text.has_warning(MeshWarningKind::no_normals));
  CHECK_FALSE(text.mesh.has_uvs());

  const LoadedMesh binary = load_gltf(io_test::write(dir / "cube.glb", glb(cube_json(), bin)));
  check_cube(binary, glm::dvec3{0.0}, 1.0);
  CHECK(binary.mesh.triangles == text.mesh.triangles);

  SECTION("an external buffer beside the file") {
    io_test::write(dir / "cube.bin", bin);
    const LoadedMesh ext =
        load_gltf(io_test::write(dir / "external.gltf", replace(cube_json(), embedded_uri, R"(, "uri": "cube.bin")")));
    check_cube(ext, glm::dvec3{0.0}, 1.0);
  }
  SECTION("the scale multiplies after the transforms") {
    MeshReadConfig config;
    config.scale = 0.01;
    check_cube(parse_gltf(embed(cube_json(R"({"mesh": 0, "translation": [100, 0, 0]})"), bin), "s.gltf", config),
               {1.0, 0.0, 0.0}, 0.01);
  }
}

TEST_CASE("glTF: node transforms place the mesh in world space", "[io][gltf]") {
  const std::string bin = cube_bin();
  SECTION("translation, rotation (quaternion) and scale: T R S") {
    // scale x by 2, turn +90 deg about z (x -> y), move by (10, 0, 0)
    const LoadedMesh m = parse_gltf(
        embed(
            cube_json(
                R"({"mesh": 0, "translation": [10, 0, 0], "rotation": [0, 0, 0.7071067811865476, 0.7071067811865476], "scale": [2, 1, 1]})"),
            bin),
        "trs.gltf");
    const auto b = io_test::bounds(m.mesh);
    CHECK_THAT(b.lo.x, WithinAbs(9.0, 1e-9));  // y in [0, 1] became -x
    CHECK_THAT(b.hi.x, WithinAbs(10.0, 1e-9));
    CHECK_THAT(b.lo.y, WithinAbs(0.0, 1e-9));
    CHECK_THAT(b.hi.y, WithinAbs(2.0, 1e-9));  // the scaled x became y
    CHECK_THAT(io_test::signed_volume(m.mesh), WithinRel(2.0, 1e-9));
  }
  SECTION("a parent's matrix (column-major, -90 deg about x as in Box.gltf) over a child's translation") {
    const std::string nodes =
        R"({"children": [1], "matrix": [1,0,0,0, 0,0,-1,0, 0,1,0,0, 0,0,0,1]}, {"mesh": 0, "translation": [0, 0, 5]})";
    std::string json = cube_json(nodes);
    const LoadedMesh m = parse_gltf(embed(json, bin), "parent.gltf");
    const auto b = io_test::bounds(m.mesh);
    // child: z in [5, 6]; the parent maps (x, y, z) to (x, z, -y)
    CHECK_THAT(b.lo.y, WithinAbs(5.0, 1e-9));
    CHECK_THAT(b.hi.y, WithinAbs(6.0, 1e-9));
    CHECK_THAT(b.lo.z, WithinAbs(-1.0, 1e-9));
    CHECK_THAT(b.hi.z, WithinAbs(0.0, 1e-9));
    CHECK_THAT(io_test::signed_volume(m.mesh), WithinRel(1.0, 1e-9));
  }
  SECTION("a mirror keeps the faces pointing out") {
    const LoadedMesh m = parse_gltf(embed(cube_json(R"({"mesh": 0, "scale": [-1, 1, 1]})"), bin), "mirror.gltf");
    CHECK_THAT(io_test::signed_volume(m.mesh), WithinRel(1.0, 1e-9));
    CHECK_THAT(io_test::bounds(m.mesh).lo.x, WithinAbs(-1.0, 1e-9));
  }
  SECTION("one mesh under two nodes is placed twice") {
    std::string json = cube_json(R"({"mesh": 0}, {"mesh": 0, "translation": [3, 0, 0]})");
    json = replace(json, R"("nodes": [0]}])", R"("nodes": [0, 1]}])");
    const LoadedMesh m = parse_gltf(embed(json, bin), "twice.gltf");
    CHECK(m.mesh.triangle_count() == 24);
    CHECK_THAT(io_test::signed_volume(m.mesh), WithinRel(2.0, 1e-9));
    MeshReadConfig config;
    config.max_triangles = 20;
    expect_file_error([&] { (void)parse_gltf(embed(json, bin), "twice.gltf", config); }, "twice.gltf",
                      "after placing every node");
  }
}

TEST_CASE("glTF: normals turn with the node, uvs come back v up", "[io][gltf]") {
  // one triangle in z = 0 with normal +z and uvs (0,0) (1,0) (0,1) in glTF's v-down convention
  std::string bin;
  for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f})  // positions
    io_test::putf(bin, v);
  for (int i = 0; i < 3; ++i)  // normals
    for (const float v : {0.f, 0.f, 1.f})
      io_test::putf(bin, v);
  for (const float v : {0.f, 0.f, 1.f, 0.f, 0.f, 1.f})  // uvs
    io_test::putf(bin, v);
  const std::string json = R"({
  "asset": {"version": "2.0"},
  "nodes": [{"mesh": 0, "rotation": [0.7071067811865476, 0, 0, 0.7071067811865476]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}]}],
  "buffers": [{"byteLength": 96@URI@}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 72, "byteStride": 12},
                  {"buffer": 0, "byteOffset": 72, "byteLength": 24, "byteStride": 8}],
  "accessors": [{"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]
})";
  const LoadedMesh m = parse_gltf(embed(json, bin), "tri.gltf");  // no scene: the root nodes
  REQUIRE(m.mesh.triangle_count() == 1);
  REQUIRE(m.mesh.has_normals());
  REQUIRE(m.mesh.has_uvs());
  for (const auto& n : m.mesh.normals) {  // +90 deg about x: +z -> -y
    CHECK_THAT(n.y, WithinAbs(-1.0, 1e-9));
    CHECK_THAT(n.z, WithinAbs(0.0, 1e-9));
  }
  CHECK(m.mesh.uvs[0] == glm::dvec2{0.0, 1.0});
  CHECK(m.mesh.uvs[1] == glm::dvec2{1.0, 1.0});
  CHECK(m.mesh.uvs[2] == glm::dvec2{0.0, 0.0});
  CHECK(m.material_names.empty());
  CHECK(m.mesh.materials.empty());
}

TEST_CASE("glTF: hostile files fail with one clear FileError", "[io][gltf][hostile]") {
  const auto dir = io_test::temp_dir("gltf_hostile");
  const std::string bin = cube_bin();
  const std::string json = cube_json();
  const auto fails = [&](const std::string& text, const std::string& what, const std::string& bytes = "") {
    const std::string file = bytes.empty() ? embed(text, bin) : bytes;
    expect_file_error([&] { (void)parse_gltf(file, "bad.gltf"); }, "bad.gltf", what);
  };
  SECTION("count x stride beyond the buffer view") {
    fails(replace(json, R"("count": 8)", R"("count": 9)"), "9 elements of stride 12 from offset 0 do not fit");
  }
  SECTION("a 2^31 count claims 24 GB and is refused before any allocation") {
    fails(replace(json, R"("count": 8)", R"("count": 2147483648)"), "2147483648 elements");
  }
  SECTION("an accessor offset past its view") {
    fails(replace(json, R"("count": 8, "type": "VEC3")", R"("count": 8, "type": "VEC3", "byteOffset": 4)"),
          "do not fit");
  }
  SECTION("many primitives over one accessor count against the triangle limit before they are built") {
    std::string prims;
    for (int i = 0; i < 1000; ++i)
      prims += std::string(i ? ", " : "") + R"({"attributes": {"POSITION": 0}, "indices": 1})";
    const std::string many =
        replace(json, R"([{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}])", "[" + prims + "]");
    MeshReadConfig config;
    config.max_triangles = 100;
    expect_file_error([&] { (void)parse_gltf(embed(many, bin), "many.gltf", config); }, "many.gltf",
                      "mesh 0 primitive 8: more than 100 triangles");
    CHECK(parse_gltf(embed(many, bin), "many.gltf").mesh.triangle_count() == 12000);
  }
  SECTION("a stride smaller than an element") {
    fails(replace(json, R"("byteLength": 96})", R"("byteLength": 96, "byteStride": 4})"),
          "byteStride 4 is smaller than an element");
  }
  SECTION("a buffer view beyond its buffer") {
    fails(replace(json, R"("byteOffset": 96, "byteLength": 72)", R"("byteOffset": 96, "byteLength": 720)"),
          "outside its buffer");
  }
  SECTION("an index past the last vertex") {
    fails(replace(replace(json, R"("count": 8)", R"("count": 7)"), R"("byteLength": 96})", R"("byteLength": 84})"),
          "out of range for 7 vertices");
  }
  SECTION("a NaN position") {
    std::string b = bin;
    b.replace(12, 4, "\x00\x00\xC0\x7F", 4);
    expect_file_error([&] { (void)parse_gltf(embed(json, b), "nan.gltf"); }, "nan.gltf", "is not finite");
  }
  SECTION("a wrong attribute type") {
    fails(replace(json, R"("componentType": 5126)", R"("componentType": 5123)"), "component type 5123");
  }
  SECTION("a node cycle") {
    fails(cube_json(R"({"mesh": 0, "children": [0]})"), "reached twice");
  }
  SECTION("a node, a mesh and a material that do not exist") {
    fails(replace(json, R"("nodes": [0]}])", R"("nodes": [5]}])"), "node 5 does not exist");
    fails(cube_json(R"({"mesh": 3})"), "uses mesh 3 of 1");
    fails(replace(json, R"("material": 0)", R"("material": 2)"), "uses material 2 of 1");
  }
  SECTION("no mesh at all") {
    fails(cube_json(R"({"name": "empty"})"), "no triangles");
  }
  SECTION("points are left out, and then nothing is left") {
    fails(replace(json, R"("material": 0)", R"("material": 0, "mode": 0)"), "no triangles");
  }
  SECTION("a sparse accessor") {
    fails(
        replace(
            json, R"("count": 8, "type": "VEC3")",
            R"("count": 8, "type": "VEC3", "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}})"),
        "sparse");
  }
  SECTION("a required extension that changes geometry") {
    fails(
        cube_json(
            R"({"mesh": 0})",
            R"(, "extensionsRequired": ["KHR_draco_mesh_compression"], "extensionsUsed": ["KHR_draco_mesh_compression"])"),
        "KHR_draco_mesh_compression");
  }
  SECTION("JSON nested 10000 deep") {
    fails(replace(json, R"("asset")",
                  R"("extras": )" + std::string(10000, '[') + std::string(10000, ']') + R"(, "asset")"),
          "nested deeper than 64");
  }
  SECTION("broken JSON") {
    fails("", "", embed(json, bin).substr(0, 200));
  }
  SECTION("a base64 buffer shorter than its byteLength") {
    fails("", "", embed(json, bin.substr(0, 100)));
  }
  SECTION(".glb: truncated, a JSON chunk past the end, a BIN chunk past the end") {
    const std::string g = glb(json, bin);
    fails("", "truncated .glb", g.substr(0, g.size() - 10));
    std::string j = g;
    j.replace(12, 4, "\xFF\xFF\xFF\x7F", 4);
    fails("", "JSON chunk declares", j);
    std::string b = g;
    const std::size_t bin_header = g.size() - 168 - 8;
    b.replace(bin_header, 4, "\x00\x10\x00\x00", 4);
    fails("", "BIN chunk declares", b);
    std::string v = g;
    v[4] = 1;
    fails("", ".glb version 1", v);
  }
  SECTION("an external buffer outside the file's folder is not read") {
    io_test::fs::create_directories(dir / "in");
    io_test::write(dir / "cube.bin", bin);
    const auto p = io_test::write(dir / "in" / "up.gltf", replace(json, embedded_uri, R"(, "uri": "../cube.bin")"));
    expect_file_error([&] { (void)load_gltf(p); }, p, "outside the file's folder");
    const auto q = io_test::write(dir / "in" / "abs.gltf",
                                  replace(json, embedded_uri, R"(, "uri": ")" + (dir / "cube.bin").string() + "\""));
    expect_file_error([&] { (void)load_gltf(q); }, q,
                      "external buffer '" + (dir / "cube.bin").string() + "' is an absolute path: not read");
    // an absolute path is refused, and said so, even to a file that exists inside the folder (not "File not found")
    io_test::write(dir / "in" / "cube.bin", bin);
    const std::string inside = (dir / "in" / "cube.bin").string();
    const auto r =
        io_test::write(dir / "in" / "abs_inside.gltf", replace(json, embedded_uri, R"(, "uri": ")" + inside + "\""));
    expect_file_error([&] { (void)load_gltf(r); }, r,
                      "external buffer '" + inside +
                          "' is an absolute path: not read (a buffer's uri must be relative to the glTF file, inside "
                          "its folder)");
    CHECK(load_gltf(io_test::write(dir / "in" / "rel.gltf", replace(json, embedded_uri, R"(, "uri": "cube.bin")")))
              .mesh.triangle_count() > 0);
    // from memory there is no folder: no external file at all
    expect_file_error([&] { (void)parse_gltf(replace(json, embedded_uri, R"(, "uri": "cube.bin")"), "mem.gltf"); },
                      "mem.gltf", "mem.gltf");
  }
  SECTION("an external buffer over the size limit") {
    io_test::write(dir / "cube.bin", bin);
    const auto p = io_test::write(dir / "ext.gltf", replace(json, embedded_uri, R"(, "uri": "cube.bin")"));
    MeshReadConfig config;
    config.max_file_bytes = io_test::fs::file_size(p) + 100;  // the .gltf fits, with its 168-byte buffer it does not
    expect_file_error([&] { (void)load_gltf(p, config); }, p, "larger than the limit");
    config.max_file_bytes = io_test::fs::file_size(p) + 168;
    CHECK(load_gltf(p, config).mesh.triangle_count() == 12);
  }
  SECTION("the file over the size limit") {
    const auto p = io_test::write(dir / "big.gltf", embed(json, bin));
    MeshReadConfig config;
    config.max_file_bytes = 512;
    expect_file_error([&] { (void)load_gltf(p, config); }, p, "larger than the limit of 512 bytes");
  }
}

#ifdef HAPTICFIELD_TEST_LOAD_MESH
TEST_CASE("load_mesh: the same cube from every format by extension", "[io]") {
  const auto dir = io_test::temp_dir("load_mesh");
  const LoadedMesh g = load_mesh(io_test::write(dir / "cube.GLB", glb(cube_json(), cube_bin(2.0))));
  check_cube(g, glm::dvec3{0.0}, 2.0);
  std::string obj;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 p = io_test::cube_corner(k, 2.0);
    obj += "v " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
  }
  for (const auto& t : io_test::cube_triangles())
    obj += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) + "\n";
  const LoadedMesh o = load_mesh(io_test::write(dir / "cube.obj", obj));
  check_cube(o, glm::dvec3{0.0}, 2.0);
  CHECK(o.mesh.triangles == g.mesh.triangles);  // same corner order, same triangles
  const auto p = io_test::write(dir / "cube.ply", "ply\n");
  expect_file_error([&] { (void)load_mesh(p); }, p, "unknown mesh format '.ply'");
}
#endif

// --- real models: ../shared/data/gltf, figures from its README.txt ---------------------
TEST_CASE("glTF: real sample models match their README's counts and bounds", "[io][gltf][real]") {
  const auto data = io_test::shared_data();
  if (data.empty() || !io_test::fs::is_directory(data / "gltf")) {
    WARN("skipped: no shared data folder (set HAPTICFIELD_SHARED_DATA)");
    return;
  }
  const auto size_of = [](const LoadedMesh& m) { return io_test::bounds(m.mesh).size(); };
  SECTION("Box: 12 triangles, 24 vertices with normals, a 1 m cube after the -90 deg root matrix") {
    const LoadedMesh m = load_gltf((data / "gltf" / "Box.gltf").string());
    CHECK(m.mesh.triangle_count() == 12);
    CHECK(m.mesh.vertex_count() == 24);
    CHECK(m.mesh.has_normals());
    CHECK_FALSE(m.mesh.has_uvs());
    const glm::dvec3 s = size_of(m);
    CHECK_THAT(glm::length(s), WithinAbs(1.732, 0.0006));
    for (int k = 0; k < 3; ++k)
      CHECK_THAT(s[k], WithinAbs(1.0, 1e-6));
    CHECK_THAT(io_test::signed_volume(m.mesh), WithinRel(1.0, 1e-6));  // closed, faces out
    CHECK(io_test::welded_edges(m.mesh).boundary == 0);
    CHECK(m.warnings.empty());
  }
  SECTION("BoxTextured: uvs 0..6 x 0..1, strided buffer views") {
    const LoadedMesh m = load_gltf((data / "gltf" / "BoxTextured.gltf").string());
    CHECK(m.mesh.triangle_count() == 12);
    CHECK(m.mesh.vertex_count() == 24);
    REQUIRE(m.mesh.has_uvs());
    glm::dvec2 lo{1e9}, hi{-1e9};
    for (const auto& uv : m.mesh.uvs) {
      lo = glm::min(lo, uv);
      hi = glm::max(hi, uv);
    }
    CHECK_THAT(lo.x, WithinAbs(0.0, 1e-6));
    CHECK_THAT(hi.x, WithinAbs(6.0, 1e-6));
    CHECK_THAT(lo.y, WithinAbs(0.0, 1e-6));  // 1 - v spans the same 0..1
    CHECK_THAT(hi.y, WithinAbs(1.0, 1e-6));
    for (int k = 0; k < 3; ++k)
      CHECK_THAT(size_of(m)[k], WithinAbs(1.0, 1e-6));
    CHECK_THAT(io_test::signed_volume(m.mesh), WithinRel(1.0, 1e-6));
  }
  SECTION("Duck: 4212 triangles, 2399 vertices (2108 positions), 1.655 x 1.540 x 1.153 m after scale 0.01") {
    const LoadedMesh m = load_gltf((data / "gltf" / "Duck.gltf").string());
    CHECK(m.mesh.triangle_count() == 4212);
    CHECK(m.mesh.vertex_count() == 2399);
    CHECK(io_test::distinct_positions(m.mesh) == 2108);
    CHECK(m.mesh.has_normals());
    CHECK(m.mesh.has_uvs());
    const glm::dvec3 s = size_of(m);
    CHECK_THAT(s.x, WithinAbs(1.655, 0.0006));
    CHECK_THAT(s.y, WithinAbs(1.540, 0.0006));
    CHECK_THAT(s.z, WithinAbs(1.153, 0.0006));
    CHECK_THAT(glm::length(s), WithinAbs(2.538, 0.0006));
    CHECK(io_test::welded_edges(m.mesh).boundary == 0);  // closed
    CHECK(io_test::signed_volume(m.mesh) > 0.0);
    std::cout << "Duck: " << m.mesh.triangle_count() << " triangles, " << m.mesh.vertex_count() << " vertices, size "
              << s.x << " x " << s.y << " x " << s.z << " m\n";
  }
  SECTION("OrientationTest: 524 triangles in 13 meshes, TRS and matrix nodes, 10.66 m cube of bounds") {
    const LoadedMesh m = load_gltf((data / "gltf" / "OrientationTest.gltf").string());
    CHECK(m.mesh.triangle_count() == 524);
    const glm::dvec3 s = size_of(m);
    for (int k = 0; k < 3; ++k)
      CHECK_THAT(s[k], WithinAbs(10.66, 0.006));
    CHECK_THAT(glm::length(s), WithinAbs(18.47, 0.006));
    std::cout << "OrientationTest: " << m.mesh.triangle_count() << " triangles, " << m.material_names.size()
              << " materials, size " << s.x << " x " << s.y << " x " << s.z << " m\n";
  }
}
