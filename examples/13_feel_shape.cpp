// feel_shape: feel a shape off-line. A probe path goes in, the proxy's
// (god-object's) forces come out, tick by tick, as a servo loop would feel
// them.
//
//   feel_shape SHAPE --probes IN.csv [--forces OUT.csv] [--paths PATHS.csv] [--stiffness K]
//              [--damping B] [--friction MU_S[,MU_K]] [--radius R] [--scale S] [--facets]
//              [--rotate AX,AY,AZ,DEG] [--translate X,Y,Z]
//              [--kind mesh|picture|depth] [--height-scale H] [--spacing S]
//
// SHAPE is a mesh (.stl, .obj, .gltf, .glb) or a height map: a picture
// whose gray level is height, or a 16-bit / float depth map, placed by
// --rotate (about the shape's own origin) and then --translate. IN.csv holds
// t,x,y,z per line (seconds, metres, the world frame: the placed shape's;
// a header line allowed; '-' reads stdin), t strictly increasing; the HIP velocity is the
// backward difference of the path. OUT.csv ('-' or no --forces: stdout)
// gets one line per probe:
//   t,proxy_x,proxy_y,proxy_z,fx,fy,fz,nx,ny,nz,u,v,primitive,contact
// the proxy [m], the force on the HIP [N], the contact normal, the touched
// point's uv, its triangle or grid cell (-1: none) and 1 while touching.
// --paths PATHS.csv gets the way the proxy went in each tick, t,point,x,y,z:
// point 0 where it started, then the end of each straight piece (every
// piece swept against the shape), the last where it stays.
// --radius R [m] makes the tool a ball of radius R centred on the HIP (the
// proxy is its centre, resting R above a face; a height map's cells are two
// flat triangles each for a ball).
// Before the forces, stderr tells the shape's box once placed [m], the
// normals the proxy pushes along and each warning of the mesh reader.
// Meshes are force-shaded by default (the file's vertex normals, else
// normals from the faces: io/mesh_shading.hpp, the default of every tool
// and of Python); --facets feels the bare triangles. --feel-texture lays a
// glTF mesh's base-colour texture on it by uv as a tangible-image texture
// (scenes/model_texture.hpp), at the size the mesh's uvs give it; with
// --relief-mm H its gray levels are also a relief, white H mm up
// (scenes/model_relief.hpp).
// Bad input: one line on stderr and exit status 1 (2 for usage errors).
#include <hapticfield/io.hpp>
#include <hapticfield/io/mesh_shading.hpp>
#include <hapticfield/scenes/model_relief.hpp>
#include <hapticfield/scenes/model_texture.hpp>
#include <hapticfield/surface.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <opencv2/core/utils/logger.hpp>

#include "common/cli.hpp"
#include "common/csv.hpp"

namespace hf = hapticfield;

