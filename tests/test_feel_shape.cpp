// Tests of the feel_shape tool (examples/13_feel_shape.cpp), run as a child
// process: --help; each bad input (missing and hostile files, bad CSV rows,
// NaN probes, t that does not increase, bad flag values, unknown flags) is
// one stderr line and a non-zero exit; closed forms: a flat STL plane gives
// F = k depth along +z with the proxy on the plane, an icosphere gives a
// force along the radius of size k depth, flat pictures and depth maps give
// F = k (height - z); with --radius R a ball on the flat STL rests R above
// it with F = k (R - z); --paths writes each tick's path, which joins the
// proxy rows and passes through no face of a thin slab (MeshChecker's plain
// scan); the real meshes of the shared data run end to end.
#include <catch2/catch.hpp>

#include "child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "hapticfield/surface/proxy_check.hpp"
#include "surface_meshes.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::WithinAbs;

const fs::path tmp = fs::path(HAPTICFIELD_TEST_TMP) / "feel_shape";

std::string in_tmp(const std::string& name) {
  fs::create_directories(tmp);
  return (tmp / name).string();
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string write(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  return path;
}

struct Result {
  int status{-1};  // exit status; -1 when killed or signalled
  std::string out, err;
};

/// Runs feel_shape with stdin from a file (or /dev/null), killed after 60 s.
Result run(const std::vector<std::string>& args, const std::string& stdin_file = "/dev/null") {
  const std::string out_file = in_tmp("stdout.txt"), err_file = in_tmp("stderr.txt");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, stdin_file.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const pid_t pid = hapticfield::testing::spawn_tool(HAPTICFIELD_TOOL_FEEL_SHAPE, args, actions);
  int raw = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  bool killed = false;
  while (waitpid(pid, &raw, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > give_up) {
      kill(pid, SIGKILL);
      waitpid(pid, &raw, 0);
      killed = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  Result r;
  if (!killed && WIFEXITED(raw)) r.status = WEXITSTATUS(raw);
  r.out = slurp(out_file);
  r.err = slurp(err_file);
  return r;
}

/// A binary STL of the mesh (no normals stored: zero facet normals).
std::string binary_stl(const hapticfield::TriangleMesh& m) {
  std::string s(80, ' ');
  const auto put32 = [&s](std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
      s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  };
  const auto putf = [&](double v) { put32(std::bit_cast<std::uint32_t>(static_cast<float>(v))); };
  put32(static_cast<std::uint32_t>(m.triangles.size()));
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k)
      putf(0.0);
    for (const std::uint32_t v : t)
      for (int k = 0; k < 3; ++k)
        putf(m.positions[v][k]);
    s.push_back('\0');
    s.push_back('\0');
  }
  return s;
}

/// A probe file: header and t,x,y,z rows, 1 ms apart.
std::string probe_csv(const std::vector<glm::dvec3>& path) {
  std::ostringstream s;
  s.precision(17);
  s << "t,x,y,z\n";
  for (std::size_t i = 0; i < path.size(); ++i)
    s << i * 1e-3 << ',' << path[i].x << ',' << path[i].y << ',' << path[i].z << '\n';
  return s.str();
}

/// One output row.
struct Row {
  double t{0};
  glm::dvec3 proxy{0.0}, f{0.0}, n{0.0};
  double u{0}, v{0};
  long long primitive{-1};
  int contact{0};
};

/// Parses the tool's output, checking the header and that every value is finite.
std::vector<Row> parse_rows(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  REQUIRE(std::getline(in, line));
  REQUIRE(line == "t,proxy_x,proxy_y,proxy_z,fx,fy,fz,nx,ny,nz,u,v,primitive,contact");
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::array<double, 14> c{};
    std::istringstream cells(line);
    std::string cell;
    for (double& x : c) {
      REQUIRE(std::getline(cells, cell, ','));
      x = std::strtod(cell.c_str(), nullptr);
      REQUIRE(std::isfinite(x));
    }
    rows.push_back(Row{c[0],
                       {c[1], c[2], c[3]},
                       {c[4], c[5], c[6]},
                       {c[7], c[8], c[9]},
                       c[10],
                       c[11],
                       static_cast<long long>(c[12]),
                       static_cast<int>(c[13])});
  }
  return rows;
}

/// A square of side `side` [m] at z = 0, two triangles facing +z.
std::string flat_plane_stl(double side) {
  hapticfield::TriangleMesh m;
  const double h = side / 2;
  m.positions = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return write(in_tmp("plane.stl"), binary_stl(m));
}

