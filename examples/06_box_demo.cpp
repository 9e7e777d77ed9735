// box_demo: the synthetic version of Kim & Kwon's accuracy stimulus (World
// Haptics 2013): a textured 20 cm box rotated about its vertical axis from
// 15 to 75 degrees in 5-degree steps, seen by a known camera (1024 x 768 px,
// f = 1000 px, 800 mm away, 20 degrees above). For each view and each of the
// two visible side faces it estimates the normal from the exact corners and
// from corners each displaced by NOISE px in a random direction, and prints
// the accuracy table and the table of ratios estimated / true component.
//
//   box_demo [--rotation DEG] [--noise PX] [--trials N] [--seed S] [--out DIR]
//   box_demo --rotation DEG --check NORMALS.txt
//
// --out DIR writes, per view, box_DEG.png (the picture), box_DEG.args (the
// picture_normals arguments for its two faces, one per line) and
// box_DEG_probes.csv (probes at the face centres moving right and down).
// --check compares `normal: nx ny nz` lines (picture_normals' output) with
// the true normals of that view: exit 0 when each is within 0.5 degrees.
// FILE "-" reads them from stdin. Faces are numbered from 1 (1 front,
// 2 side), in the order of the --face arguments box_DEG.args gives, as
// picture_normals --verbose numbers them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "common/cli.hpp"
#include "hapticfield/normals.hpp"

using namespace hapticfield;

namespace {

struct Args {
  std::vector<double> rotations = box_rotations();
  double noise = 1.0;
  int trials = 200;
  unsigned seed = 2013;
  std::string out;
  std::string check;
};

constexpr const char* usage =
    "usage: box_demo [--rotation DEG] [--noise PX] [--trials N] [--seed S] [--out DIR]\n"
    "       box_demo --rotation DEG --check NORMALS.txt\n"
    "Kim & Kwon's rotated-box accuracy stimulus, synthetic: estimates the two visible\n"
    "faces' normals from exact and noisy corners and prints the accuracy tables.\n"
    "  --rotation DEG   one view only [deg], in (0, 90) (default: 15 to 75 in 5 degree steps)\n"
    "  --noise PX       corner displacement [px], in [0, 100] (default 1)\n"
    "  --trials N       noisy trials per face, 1..100000 (default 200)\n"
    "  --seed S         random seed, 0..4294967295 (default 2013)\n"
    "  --out DIR        write box_DEG.png, box_DEG.args and box_DEG_probes.csv per view\n"
    "  --check FILE     compare picture_normals' 'normal: nx ny nz' lines with the truth (FILE\n"
    "                   '-': stdin); faces 1 (front) and 2 (side) as in box_DEG.args; exit 0\n"
    "                   when each is within 0.5 degrees, 1 otherwise\n"
    "  -h, --help       this text\n"
    "Exit status: 0 done, 1 bad input or a failed check, 2 usage error.\n";

Args parse(cli::Parser& p) {
  Args a;
  while (p.next()) {
    if (p.is("--rotation")) {
      a.rotations = {p.real(cli::open(0.0, 90.0))};
    } else if (p.is("--noise")) {
      a.noise = p.real(cli::closed(0.0, 100.0));
    } else if (p.is("--trials")) {
      a.trials = static_cast<int>(p.integer(1, 100000));
    } else if (p.is("--seed")) {
      a.seed = static_cast<unsigned>(p.integer(0, 4294967295LL));
    } else if (p.is("--out")) {
      a.out = p.output_dir();
    } else if (p.is("--check")) {
      a.check = p.value();
    } else {
      p.unknown();
    }
  }
  if (!a.check.empty() && a.rotations.size() != 1) throw cli::UsageError("--check needs --rotation");
  p.finish();
  return a;
}

int check(const Args& a, const BoxScene& scene) {
  const BoxView view = render_box(scene, a.rotations[0], false);
  constexpr std::size_t max_check_bytes = std::size_t{1} << 20;  // [bytes]
  const std::string source = a.check == "-" ? std::string("stdin") : "'" + a.check + "'";
  std::string text;
  if (a.check == "-") {  // a pipe: picture_normals ... | box_demo --rotation 45 --check -
    char buf[4096];
    while (std::cin.read(buf, sizeof buf) || std::cin.gcount() > 0) {
      text.append(buf, static_cast<std::size_t>(std::cin.gcount()));
      if (text.size() > max_check_bytes) throw FileError("--check: stdin holds more than 1 MiB");
    }
  } else {
    try {
      text = read_file(a.check, max_check_bytes);
    } catch (const FileError& e) {
      throw FileError(std::string("--check: ") + e.what());
    }
  }
  std::istringstream in(text);
  std::string line;
  std::size_t f = 0;
  int failures = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    glm::dvec3 n{0.0};
    if (!(s >> tag >> n.x >> n.y >> n.z) || tag != "normal:") continue;
    if (f >= 2) throw FileError("--check: more than two normals in " + source);
    const double err = angle_between_deg(n, view.normals[f]);
    // numbered from 1 in --face order, as picture_normals --verbose numbers them
    std::printf("face %zu (%s): %.6f %.6f %.6f vs true %.6f %.6f %.6f: %.4f deg\n", f + 1, f == 0 ? "front" : "side",
                n.x, n.y, n.z, view.normals[f].x, view.normals[f].y, view.normals[f].z, err);
    if (!(err <= 0.5) || std::abs(glm::length(n) - 1.0) > 1e-5) ++failures;
    ++f;
  }
  if (f != 2)
    throw FileError("--check: expected two 'normal: nx ny nz' lines in " + source + ", got " + std::to_string(f));
  return failures == 0 ? 0 : 1;
}