namespace {

constexpr const char* usage =
    "usage: feel_shape SHAPE --probes IN.csv [options]\n"
    "Feels a shape off-line: the proxy (god-object) follows a probe path and\n"
    "its forces are written tick by tick.\n"
    "  SHAPE                 a mesh (.stl, .obj, .gltf, .glb) or a height map: a picture\n"
    "                        (gray level = height) or a 16-bit / float depth map\n"
    "  --probes IN.csv       t,x,y,z per line [s, m] in the world frame (the shape placed by\n"
    "                        --rotate and --translate), t strictly increasing (a header\n"
    "                        line allowed); '-' reads stdin (required)\n"
    "  --forces OUT.csv      where the forces go; '-' (default) is stdout. Columns:\n"
    "                        t,proxy_x,proxy_y,proxy_z,fx,fy,fz,nx,ny,nz,u,v,primitive,contact\n"
    "                        [s, m, N, -]; primitive -1 and contact 0 when not touching\n"
    "  --paths PATHS.csv     the way the proxy went in each tick: t,point,x,y,z [s, -, m], point 0\n"
    "                        where it started, then the end of each straight piece (each one\n"
    "                        swept against the shape), the last where it stays; a file, not '-'\n"
    "  --stiffness K         proxy spring [N/m], in (0, 1e6] (default 1500)\n"
    "  --damping B           on the normal velocity while touching [N s/m], in [0, 1e4] (default 0)\n"
    "  --friction MU         static and dynamic friction [-], MU_S,MU_K or one value for both,\n"
    "                        0 <= MU_K <= MU_S <= 10 (default 0: frictionless)\n"
    "  --radius R            the tool's radius [m], in [0, 0.05] (default 0: a point); > 0 a ball\n"
    "                        centred on the HIP: the proxy columns are its centre, R above a face\n"
    "                        (a height map's cells are two flat triangles each for a ball)\n"
    "  --scale S             a mesh file's unit in metres, in (0, 1e6] (default 1; 0.001 for mm)\n"
    "  --facets              a mesh is felt by its face normals (flat facets); default: force\n"
    "                        shading with the file's vertex normals, else normals from the faces\n"
    "  --smooth              the default shading, named (kept for scripts)\n"
    "  --rotate AX,AY,AZ,DEG turn the shape by DEG degrees about the axis (AX,AY,AZ) through its\n"
    "                        own origin, right-handed (default: none)\n"
    "  --translate X,Y,Z     then move it by (X,Y,Z) [m] (default 0,0,0)\n"
    "  --kind K              mesh, picture or depth (default: mesh by extension; a one-channel\n"
    "                        16-bit or float image is a depth map, any other picture a picture)\n"
    "  --height-scale H      picture: height of one gray level [mm] (default 0.01);\n"
    "                        depth map: metres per unit (default 1e-6), in (0, 1e6]\n"
    "  --spacing S           height map: distance between pixel centres [m], in (0, 1e3] (default 1e-4)\n"
    "  --feel-texture        a glTF mesh's base-colour texture felt as a tangible-image texture\n"
    "                        laid by uv (its pixel size from the mesh's uvs; 0.5 N at an edge)\n"
    "  --relief-mm H         with --feel-texture: its gray levels also as a relief, white H mm up, in (0, 10]\n"
    "  -h, --help            this text\n"
    "Height maps: pixel (column c, row r) of a W x H map is at x = c S, y = (H - 1 - r) S,\n"
    "z = its height; the surface is solid below. Reads at most 1000000 probes.\n"
    "stderr tells the placed shape's box [m], its normals, the tool ball and every mesh warning.\n"
    "Exit status: 0 done, 1 bad input (files, meshes, probes), 2 usage error.\n";

enum class Kind { automatic, mesh, picture, depth };

struct Arguments {
  std::string shape;
  std::string probes;
  std::string forces = "-";
  std::string paths;  ///< --paths: where each tick's path goes; empty: nowhere
  hf::ProxyConfig proxy{};
  double scale = 1.0;
  bool scale_given = false;
  bool smooth = false;
  bool facets = false;
  hf::Pose pose{};
  Kind kind = Kind::automatic;
  std::optional<double> height_scale;
  double spacing = 1e-4;
  bool spacing_given = false;
  bool feel_texture = false;
  double relief_mm = 0.0;  ///< --relief-mm: the texture's relief at white [mm]; 0: none
};

/// N comma-separated finite numbers.
template <std::size_t N>
std::array<double, N> parse_reals(const std::string& text, const std::string& flag, const char* form) {
  std::array<double, N> out{};
  std::size_t begin = 0;
  for (std::size_t i = 0; i < N; ++i) {
    const std::size_t comma = text.find(',', begin);
    if ((i + 1 < N) == (comma == std::string::npos))
      throw hf::cli::UsageError(flag + " expects " + form + ", got '" + text + "'");
    out[i] =
        hf::cli::parse_real(text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin), flag);
    begin = comma + 1;
  }
  return out;
}