/// One error: the status, exactly one stderr line naming the tool.
void check_error(const std::vector<std::string>& args, int status, const std::string& says,
                 const std::string& stdin_file = "/dev/null") {
  std::string shown;
  for (const auto& a : args)
    shown += " '" + a + "'";
  CAPTURE(shown);
  const Result r = run(args, stdin_file);
  CAPTURE(r.err);
  CHECK(r.status == status);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.rfind("feel_shape: ", 0) == 0);
  CHECK(r.err.find(says) != std::string::npos);
  CHECK(r.err.find("terminate called") == std::string::npos);
}

fs::path shared_data() {
  if (const char* env = std::getenv("HAPTICFIELD_SHARED_DATA"); env && *env) return fs::path(env);
  const fs::path p = fs::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  return fs::is_directory(p) ? p : fs::path();
}

}  // namespace

TEST_CASE("feel_shape --help prints the usage on stdout and exits 0", "[feel_shape]") {
  for (const char* flag : {"--help", "-h"}) {
    const Result r = run({flag});
    CHECK(r.status == 0);
    CHECK(r.out.rfind("usage: feel_shape", 0) == 0);
    CHECK(r.out.find("--stiffness") != std::string::npos);
    CHECK(r.out.find("default 1500") != std::string::npos);
    CHECK(r.out.find("--radius R            the tool's radius [m], in [0, 0.05]") != std::string::npos);
    CHECK(r.err.empty());
  }
}