void write_files(const Args& a, const BoxScene& scene, const BoxView& view) {
  const std::string base = a.out + "/box_" + std::to_string(static_cast<int>(std::lround(view.rotation_deg)));
  if (!cv::imwrite(base + ".png", view.picture)) throw FileError("--out: cannot write '" + base + ".png'");
  std::ofstream args(base + ".args");
  for (const auto& face : view.corners) {
    args << "--face\n";
    char buf[64];
    for (std::size_t k = 0; k < 4; ++k) {
      std::snprintf(buf, sizeof buf, "%s%.4f,%.4f", k ? " " : "", face[k].x, face[k].y);
      args << buf;
    }
    args << "\n";
  }
  args << "--size\n" << scene.edge_mm << "," << scene.edge_mm << "\n--focal\n" << scene.focal_px << "\n";
  std::ofstream probes(base + "_probes.csv");
  probes << "x,y,vx,vy\n";
  for (const auto& face : view.corners) {
    const glm::dvec2 c = 0.25 * (face[0] + face[1] + face[2] + face[3]);
    probes << c.x << "," << c.y << ",200,0\n" << c.x << "," << c.y << ",-200,0\n" << c.x << "," << c.y << ",0,200\n";
  }
  if (!args || !probes) throw FileError("--out: cannot write '" + base + ".args' or '" + base + "_probes.csv'");
}