/// MU or MU_S,MU_K.
std::pair<double, double> parse_friction(const std::string& text) {
  const auto range = hf::cli::closed(0.0, 10.0);
  if (text.find(',') == std::string::npos) {
    const double mu = hf::cli::parse_real(text, "--friction");
    if (!range.contains(mu))
      throw hf::cli::UsageError("--friction must be in " + range.text() + ", got '" + text + "'");
    return {mu, mu};
  }
  const auto [mu_s, mu_k] = hf::cli::parse_pair(text, "--friction", range);
  if (mu_k > mu_s)
    throw hf::cli::UsageError("--friction: the dynamic coefficient (" + text.substr(text.find(',') + 1) +
                              ") must not exceed the static one");
  return {mu_s, mu_k};
}

Arguments parse(hf::cli::Parser& p) {
  Arguments a;
  bool probes_given = false;
  hf::cli::Input shape("SHAPE");
  while (p.next()) {
    if (p.is("--probes")) {
      a.probes = p.value();
      probes_given = true;
    } else if (p.is("--forces")) {
      const std::string& v = p.value();
      a.forces = v;
      if (v != "-") {  // checked by finish() like every output file
        hf::cli::check_output_file(v, "--forces");
      }
    } else if (p.is("--paths")) {
      a.paths = p.value();
      if (a.paths == "-") throw hf::cli::UsageError("--paths needs a file: '-' (stdout) is where the forces go");
      hf::cli::check_output_file(a.paths, "--paths");
    } else if (p.is("--stiffness")) {
      a.proxy.stiffness = p.real(hf::cli::open_closed(0.0, 1e6));
    } else if (p.is("--damping")) {
      a.proxy.damping = p.real(hf::cli::closed(0.0, 1e4));
    } else if (p.is("--friction")) {
      std::tie(a.proxy.static_friction, a.proxy.dynamic_friction) = parse_friction(p.value());
    } else if (p.is("--radius")) {
      a.proxy.radius = p.real(hf::cli::closed(0.0, hf::proxy_max_radius));
    } else if (p.is("--scale")) {
      a.scale = p.real(hf::cli::open_closed(0.0, 1e6));
      a.scale_given = true;
    } else if (p.is("--smooth")) {
      a.smooth = true;
    } else if (p.is("--facets")) {
      a.facets = true;
    } else if (p.is("--feel-texture")) {
      a.feel_texture = true;
    } else if (p.is("--relief-mm")) {
      a.relief_mm = p.real(hf::cli::open_closed(0.0, 10.0));
    } else if (p.is("--rotate")) {
      const auto r = parse_reals<4>(p.value(), "--rotate", "AX,AY,AZ,DEG");
      const glm::dvec3 axis{r[0], r[1], r[2]};
      if (!(glm::length(axis) > 0.0) || !std::isfinite(glm::length(axis)) || !(std::fabs(r[3]) <= 3600.0))
        throw hf::cli::UsageError("--rotate: the axis must not be zero and the angle within +-3600 degrees");
      a.pose = hf::Pose::from_axis_angle(axis, r[3] * std::numbers::pi / 180.0, a.pose.translation);
    } else if (p.is("--translate")) {
      const auto t = parse_reals<3>(p.value(), "--translate", "X,Y,Z [m]");
      for (const double x : t)
        if (!(std::fabs(x) <= 1e6)) throw hf::cli::UsageError("--translate: each part must be within +-1e6 m");
      a.pose.translation = {t[0], t[1], t[2]};
    } else if (p.is("--kind")) {
      a.kind = p.choice<Kind>("kind", {{"mesh", Kind::mesh}, {"picture", Kind::picture}, {"depth", Kind::depth}});
    } else if (p.is("--height-scale")) {
      a.height_scale = p.real(hf::cli::open_closed(0.0, 1e6));
    } else if (p.is("--spacing")) {
      a.spacing = p.real(hf::cli::open_closed(0.0, 1e3));
      a.spacing_given = true;
    } else {
      p.input_or_unknown(shape);
    }
  }
  a.shape = shape.required();
  if (!probes_given) throw hf::cli::UsageError("no --probes given");
  if (a.smooth && a.facets) throw hf::cli::UsageError("--smooth and --facets: give one shading");
  p.finish();
  return a;
}