TEST_CASE("feel_shape: each bad input is one line on stderr and a non-zero exit", "[feel_shape][bad]") {
  const std::string plane = flat_plane_stl(0.2);
  const std::string good = write(in_tmp("good.csv"), "t,x,y,z\n0,0,0,0.01\n0.001,0,0,-0.001\n");
  const std::string bad_row = write(in_tmp("bad_row.csv"), "t,x,y,z\n0,0,0,0.01\n0.001,0,zero,-0.001\n");
  const std::string three = write(in_tmp("three.csv"), "t,x,y,z\n0,0,0,0.01\n0.001,0,0\n");
  const std::string nan_probe = write(in_tmp("nan.csv"), "t,x,y,z\n0,0,0,0.01\n0.001,nan,0,-0.001\n");
  const std::string inf_probe = write(in_tmp("inf.csv"), "t,x,y,z\n0,0,0,0.01\n0.001,0,0,-inf\n");
  const std::string backwards = write(in_tmp("backwards.csv"), "t,x,y,z\n0,0,0,0.01\n0.002,0,0,0\n0.001,0,0,0\n");
  const std::string repeated = write(in_tmp("repeated.csv"), "t,x,y,z\n0,0,0,0.01\n0,0,0,0\n");
  const std::string empty = write(in_tmp("empty.csv"), "t,x,y,z\n");
  // hostile meshes: a NaN vertex, a binary STL declaring a billion triangles in 84 bytes, not a mesh at all
  const std::string nan_mesh =
      write(in_tmp("nan.stl"),
            "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 nan\nvertex 0 1 0\nendloop\nendfacet\n"
            "endsolid x\n");
  std::string huge(80, ' ');
  huge += std::string("\x00\xCA\x9A\x3B", 4);  // 1e9 triangles
  const std::string huge_mesh = write(in_tmp("huge.stl"), huge);
  const std::string text_obj = write(in_tmp("text.obj"), "this is not an OBJ file\x01\x02\n");
  const std::string text_png = write(in_tmp("text.png"), "this is text, not a picture\n");
  cv::Mat gray8(20, 20, CV_8U, cv::Scalar(100));
  const std::string picture = in_tmp("gray.png");
  REQUIRE(cv::imwrite(picture, gray8));

  // bad input: status 1
  check_error({in_tmp("missing.stl"), "--probes", good}, 1, "missing.stl");
  check_error({nan_mesh, "--probes", good}, 1, "not finite");
  check_error({huge_mesh, "--probes", good}, 1, "huge.stl");
  check_error({text_obj, "--probes", good}, 1, "text.obj");
  check_error({text_png, "--probes", good}, 1, "text.png");
  check_error({in_tmp("mesh.ply"), "--probes", good, "--kind", "mesh"}, 1, "mesh.ply");
  check_error({picture, "--kind", "depth", "--probes", good}, 1, "8-bit");
  check_error({plane, "--probes", in_tmp("missing.csv")}, 1, "missing.csv");
  check_error({plane, "--probes", bad_row}, 1, "bad_row.csv:3");
  check_error({plane, "--probes", three}, 1, "three.csv:3");
  check_error({plane, "--probes", nan_probe}, 1, "finite");
  check_error({plane, "--probes", inf_probe}, 1, "finite");
  check_error({plane, "--probes", backwards}, 1, "increase");
  check_error({plane, "--probes", repeated}, 1, "increase");
  check_error({plane, "--probes", empty}, 1, "no t,x,y,z rows");
  check_error({plane, "--probes", "-"}, 1, "stdin", bad_row);
  check_error({plane, "--probes", good, "--forces", in_tmp("no/such/folder/out.csv")}, 1, "--forces");
  check_error({plane, "--probes", good, "--paths", in_tmp("no/such/folder/paths.csv")}, 1, "--paths");
  check_error({plane, "--probes", good, "--paths", tmp.string()}, 1, "it is a folder");
  // usage errors: status 2
  check_error({plane, "--probes", good, "--paths", "-"}, 2, "--paths needs a file");
  check_error({plane, "--probes", good, "--stiffness", "-1500"}, 2, "--stiffness");
  check_error({plane, "--probes", good, "--stiffness", "nan"}, 2, "--stiffness");
  check_error({plane, "--probes", good, "--stiffness", "0"}, 2, "--stiffness");
  check_error({plane, "--probes", good, "--damping", "-1"}, 2, "--damping");
  check_error({plane, "--probes", good, "--friction", "0.2,0.5"}, 2, "--friction");
  check_error({plane, "--probes", good, "--friction", "-0.1"}, 2, "--friction");
  check_error({plane, "--probes", good, "--scale", "0"}, 2, "--scale");
  check_error({plane, "--probes", good, "--spacing", "1e-3"}, 2, "height maps");
  check_error({picture, "--probes", good, "--scale", "0.001"}, 2, "--scale");
  check_error({picture, "--probes", good, "--spacing", "-1"}, 2, "--spacing");
  check_error({picture, "--probes", good, "--height-scale", "inf"}, 2, "--height-scale");
  check_error({plane, "--probes", good, "--kind", "cloud"}, 2, "--kind");
  check_error({plane, "--probes", good, "--bogus"}, 2, "--bogus");
  check_error({plane, "--probes"}, 2, "--probes needs a value");
  check_error({plane}, 2, "no --probes");
  check_error({"--probes", good}, 2, "no SHAPE");
  check_error({plane, plane, "--probes", good}, 2, "more than one SHAPE");
  check_error({plane, "--probes", good, "--smooth", "--facets"}, 2, "one shading");
  check_error({picture, "--probes", good, "--facets"}, 2, "--facets is for meshes");
  check_error({plane, "--probes", good, "--rotate", "0,0,1"}, 2, "--rotate expects AX,AY,AZ,DEG");
  check_error({plane, "--probes", good, "--rotate", "0,0,0,90"}, 2, "axis must not be zero");
  check_error({plane, "--probes", good, "--rotate", "0,0,1,nan"}, 2, "--rotate");
  check_error({plane, "--probes", good, "--translate", "1,2"}, 2, "--translate expects X,Y,Z");
  check_error({plane, "--probes", good, "--translate", "1,2,3,4"}, 2, "--translate expects X,Y,Z");
  check_error({plane, "--probes", good, "--translate", "0,inf,0"}, 2, "--translate");
  // the tool's radius: metres in [0, 0.05]
  check_error({plane, "--probes", good, "--radius", "-0.001"}, 2, "--radius must be in [0, 0.05]");
  check_error({plane, "--probes", good, "--radius", "0.051"}, 2, "--radius must be in [0, 0.05]");
  check_error({plane, "--probes", good, "--radius", "2"}, 2, "--radius must be in [0, 0.05]");
  check_error({plane, "--probes", good, "--radius", "nan"}, 2, "--radius");
  check_error({plane, "--probes", good, "--radius", "2mm"}, 2, "--radius");
  check_error({plane, "--probes", good, "--radius"}, 2, "--radius needs a value");
  // a mesh with nothing to touch: every triangle without area
  const std::string flat = write(in_tmp("degenerate.stl"),
                                 "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 2 0 0\n"
                                 "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\n"
                                 "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n");
  check_error({flat, "--probes", good}, 1, "all 2 triangles have zero area");
  check_error({write(in_tmp("empty.obj"), "# nothing\nv 0 0 0\n"), "--probes", good}, 1, "empty.obj");
}

