// bench_view3d: frame time of the 3D view's software renderer
// (tools/view/mesh_render.hpp) at 800 x 600 px on UV spheres of 20k to
// 1.3M triangles, drawn in full and through the display budget (vertex
// clustering), and on the real meshes of ../shared/data/meshes when
// present. Each frame turns the camera a little (as a live view does).
// Prints the median and worst frame [ms] and the CPU time of the
// decimation [ms]. Speed is measured here, never asserted.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "../tests/view/uv_sphere.hpp"
#include "hapticfield/io/obj.hpp"
#include "view/display_mesh.hpp"
#include "view/mesh_render.hpp"
#include "view/scene3d.hpp"

using namespace hapticfield;
using namespace hapticfield::view;
using clock_type = std::chrono::steady_clock;

namespace {

double ms_since(clock_type::time_point t0) {
  return std::chrono::duration<double, std::milli>(clock_type::now() - t0).count();
}

void frames(const char* name, const TriangleMesh& mesh, std::size_t budget) {
  const auto t0 = clock_type::now();
  const DisplayMesh display = display_mesh(mesh, glm::dvec3{0.0}, budget);
  const double build_ms = ms_since(t0);
  glm::vec3 centre = 0.5f * (display.lo + display.hi);
  const double radius = 0.5 * glm::length(glm::dvec3(display.hi - display.lo));
  OrbitCamera camera;
  camera.frame(glm::dvec3(centre), radius);
  camera.pitch = 0.5;
  RenderTarget target;
  std::vector<double> times;
  Sample3d now;
  now.hip = now.proxy = glm::dvec3(centre);
  std::size_t drawn = 0;
  for (int k = 0; k < 40; ++k) {
    camera.yaw = 0.05 * k;
    const auto t = clock_type::now();
    drawn = draw_scene3d(target, display, camera, now).stats.drawn;
    times.push_back(ms_since(t));
  }
  std::sort(times.begin(), times.end());
  std::printf("%-28s %9zu %9zu %9zu %8.1f %8.1f %8.1f\n", name, mesh.triangles.size(), display.triangles.size(), drawn,
              times[times.size() / 2], times.back(), build_ms);
}

}  // namespace

int main() {
  std::printf("frames of 800 x 600 px (median and worst of 40) [ms]; 'build' is the display mesh (decimation) [ms]\n");
  std::printf("%-28s %9s %9s %9s %8s %8s %8s\n", "mesh", "triangles", "shown", "drawn", "median", "worst", "build");
  for (const auto& [slices, stacks] : {std::pair{100, 100}, {224, 224}, {500, 500}, {800, 800}}) {
    const TriangleMesh sphere = test::uv_sphere(0.05, slices, stacks);
    char name[64];
    std::snprintf(name, sizeof name, "sphere %dx%d, full", slices, stacks);
    frames(name, sphere, sphere.triangles.size());
    if (sphere.triangles.size() > default_display_triangles) {
      std::snprintf(name, sizeof name, "sphere %dx%d, budget", slices, stacks);
      frames(name, sphere, default_display_triangles);
    }
  }
  const std::filesystem::path data =
      std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data" / "meshes";
  for (const char* file : {"stanford-bunny.obj", "rocker-arm.obj", "fandisk.obj"}) {
    const auto path = data / file;
    if (!std::filesystem::exists(path)) {
      std::printf("%-28s (absent: %s)\n", file, path.string().c_str());
      continue;
    }
    const TriangleMesh mesh = io::load_obj(path.string()).mesh;
    frames(file, mesh, mesh.triangles.size());
  }
  return 0;
}