bool is_mesh_file(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext)
    c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return ext == ".stl" || ext == ".obj" || ext == ".gltf" || ext == ".glb";
}

/// The probes: t,x,y,z rows, finite, t strictly increasing.
std::vector<std::array<double, 4>> read_probes(const std::string& path) {
  const hf::cli::CsvConfig config{.columns = "t,x,y,z", .what = "probes", .finite_only = true};
  std::vector<std::array<double, 4>> rows;
  if (path == "-") {
    std::string text;
    const std::size_t limit = (config.max_rows + 1) * (config.max_line_bytes + 2);
    char buffer[65536];
    std::size_t got = 0;
    while ((got = std::fread(buffer, 1, sizeof buffer, stdin)) > 0) {
      text.append(buffer, got);
      if (text.size() > limit) throw hf::FileError("stdin: more than " + std::to_string(limit) + " bytes of probes");
    }
    if (std::ferror(stdin)) throw hf::FileError("cannot read probes from stdin");
    rows = hf::cli::parse_csv<4>(text, "stdin", config);
  } else {
    rows = hf::cli::read_csv<4>(path, config);
  }
  const std::string name = path == "-" ? "stdin" : path;
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (!(rows[i][0] > rows[i - 1][0]))
      throw hf::FileError(name + ": t must increase strictly, but probe " + std::to_string(i + 1) +
                          " has t = " + hf::cli::detail::number_text(rows[i][0]) + " after " +
                          hf::cli::detail::number_text(rows[i - 1][0]));
  return rows;
}

/// Feels the path on one shape and writes a line per probe (and, when
/// `paths` is open, a line per point of each tick's path).
template <class Field>
void feel(Field field, const std::vector<std::array<double, 4>>& probes, std::FILE* out, std::FILE* paths,
          std::size_t& touching, double& largest) {
  std::fprintf(out, "t,proxy_x,proxy_y,proxy_z,fx,fy,fz,nx,ny,nz,u,v,primitive,contact\n");
  if (paths) std::fprintf(paths, "t,point,x,y,z\n");
  glm::dvec3 previous{0.0};
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const auto& [t, x, y, z] = probes[i];
    hf::Probe probe;
    probe.position = {x, y, z};
    probe.time = t;
    if (i > 0) {
      probe.period = t - probes[i - 1][0];
      probe.velocity = (probe.position - previous) / probe.period;
    }
    previous = probe.position;
    const glm::dvec3 f = field.force(probe);
    const hf::Contact& c = field.last_contact();
    const glm::dvec3 proxy = field.constraint().proxy();
    const long long primitive =
        c.touching && c.primitive != hf::no_primitive ? static_cast<long long>(c.primitive) : -1LL;
    std::fprintf(out, "%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%lld,%d\n", t, proxy.x,
                 proxy.y, proxy.z, f.x, f.y, f.z, c.normal.x, c.normal.y, c.normal.z, c.surface_uv.x, c.surface_uv.y,
                 primitive, c.touching ? 1 : 0);
    if (paths) {
      const hf::ProxyPath& path = field.constraint().last_path();
      for (int q = 0; q < path.count; ++q) {
        const glm::dvec3& at = path.points[static_cast<std::size_t>(q)];
        std::fprintf(paths, "%.12g,%d,%.17g,%.17g,%.17g\n", t, q, at.x, at.y, at.z);
      }
    }
    touching += c.touching ? 1 : 0;
    largest = std::fmax(largest, glm::length(f));
  }
}

/// The mesh or height map placed by the pose, ready for the proxy, and what to tell about it.
struct Loaded {
  std::variant<hf::Posed<hf::MeshShape>, hf::Posed<hf::HeightFieldShape>> shape;
  std::vector<std::string> notes;  ///< for stderr, once the input is known good
  cv::Mat texture;                 ///< --feel-texture: the mesh's base-colour picture
  double metres_per_uv = 0.0;      ///< --feel-texture: the mesh's size of one uv unit [m]
};