TEST_CASE(
    "feel_shape --rotate --translate: a placed plane pushes along its turned normal with k depth, its box "
    "on stderr",
    "[feel_shape]") {
  const std::string plane = flat_plane_stl(0.2);
  // the plane z = 0 (normal +z) turned 90 degrees about x: normal -y; then moved to y = 0.05
  const glm::dvec3 n{0.0, -1.0, 0.0};
  const glm::dvec3 on{0.01, 0.05, 0.02};
  std::vector<glm::dvec3> path{on + 0.01 * n};
  for (int i = 1; i <= 20; ++i)
    path.push_back(on - (1e-4 * i) * n);
  const std::string probes = write(in_tmp("turned.csv"), probe_csv(path));
  const Result r =
      run({plane, "--probes", probes, "--stiffness", "800", "--rotate", "1,0,0,90", "--translate", "0,0.05,0"});
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.find("x [-0.1, 0.1] y [0.05, 0.05] z [-0.1, 0.1] m") != std::string::npos);
  const std::vector<Row> rows = parse_rows(r.out);
  REQUIRE(rows.size() == path.size());
  CHECK(rows[0].contact == 0);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    INFO("probe " << i);
    REQUIRE(rows[i].contact == 1);
    const glm::dvec3 expected = 800.0 * (1e-4 * static_cast<double>(i)) * n;
    CHECK(glm::length(rows[i].f - expected) < 1e-6);
    CHECK(glm::length(rows[i].n - n) < 1e-9);
    CHECK_THAT(rows[i].proxy.y, WithinAbs(0.05, 1e-6));
  }
}

TEST_CASE("feel_shape prints every mesh warning on stderr, saying what the surface does", "[feel_shape]") {
  // an OBJ without normals and with a triangle of zero area
  const std::string obj = write(in_tmp("warned.obj"), "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0.2 0 0\nf 1 2 3\nf 1 2 4\n");
  const std::string probes =
      write(in_tmp("warned.csv"), probe_csv({{0.02, 0.02, 0.01}, {0.02, 0.02, -0.001}, {0.021, 0.02, -0.002}}));
  for (const bool facets : {false, true}) {
    std::vector<std::string> args{obj, "--probes", probes};
    if (facets) args.push_back("--facets");
    const Result r = run(args);
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.find("mesh of 2 triangles (1 with an area)") != std::string::npos);
    CHECK(r.err.find("warning: 1 of 2 triangles have zero area") != std::string::npos);
    CHECK(r.err.find(facets ? "warning: no vertex normals in the file: the surface uses face normals"
                            : "warning: no vertex normals in the file: computed from the faces") != std::string::npos);
    CHECK(r.err.find(facets ? "normals: face normals" : "normals: vertex normals from the faces") != std::string::npos);
    const std::vector<Row> rows = parse_rows(r.out);
    REQUIRE(rows.size() == 3);
    CHECK_THAT(rows[2].f.z, WithinAbs(1500.0 * 0.002, 1e-6));
  }
}

TEST_CASE("feel_shape: probes pressing into a flat STL plane give F = k depth along +z, the proxy on the plane",
          "[feel_shape]") {
  const std::string plane = flat_plane_stl(0.2);
  std::vector<glm::dvec3> path{{0.01, -0.02, 0.01}};
  for (int i = 1; i <= 50; ++i)
    path.push_back({0.01 + 2e-4 * i, -0.02 + 1e-4 * i, -1e-4 * i});  // 0.1 .. 5 mm deep, sliding
  const std::string probes = write(in_tmp("press.csv"), probe_csv(path));
  const double k = 800.0;
  const Result r = run({plane, "--probes", probes, "--stiffness", "800"});
  INFO(r.err);
  REQUIRE(r.status == 0);
  // stderr tells the shape and its box in metres, one line (an STL has no normals to warn about)
  CHECK(r.err == "feel_shape: " + plane +
                     ": mesh of 2 triangles, x [-0.1, 0.1] y [-0.1, 0.1] z [0, 0] m, normals: vertex normals from "
                     "the faces (force shading)\n");
  const std::vector<Row> rows = parse_rows(r.out);
  REQUIRE(rows.size() == path.size());
  CHECK(rows[0].contact == 0);
  CHECK(rows[0].primitive == -1);
  CHECK(rows[0].f == glm::dvec3{0.0});
  for (std::size_t i = 1; i < rows.size(); ++i) {
    INFO("probe " << i);
    const Row& row = rows[i];
    const double depth = -path[i].z;
    CHECK(row.contact == 1);
    CHECK((row.primitive == 0 || row.primitive == 1));
    CHECK_THAT(row.t, WithinAbs(i * 1e-3, 1e-15));
    CHECK_THAT(row.f.z, WithinAbs(k * depth, 1e-6));
    CHECK_THAT(row.f.x, WithinAbs(0.0, 1e-9));
    CHECK_THAT(row.f.y, WithinAbs(0.0, 1e-9));
    CHECK_THAT(row.proxy.z, WithinAbs(0.0, 1e-6));  // on the plane (lifted by its tiny offset)
    CHECK_THAT(row.proxy.x, WithinAbs(path[i].x, 1e-9));
    CHECK_THAT(row.proxy.y, WithinAbs(path[i].y, 1e-9));
    CHECK(row.n == glm::dvec3{0.0, 0.0, 1.0});
  }
  // the same path from stdin to a file: the same numbers
  const std::string out = in_tmp("press_out.csv");
  const Result piped = run({plane, "--probes", "-", "--forces", out, "--stiffness", "800"}, probes);
  REQUIRE(piped.status == 0);
  CHECK(slurp(out) == r.out);
  CHECK(piped.out.find("51 probes, 50 touching") != std::string::npos);

  // with friction mu_s = 0.5, mu_k = 0.4 the tangential force stays inside the cone
  const Result rubbed = run({plane, "--probes", probes, "--stiffness", "800", "--friction", "0.5,0.4"});
  REQUIRE(rubbed.status == 0);
  int sliding = 0;
  for (const Row& row : parse_rows(rubbed.out)) {
    const double ft = std::hypot(row.f.x, row.f.y);
    CHECK(ft <= 0.5 * row.f.z + 1e-9);
    sliding += ft > 0.39 * row.f.z;
  }
  CHECK(sliding > 10);
}

