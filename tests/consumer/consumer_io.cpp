// A mesh-file user: writes a one-triangle OBJ, an STL and a glTF, reads
// them back through the installed io part (tinygltf, tinyobjloader) and
// checks the triangle's area.
#include <hapticfield/io.hpp>

#include <cstdio>
#include <fstream>
#include <string>

int main(int argc, char** argv) {
  namespace hio = hapticfield::io;
  if (argc != 2) return 2;
  const std::string dir = argv[1];
  std::ofstream(dir + "/tri.obj") << "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n";
  std::ofstream(dir + "/tri.stl") << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 2 0 0\n"
                                     "vertex 0 2 0\nendloop\nendfacet\nendsolid t\n";
  // the same triangle in glTF: 3 float positions, base64
  std::ofstream(dir + "/tri.gltf")
      << R"({"asset": {"version": "2.0"}, "nodes": [{"mesh": 0}],)"
      << R"("meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],)"
      << R"("buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,)"
      << R"(AAAAAAAAAAAAAAAAAAAAQAAAAAAAAAAAAAAAAAAAAEAAAAAA"}],)"
      << R"("bufferViews": [{"buffer": 0, "byteLength": 36}],)"
      << R"("accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}]})";
  hio::MeshReadConfig config;
  config.scale = 0.01;  // the files are in centimetres
  int good = 0;
  for (const char* name : {"tri.obj", "tri.stl", "tri.gltf"}) {
    const hio::LoadedMesh m = hio::load_mesh(dir + "/" + name, config);
    const auto& p = m.mesh.positions;
    const auto& t = m.mesh.triangles.at(0);
    const double area = 0.5 * glm::length(glm::cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]));  // [m^2]
    std::printf("consumer_io: %s, %zu triangle, area %.6f m^2\n", name, m.mesh.triangle_count(), area);
    if (m.mesh.triangle_count() == 1 && area > 0.000199 && area < 0.000201) ++good;
  }
  return good == 3 ? 0 : 1;
}