std::string box_text(const hf::io::Bounds& b) {
  char text[256];
  std::snprintf(text, sizeof text, "x [%.6g, %.6g] y [%.6g, %.6g] z [%.6g, %.6g] m", b.lo.x, b.hi.x, b.lo.y, b.hi.y,
                b.lo.z, b.hi.z);
  return text;
}

Loaded load_shape(const Arguments& args, bool mesh) {
  if (mesh) {
    hf::io::MeshReadConfig read;
    read.scale = args.scale;
    hf::io::LoadedMesh loaded = hf::io::load_mesh(args.shape, read);
    cv::Mat texture;  // --feel-texture: read before the mesh moves into its shape
    double uv_metres = 0.0;
    if (args.feel_texture) {
      texture = hf::material::base_colour_picture(loaded);
      uv_metres = hf::material::metres_per_uv(loaded.mesh);
    }
    hf::io::MeshShapeReport report;
    hf::MeshShape shape = hf::io::mesh_shape_from(
        loaded, args.shape, args.facets ? hf::io::MeshShading::faceted : hf::io::MeshShading::smooth,
        hf::bvh_default_max_nodes, &report);
    Loaded out{hf::Posed<hf::MeshShape>(shape, args.pose), {}, {}, 0.0};
    std::string what = "mesh of " + std::to_string(report.triangles) + " triangles";
    if (report.touchable < report.triangles) what += " (" + std::to_string(report.touchable) + " with an area)";
    out.notes.push_back(what + ", " + box_text(hf::io::placed_bounds(shape.mesh(), args.pose)) +
                        ", normals: " + report.normals);
    for (const hf::io::MeshWarning& w : loaded.warnings)
      out.notes.push_back("warning: " + w.message);
    if (args.feel_texture) {
      out.texture = texture;
      out.metres_per_uv = uv_metres;
      char text[160];
      std::snprintf(text, sizeof text, "texture: %d x %d px felt by uv, %.6g m per uv unit", out.texture.cols,
                    out.texture.rows, out.metres_per_uv);
      out.notes.emplace_back(text);
      if (args.relief_mm > 0.0) {
        std::snprintf(text, sizeof text, "relief: the texture's gray levels, white %.6g mm up", args.relief_mm);
        out.notes.emplace_back(text);
      }
    }
    return out;
  }
  const cv::Mat image = hf::cli::quiet_stderr([&] { return hf::load_image(args.shape); });
  const bool depth =
      args.kind == Kind::depth || (args.kind == Kind::automatic && image.channels() == 1 &&
                                   (image.depth() == CV_16U || image.depth() == CV_32F || image.depth() == CV_64F));
  hf::io::HeightGrid grid;
  if (depth) {
    hf::io::DepthMapConfig config;
    config.pixel_size = args.spacing;
    config.metres_per_unit = args.height_scale.value_or(1e-6);
    grid = hf::io::height_grid_from_depth(image, args.shape, config);
  } else {
    hf::io::PictureHeightConfig config;
    config.pixel_size = args.spacing;
    config.mm_per_level = args.height_scale.value_or(0.01);
    try {
      grid = hf::io::height_grid_from_gray(hf::to_gray(image), config);
    } catch (const std::invalid_argument& e) {
      throw hf::ImageError("cannot use '" + args.shape + "': " + e.what());
    }
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double h : grid.heights)
    lo = std::fmin(lo, h), hi = std::fmax(hi, h);
  const hf::io::Bounds box = hf::io::placed_bounds(
      {0.0, 0.0, lo}, {(grid.width - 1) * grid.spacing_x, (grid.height - 1) * grid.spacing_y, hi}, args.pose);
  Loaded out{hf::Posed<hf::HeightFieldShape>(hf::HeightFieldShape(grid), args.pose), {}, {}, 0.0};
  out.notes.push_back(std::string(depth ? "depth map" : "height map") + " of " + std::to_string(grid.width) + " x " +
                      std::to_string(grid.height) + " samples, " + box_text(box) +
                      ", normals: blended corner normals (force shading)");
  return out;
}