TEST_CASE("feel_shape --radius: a ball pressed into a flat STL rests R above it, F = k (R - the HIP's height)",
          "[feel_shape][radius]") {
  const std::string plane = flat_plane_stl(0.2);
  const double k = 800.0;
  for (const double radius : {0.0005, 0.002, 0.005}) {
    INFO("--radius " << radius);
    // free from 10 mm, then from 0.5 mm above the ball's touch down to 2 mm below the plane, sliding
    std::vector<glm::dvec3> path{{0.01, -0.02, 0.01}};
    for (int i = 1; i <= 40; ++i)
      path.push_back({0.01 + 2e-4 * i, -0.02 + 1e-4 * i, radius + 5e-4 - (radius + 2.5e-3) * i / 40.0});
    const std::string probes = write(in_tmp("ball.csv"), probe_csv(path));
    char text[32];
    std::snprintf(text, sizeof text, "%g", radius);
    const Result r = run({plane, "--probes", probes, "--stiffness", "800", "--radius", text});
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.find("tool: a ball of radius " + std::string(text) + " m") != std::string::npos);
    const std::vector<Row> rows = parse_rows(r.out);
    REQUIRE(rows.size() == path.size());
    int touching = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      INFO("probe " << i << " at z = " << path[i].z);
      const Row& row = rows[i];
      if (path[i].z > radius + 1e-6) {  // the ball's lowest point above the plane: free, the proxy at the HIP
        CHECK(row.contact == 0);
        CHECK(row.f == glm::dvec3{0.0});
        CHECK(glm::length(row.proxy - path[i]) < 1e-12);
        continue;
      }
      if (path[i].z > radius - 1e-6) continue;  // within the proxy's lift of the touch
      ++touching;
      CHECK(row.contact == 1);
      CHECK_THAT(row.f.z, WithinAbs(k * (radius - path[i].z), 1e-6));
      CHECK_THAT(row.f.x, WithinAbs(0.0, 1e-9));
      CHECK_THAT(row.f.y, WithinAbs(0.0, 1e-9));
      CHECK_THAT(row.proxy.z, WithinAbs(radius, 1e-6));  // the ball's centre, R above the plane
      CHECK_THAT(row.proxy.x, WithinAbs(path[i].x, 1e-9));
      CHECK_THAT(row.proxy.y, WithinAbs(path[i].y, 1e-9));
      CHECK(row.n == glm::dvec3{0.0, 0.0, 1.0});
    }
    CHECK(touching > 30);
  }
  // --radius 0 is the point proxy: the same output as without it
  const std::string probes = write(in_tmp("ball0.csv"), probe_csv({{0.0, 0.0, 0.01}, {0.001, 0.0, -0.001}}));
  const Result point = run({plane, "--probes", probes});
  const Result zero = run({plane, "--probes", probes, "--radius", "0"});
  REQUIRE(point.status == 0);
  CHECK(zero.out == point.out);
  CHECK(zero.err == point.err);
}