int run(const Args& a) {
  const BoxScene scene;
  if (!a.check.empty()) return check(a, scene);
  if (!a.out.empty()) std::filesystem::create_directories(a.out);
  const Camera camera = scene.camera();
  const glm::dvec2 size{scene.edge_mm, scene.edge_mm};
  std::mt19937 rng(a.seed);
  std::uniform_real_distribution<double> direction(0.0, 2.0 * std::numbers::pi);

  std::printf("Synthetic box: %.0f mm edge, %d x %d px, f = %.0f px, %.0f mm away, %.0f deg above.\n", scene.edge_mm,
              scene.width, scene.height, scene.focal_px, scene.distance_mm, scene.elevation_deg);
  std::printf("Noise: each corner displaced by %.2f px in a random direction, %d trials (seed %u).\n\n", a.noise,
              a.trials, a.seed);
  std::printf("Accuracy: angle between estimated and true normal [deg]\n");
  std::printf("%5s %-5s %-26s %9s %19s %19s %9s\n", "rot", "face", "true normal", "exact", "noisy mean / max",
              "closed-form m / max", "rms [px]");
  struct Ratio {
    double rotation;
    int face;
    glm::dvec3 truth, exact, noisy;
  };
  std::vector<Ratio> ratios;
  double worst_exact = 0.0;
  double worst_noisy = 0.0;
  double aspect_mean = 0.0;  // unknown size: aspect recovered with K, same noisy corners
  double aspect_max = 0.0;
  double aspect_ratio_err = 0.0;
  std::vector<double> focals;  // focal length from the faces' right angles, noisy corners
  int samples = 0;
  for (double rotation : a.rotations) {
    const BoxView view = render_box(scene, rotation, !a.out.empty());
    if (!a.out.empty()) write_files(a, scene, view);
    for (int f = 0; f < 2; ++f) {
      const std::vector<glm::dvec2> corners(view.corners[f].begin(), view.corners[f].end());
      const glm::dvec3 truth = view.normals[f];
      const glm::dvec3 exact = estimate_rectangle_pose(camera, corners, size).normal;
      double mean = 0.0;
      double max = 0.0;
      double cf_mean = 0.0;
      double cf_max = 0.0;
      double rms = 0.0;
      glm::dvec3 noisy{0.0};
      for (int k = 0; k < a.trials; ++k) {
        auto c = corners;
        for (auto& p : c) {
          const double d = direction(rng);
          p += a.noise * glm::dvec2{std::cos(d), std::sin(d)};
        }
        const FacePose pose = estimate_rectangle_pose(camera, c, size);
        const double e = angle_between_deg(pose.normal, truth);
        const double ecf = angle_between_deg(pose.closed_form_normal, truth);
        mean += e / a.trials;
        max = std::max(max, e);
        cf_mean += ecf / a.trials;
        cf_max = std::max(cf_max, ecf);
        rms += pose.rms_reprojection_px / a.trials;
        noisy += pose.normal / double(a.trials);
        const FacePose free = estimate_rectangle_pose(camera, c);
        const double ea = angle_between_deg(free.normal, truth);
        aspect_mean += ea;
        aspect_max = std::max(aspect_max, ea);
        aspect_ratio_err = std::max(aspect_ratio_err, std::abs(free.width / free.height - 1.0));
        ++samples;
        if (auto focal = focal_from_rectangle(c, Camera::image_centre(scene.width, scene.height)))
          focals.push_back(*focal);
      }
      const double err = angle_between_deg(exact, truth);
      worst_exact = std::max(worst_exact, err);
      worst_noisy = std::max(worst_noisy, max);
      std::printf("%5.0f %-5s (%7.4f %7.4f %7.4f) %9.2e %9.3f / %7.3f %9.3f / %7.3f %9.3f\n", rotation,
                  f == 0 ? "front" : "side", truth.x, truth.y, truth.z, err, mean, max, cf_mean, cf_max, rms);
      ratios.push_back({rotation, f, truth, exact, noisy});
    }
  }
  std::printf("\nworst: %.2e deg from exact corners (bound 0.5), %.3f deg with %.2f px noise (bound 2)\n\n",
              worst_exact, worst_noisy, a.noise);
  std::sort(focals.begin(), focals.end());
  std::printf(
      "unknown size (aspect recovered with K), same noisy corners: mean %.3f deg, worst %.3f deg, "
      "aspect within %.1f%% of 1\n",
      aspect_mean / std::max(samples, 1), aspect_max, 100.0 * aspect_ratio_err);
  if (!focals.empty())
    std::printf(
        "focal length from one face's right angles, noisy corners: median %.0f px, 10-90%% "
        "range %.0f-%.0f px (true %.0f px)\n\n",
        focals[focals.size() / 2], focals[focals.size() / 10], focals[focals.size() * 9 / 10], scene.focal_px);
  std::printf(
      "Ratios estimated / true normal component (the paper reports 0.99-1.03); '-' where |true| < "
      "0.05\n");
  std::printf("%5s %-5s %8s %8s %8s   %8s %8s %8s\n", "rot", "face", "x exact", "y exact", "z exact", "x noisy",
              "y noisy", "z noisy");
  const auto ratio = [](double est, double truth) {
    char buf[16];
    if (std::abs(truth) < 0.05)
      std::snprintf(buf, sizeof buf, "%8s", "-");
    else
      std::snprintf(buf, sizeof buf, "%8.4f", est / truth);
    return std::string(buf);
  };
  for (const auto& r : ratios)
    std::printf("%5.0f %-5s %s %s %s   %s %s %s\n", r.rotation, r.face == 0 ? "front" : "side",
                ratio(r.exact.x, r.truth.x).c_str(), ratio(r.exact.y, r.truth.y).c_str(),
                ratio(r.exact.z, r.truth.z).c_str(), ratio(r.noisy.x, r.truth.x).c_str(),
                ratio(r.noisy.y, r.truth.y).c_str(), ratio(r.noisy.z, r.truth.z).c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::main("box_demo", usage, argc, argv, [](cli::Parser& p) { return run(parse(p)); });
}