int run(const Arguments& args) {
  const bool mesh = args.kind == Kind::mesh || (args.kind == Kind::automatic && is_mesh_file(args.shape));
  if (mesh && (args.height_scale || args.spacing_given))
    throw hf::cli::UsageError("--height-scale and --spacing are for height maps, not meshes");
  if (!mesh && args.feel_texture)
    throw hf::cli::UsageError("--feel-texture is for meshes with a base-colour texture (glTF)");
  if (args.relief_mm > 0.0 && !args.feel_texture) throw hf::cli::UsageError("--relief-mm needs --feel-texture");
  if (!mesh && args.scale_given)
    throw hf::cli::UsageError("--scale is for meshes; a height map takes --spacing and --height-scale");
  if (!mesh && (args.smooth || args.facets))
    throw hf::cli::UsageError(std::string(args.smooth ? "--smooth" : "--facets") +
                              " is for meshes (a height field is always shaded)");
  // the shape first (a missing or hostile file is reported before stdin is read)
  Loaded loaded = load_shape(args, mesh);
  if (args.proxy.radius > 0.0) {
    char text[120];
    std::snprintf(text, sizeof text, "tool: a ball of radius %.6g m (the proxy columns are its centre)",
                  args.proxy.radius);
    loaded.notes.emplace_back(text);
  }
  const auto probes = read_probes(args.probes);
  std::FILE* out = args.forces == "-" ? stdout : std::fopen(args.forces.c_str(), "w");
  if (!out) throw hf::FileError("cannot write forces file '" + args.forces + "'");
  std::FILE* paths = args.paths.empty() ? nullptr : std::fopen(args.paths.c_str(), "w");
  if (!args.paths.empty() && !paths) throw hf::FileError("cannot write paths file '" + args.paths + "'");
  // the input is good: what the shape is, where it is, what the reader said
  for (const std::string& note : loaded.notes)
    std::fprintf(stderr, "feel_shape: %s: %s\n", args.shape.c_str(), note.c_str());
  std::fflush(stderr);
  std::size_t touching = 0;
  double largest = 0.0;
  std::visit(
      [&](auto& s) {
        using S = std::remove_cvref_t<decltype(s)>;
        if (loaded.texture.empty()) {
          feel(hf::contact(hf::ProxyConstraint<S>(std::move(s), args.proxy)), probes, out, paths, touching, largest);
        } else if (args.relief_mm > 0.0) {
          hf::material::ModelTextureConfig texture;
          texture.proxy = args.proxy;
          feel(hf::material::relief_surface(std::move(s), loaded.texture, loaded.metres_per_uv, args.relief_mm / 1000.0,
                                            texture),
               probes, out, paths, touching, largest);
        } else {
          hf::material::ModelTextureConfig texture;
          texture.proxy = args.proxy;
          feel(hf::material::textured_surface(std::move(s), loaded.texture, loaded.metres_per_uv, texture), probes, out,
               paths, touching, largest);
        }
      },
      loaded.shape);
  const bool failed = std::ferror(out) != 0;
  if (out != stdout ? std::fclose(out) != 0 || failed : std::fflush(out) != 0 || failed)
    throw hf::FileError("cannot write forces file '" + args.forces + "'");
  if (paths) {
    const bool paths_failed = std::ferror(paths) != 0;
    if (std::fclose(paths) != 0 || paths_failed) throw hf::FileError("cannot write paths file '" + args.paths + "'");
  }
  if (out != stdout)
    std::printf("%s: %zu probes, %zu touching, largest |F| %.6g N; forces written to %s\n", args.shape.c_str(),
                probes.size(), touching, largest, args.forces.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // errors are reported once, by us
  return hf::cli::main("feel_shape", usage, argc, argv, [](hf::cli::Parser& p) { return run(parse(p)); });
}