TEST_CASE("feel_shape: a probe path into an icosphere STL gives a force along the radius, k depth", "[feel_shape]") {
  const double radius = 0.03, k = 1000.0;
  const std::string sphere = write(in_tmp("sphere.stl"), binary_stl(hapticfield::test::icosphere(5, radius)));
  // into the ball along 20 directions, 1 mm deep, out to 3 R between them
  std::vector<glm::dvec3> path;
  std::vector<glm::dvec3> directions;
  for (int i = 0; i < 20; ++i) {
    const double a = 0.7 * i, z = -0.9 + 1.8 * i / 19.0;
    const glm::dvec3 d =
        glm::normalize(glm::dvec3{std::cos(a) * std::sqrt(1 - z * z), std::sin(a) * std::sqrt(1 - z * z), z});
    path.push_back(3.0 * radius * d);
    path.push_back((radius + 0.002) * d);
    path.push_back((radius - 0.001) * d);
    directions.push_back(d);
  }
  const std::string probes = write(in_tmp("sphere.csv"), probe_csv(path));
  for (const bool smooth : {false, true}) {
    INFO((smooth ? "force shading (the default)" : "--facets"));
    std::vector<std::string> args{sphere, "--probes", probes, "--stiffness", "1000"};
    if (!smooth) args.push_back("--facets");
    const Result r = run(args);
    INFO(r.err);
    REQUIRE(r.status == 0);
    const std::vector<Row> rows = parse_rows(r.out);
    REQUIRE(rows.size() == path.size());
    double worst_degrees = 0.0;
    for (std::size_t i = 0; i < directions.size(); ++i) {
      INFO("direction " << i);
      CHECK(rows[3 * i].contact == 0);
      CHECK(rows[3 * i + 1].contact == 0);
      const Row& in = rows[3 * i + 2];
      REQUIRE(in.contact == 1);
      const double cosine = glm::dot(glm::normalize(in.f), directions[i]);
      worst_degrees = std::max(worst_degrees, std::acos(std::min(1.0, cosine)) * 180.0 / M_PI);
      // the facets lie within their sagitta (6 um: 2 degree edges) inside the ball
      CHECK_THAT(glm::length(in.f), WithinAbs(k * 0.001, k * 8e-6));
      CHECK_THAT(glm::length(in.proxy), WithinAbs(radius, 8e-6));
    }
    // a facet's normal is within its circumradius angle (1.2 degrees measured) of the radius; force shading
    // turns the force onto the radius (0.11 degrees measured)
    INFO("worst angle to the radius " << worst_degrees << " degrees");
    CHECK(worst_degrees < (smooth ? 0.2 : 1.5));
  }
}

TEST_CASE(
    "feel_shape --paths: each tick's path starts where the last one stayed, ends on the proxy and passes "
    "through no face",
    "[feel_shape]") {
  // a slab 0.3 mm thick and 20 mm wide, pressed into 1 mm deep (through it) and slid off each of its four edges at
  // 2 mm a tick with friction: the proxy goes round the rims in long one-tick moves of several pieces
  hapticfield::TriangleMesh slab = hapticfield::test::box({-0.01, -0.01, -0.00015}, {0.01, 0.01, 0.00015});
  for (glm::dvec3& p : slab.positions)  // as the STL holds them
    p = glm::dvec3(glm::vec3(p));
  const std::string mesh = write(in_tmp("slab.stl"), binary_stl(slab));
  std::vector<glm::dvec3> path;
  const std::array<glm::dvec3, 4> headings{{{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -0.8, -0.6}}};
  for (const glm::dvec3& heading : headings) {
    const glm::dvec3 start{0.002, -0.001, 0.003};
    for (int i = 0; i <= 20; ++i)
      path.push_back(start + (i / 20.0) * glm::dvec3{0, 0, -0.004});
    for (int i = 1; i <= 12; ++i)
      path.push_back(path.back() + 0.002 * heading);
    for (int i = 1; i <= 10; ++i)
      path.push_back(path.back() + glm::dvec3{0, 0, 0.001});
  }
  const std::string probes = write(in_tmp("slab.csv"), probe_csv(path));
  const std::string paths = in_tmp("slab_paths.csv");
  const Result r = run({mesh, "--probes", probes, "--paths", paths, "--friction", "0.4,0.3"});
  INFO(r.err);
  REQUIRE(r.status == 0);
  const std::vector<Row> rows = parse_rows(r.out);
  REQUIRE(rows.size() == path.size());
  // t,point,x,y,z: the ticks' points in order
  std::istringstream in(slurp(paths));
  std::string line;
  REQUIRE(std::getline(in, line));
  REQUIRE(line == "t,point,x,y,z");
  std::vector<std::vector<glm::dvec3>> ticks(rows.size());
  std::size_t tick = 0;
  while (std::getline(in, line)) {
    double t = 0.0, x = 0.0, y = 0.0, z = 0.0;
    int point = -1;
    REQUIRE(std::sscanf(line.c_str(), "%lf,%d,%lf,%lf,%lf", &t, &point, &x, &y, &z) == 5);
    if (point == 0 && !ticks[tick].empty()) ++tick;
    REQUIRE(tick < rows.size());
    REQUIRE(t == Approx(rows[tick].t).margin(1e-12));
    REQUIRE(point == static_cast<int>(ticks[tick].size()));
    ticks[tick].push_back({x, y, z});
  }
  REQUIRE(tick + 1 == rows.size());
  const hapticfield::MeshChecker checker(slab);
  std::size_t pieces = 0, long_moves = 0;
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    INFO("tick " << i);
    REQUIRE(!ticks[i].empty());
    // the forces file rounds the proxy to 12 digits
    CHECK(glm::length(ticks[i].back() - rows[i].proxy) < 1e-12);
    if (i > 0) CHECK(glm::length(ticks[i].front() - rows[i - 1].proxy) < 1e-12);
    for (std::size_t q = 0; q + 1 < ticks[i].size(); ++q) {
      ++pieces;
      const hapticfield::PathCrossing c = checker.crossing(ticks[i][q], ticks[i][q + 1]);
      INFO("piece " << q << " crosses triangle " << c.triangle);
      CHECK(!c.found());
    }
    if (ticks[i].size() > 3 && glm::length(ticks[i].back() - ticks[i].front()) > 5e-4) ++long_moves;
  }
  CHECK(pieces > rows.size());
  CHECK(long_moves >= 4);  // round each rim
}

TEST_CASE("feel_shape: a flat picture and a 16-bit depth map give F = k (height - z) above their footprint",
          "[feel_shape]") {
  cv::Mat gray8(30, 40, CV_8U, cv::Scalar(120));
  const std::string picture = in_tmp("flat120.png");
  REQUIRE(cv::imwrite(picture, gray8));
  cv::Mat depth16(30, 40, CV_16U, cv::Scalar(5000));
  const std::string depth = in_tmp("flat5000.png");
  REQUIRE(cv::imwrite(depth, depth16));
  // picture: 120 levels x 0.02 mm = 2.4 mm; depth: 5000 x 1 um = 5 mm; 1 mm pitch: 39 x 29 mm
  struct Case {
    std::string file;
    std::vector<std::string> flags;
    double height;
  };
  for (const Case& c : {Case{picture, {"--height-scale", "0.02", "--spacing", "1e-3"}, 0.0024},
                        Case{depth, {"--spacing", "1e-3"}, 0.005}}) {
    INFO(c.file);
    const std::vector<glm::dvec3> path{
        {0.02, 0.015, 0.02}, {0.02, 0.015, c.height - 0.001}, {0.021, 0.016, c.height - 0.002}};
    const std::string probes = write(in_tmp("flat.csv"), probe_csv(path));
    std::vector<std::string> args{c.file, "--probes", probes, "--stiffness", "1200"};
    args.insert(args.end(), c.flags.begin(), c.flags.end());
    const Result r = run(args);
    INFO(r.err);
    REQUIRE(r.status == 0);
    const std::vector<Row> rows = parse_rows(r.out);
    REQUIRE(rows.size() == 3);
    CHECK(rows[0].contact == 0);
    for (int i : {1, 2}) {
      CHECK(rows[static_cast<std::size_t>(i)].contact == 1);
      CHECK_THAT(rows[static_cast<std::size_t>(i)].f.z, WithinAbs(1200.0 * 0.001 * i, 1e-6));
      CHECK_THAT(rows[static_cast<std::size_t>(i)].proxy.z, WithinAbs(c.height, 1e-6));
      // uv runs 0..1 over the footprint (39 x 29 mm)
      CHECK_THAT(rows[static_cast<std::size_t>(i)].u, WithinAbs(path[static_cast<std::size_t>(i)].x / 0.039, 1e-6));
    }
    // a 3 mm ball on the same map rests 3 mm above it: F = k (height + r - z)
    args.insert(args.end(), {"--radius", "0.003"});
    const Result ball = run(args);
    INFO(ball.err);
    REQUIRE(ball.status == 0);
    const std::vector<Row> balls = parse_rows(ball.out);
    REQUIRE(balls.size() == 3);
    for (int i : {1, 2}) {
      CHECK(balls[static_cast<std::size_t>(i)].contact == 1);
      CHECK_THAT(balls[static_cast<std::size_t>(i)].f.z, WithinAbs(1200.0 * (0.003 + 0.001 * i), 1e-6));
      CHECK_THAT(balls[static_cast<std::size_t>(i)].proxy.z, WithinAbs(c.height + 0.003, 1e-6));
    }
  }
}

TEST_CASE("feel_shape: real meshes run end to end with finite output", "[feel_shape][real]") {
  const fs::path shared = shared_data();
  if (shared.empty()) {
    WARN("the shared data folder is absent: real meshes skipped");
    return;
  }
  int felt = 0;
  for (const char* name : {"meshes/stanford-bunny.obj", "meshes/spot.obj", "meshes/fandisk.obj", "gltf/Duck.gltf"}) {
    const fs::path file = shared / name;
    if (!fs::exists(file)) continue;
    INFO(name);
    // the vertices' bounds, read here from the file's 'v' lines (OBJ) or
    // taken wide (glTF): a vertical descent through the middle
    glm::dvec3 lo{1e300}, hi{-1e300};
    if (file.extension() == ".obj") {
      std::istringstream in(slurp(file));
      std::string line;
      while (std::getline(in, line))
        if (line.rfind("v ", 0) == 0) {
          std::istringstream v(line.substr(2));
          glm::dvec3 p;
          v >> p.x >> p.y >> p.z;
          lo = glm::min(lo, p);
          hi = glm::max(hi, p);
        }
    } else {
      lo = glm::dvec3{-2.0};
      hi = glm::dvec3{2.0};
    }
    REQUIRE(lo.x < hi.x);
    const glm::dvec3 mid = 0.5 * (lo + hi);
    std::vector<glm::dvec3> path;
    for (int i = 0; i <= 400; ++i)
      path.push_back({mid.x, mid.y, hi.z + 0.1 * (hi.z - lo.z) - i * 0.6 * (hi.z - lo.z) / 400.0});
    const std::string probes = write(in_tmp("real.csv"), probe_csv(path));
    const Result r = run({file.string(), "--probes", probes, "--stiffness", "1000"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    const std::vector<Row> rows = parse_rows(r.out);  // every value finite
    REQUIRE(rows.size() == path.size());
    int touching = 0;
    for (const Row& row : rows) {
      touching += row.contact;
      if (row.contact) {
        CHECK(row.primitive >= 0);
        CHECK_THAT(glm::length(row.n), WithinAbs(1.0, 1e-9));
        CHECK(glm::length(row.f) <= 1000.0 * (hi.z - lo.z) + 1e-9);  // never more than k x the mesh's height
      }
    }
    if (file.extension() == ".obj") CHECK(touching > 0);  // the descent through the bounds' middle meets it
    ++felt;
  }
  if (felt == 0) WARN("no real mesh found under " << shared.string());
}

TEST_CASE("feel_shape --feel-texture: a glTF model felt with its base-colour texture; no texture is one error",
          "[feel_shape][texture]") {
  check_error({flat_plane_stl(0.1), "--probes", "-", "--feel-texture"}, 1, "has no base-colour texture");
  const fs::path shared = shared_data();
  const fs::path duck = shared.empty() ? fs::path() : shared / "gltf" / "Duck.gltf";
  if (duck.empty() || !fs::exists(duck)) {
    WARN("the shared data folder is absent: the textured Duck skipped");
    return;
  }
  std::vector<glm::dvec3> path;
  for (int i = 0; i <= 400; ++i)  // down onto the Duck's back and along it
    path.push_back({0.2 + 0.001 * i, 2.0 - 0.005 * std::min(i, 240), 0.0});
  const std::string probes = write(in_tmp("duck.csv"), probe_csv(path));
  const Result plain = run({duck.string(), "--probes", probes, "--stiffness", "1000"});
  const Result textured = run({duck.string(), "--probes", probes, "--stiffness", "1000", "--feel-texture"});
  INFO(textured.err);
  REQUIRE(plain.status == 0);
  REQUIRE(textured.status == 0);
  CHECK(textured.err.find("texture: 512 x 512 px felt by uv") != std::string::npos);
  const std::vector<Row> a = parse_rows(plain.out), b = parse_rows(textured.out);
  REQUIRE(a.size() == path.size());
  REQUIRE(b.size() == path.size());
  int touching = 0;
  for (const Row& row : b)
    touching += row.contact;
  CHECK(touching > 0);
  // --relief-mm: the picture's gray levels as a relief on top: the forces differ from the texture alone where pressed
  check_error({duck.string(), "--probes", probes, "--relief-mm", "0.5"}, 2, "--relief-mm needs --feel-texture");
  const Result relief =
      run({duck.string(), "--probes", probes, "--stiffness", "1000", "--feel-texture", "--relief-mm", "0.5"});
  INFO(relief.err);
  REQUIRE(relief.status == 0);
  CHECK(relief.err.find("relief: the texture's gray levels, white 0.5 mm up") != std::string::npos);
  const std::vector<Row> c = parse_rows(relief.out);
  REQUIRE(c.size() == path.size());
  int differ = 0;
  for (std::size_t i = 0; i < c.size(); ++i)
    differ += c[i].contact && glm::length(c[i].f - b[i].f) > 1e-6;
  CHECK(differ > 0);
}
