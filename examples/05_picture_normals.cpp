// picture_normals: estimate the normals of planar faces marked in a picture
// (Kim & Kwon, World Haptics 2013) and evaluate the normal field's forces.
//
//   picture_normals IMAGE --face "x1,y1 x2,y2 x3,y3 x4,y4" [--face ...]
//       [--size W,H] [--intrinsics FILE.yml | --focal F [--center cx,cy]]
//       [--overlay OUT.png] [--probes IN.csv --forces OUT.csv]
//       [--force-map OUT.png] [--gradient] [--shading CELL_PX] [--verbose]
//
// Prints one line per face, `normal: nx ny nz` (camera frame: x right,
// y down, z forward; unit; toward the camera). Corners go around the face:
// the first maps to (0, 0) on the face, then (W, 0), (W, H), (0, H). One
// --size applies to every face; as many --size as --face pair up in order;
// without a size the aspect ratio is recovered with K. Without
// --intrinsics / --focal the focal length is estimated from the faces'
// right angles (or guessed from a 60 degree field of view) and a note goes
// to stderr. Probes: each line of IN.csv is x,y,vx,vy [px, px/s]; OUT.csv
// gets the header line x,y,fx,fy, then x,y,fx,fy [N] per probe in the image
// plane (fy positive downward), each probe
// evaluated from a fresh field state. --force-map draws, over a gray copy of
// the picture, the force felt moving right at 100 mm/s: red where it
// resists (climbing), green where it assists (descending). On bad input: one line on stderr,
// exit status 1 (2 for usage errors).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <filesystem>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.hpp"
#include "common/csv.hpp"
#include "common/picture.hpp"
#include "hapticfield/normals.hpp"

using namespace hapticfield;

namespace {

struct Args {
  std::string image;
  std::vector<std::vector<glm::dvec2>> faces;
  std::vector<glm::dvec2> sizes;
  std::string intrinsics;
  std::optional<double> focal;
  std::optional<glm::dvec2> centre;
  std::string overlay;
  std::string force_map;
  std::string probes;
  std::string forces;
  bool gradient = false;
  double shading = 0.0;
  std::uint64_t max_pixels = default_max_pixels;
  bool verbose = false;
};

constexpr const char* usage =
    "usage: picture_normals IMAGE --face \"x1,y1 x2,y2 x3,y3 x4,y4\" [--face ...] [options]\n"
    "Estimates the normals of planar faces marked in a picture (Kim & Kwon 2013).\n"
    "  IMAGE                 picture file (any format OpenCV reads), at most --max-mpx\n"
    "  --face CORNERS        4 corners [px] going around the face, each coordinate in\n"
    "                        [-1e6, 1e6]; repeat for more faces\n"
    "  --size W,H            face size [mm], each in (0, 1e6]; one for all faces or one per face\n"
    "                        (without it the aspect ratio is recovered with K)\n"
    "  --intrinsics FILE.yml camera matrix from an OpenCV calibration file\n"
    "  --focal F             focal length [px], in [1, 1e6] (without it, estimated)\n"
    "  --center cx,cy        principal point [px], each in [-1e6, 1e6]; needs --focal\n"
    "  --overlay OUT.png     draw the faces and their normals over the picture\n"
    "  --probes IN.csv       x,y,vx,vy per line [px, px/s], finite, at most 1000000 lines;\n"
    "                        needs --forces\n"
    "  --forces OUT.csv      a header line x,y,fx,fy, then x,y,fx,fy per probe [N], image axes\n"
    "                        (fy down)\n"
    "  --force-map OUT.png   the force felt moving right at 100 mm/s: red resists, green assists\n"
    "  --gradient            force from the slope itself instead of along the motion\n"
    "  --shading CELL        force shading on a grid of CELL [px], in [1, 1e4]\n"
    "  --max-mpx N           largest picture accepted [megapixels], in (0, 1e6] (default 100),\n"
    "                        read from the header before decoding\n"
    "  --verbose             per-face diagnostics on stderr (faces numbered from 1, in --face order)\n"
    "  -h, --help            this text\n"
    "Exit status: 0 done, 1 bad input (files, degenerate faces), 2 usage error.\n";

/// Pixel coordinates accepted on the command line [px].
const cli::Interval pixel_range = cli::closed(-1e6, 1e6);

std::vector<glm::dvec2> parse_face(const std::string& raw) {
  // tolerate "x, y" and ';' between corners
  std::string text;
  for (char c : raw) {
    if (c == ';' || c == '\t') c = ' ';
    if (c == ' ' && !text.empty() && text.back() == ',') continue;
    if (c == ',' && !text.empty() && text.back() == ' ') text.pop_back();
    text.push_back(c);
  }
  std::istringstream in(text);
  std::vector<glm::dvec2> points;
  std::string token;
  while (in >> token && points.size() <= 4) {
    const auto [x, y] = cli::parse_pair(token, "--face", pixel_range);
    points.push_back({x, y});
  }
  if (points.size() != 4)
    throw cli::UsageError("--face expects 4 corners \"x1,y1 x2,y2 x3,y3 x4,y4\" [px], got " +
                          (points.size() > 4 ? std::string("more") : std::to_string(points.size())));
  return points;
}

Args parse(cli::Parser& p) {
  Args a;
  cli::Input image("IMAGE");
  while (p.next()) {
    if (p.is("--face")) {
      a.faces.push_back(parse_face(p.value()));
    } else if (p.is("--size")) {
      const auto [w, h] = p.pair(cli::open_closed(0.0, 1e6));
      a.sizes.push_back({w, h});
    } else if (p.is("--intrinsics")) {
      a.intrinsics = p.value();
    } else if (p.is("--max-mpx")) {
      a.max_pixels = p.megapixels();
    } else if (p.is("--focal")) {
      a.focal = p.real(cli::closed(1.0, 1e6));
    } else if (p.is("--center") || p.is("--centre")) {
      const auto [x, y] = p.pair(pixel_range);
      a.centre = glm::dvec2{x, y};
    } else if (p.is("--overlay")) {
      a.overlay = p.output_file();
    } else if (p.is("--force-map")) {
      a.force_map = p.output_file();
    } else if (p.is("--probes")) {
      a.probes = p.value();
    } else if (p.is("--forces")) {
      a.forces = p.output_file();
    } else if (p.is("--gradient")) {
      a.gradient = true;
    } else if (p.is("--shading")) {
      a.shading = p.real(cli::closed(1.0, 1e4));
    } else if (p.is("--verbose")) {
      a.verbose = true;
    } else {
      p.input_or_unknown(image);
    }
  }
  a.image = image.required();
  if (a.faces.empty()) throw cli::UsageError("no --face given");
  if (a.sizes.size() > 1 && a.sizes.size() != a.faces.size())
    throw cli::UsageError("give one --size for all faces or one per --face");
  if (!a.intrinsics.empty() && (a.focal || a.centre))
    throw cli::UsageError("--intrinsics and --focal/--center are exclusive");
  if (a.centre && !a.focal) throw cli::UsageError("--center needs --focal");
  if (a.probes.empty() != a.forces.empty()) throw cli::UsageError("--probes and --forces go together");
  p.finish();
  return a;
}

/// K for the picture; notes for the user are collected in `notes` and
/// printed only once the faces are known to be valid (so a failure prints
/// one line).
Camera make_camera(const Args& a, int width, int height, std::ostringstream& notes) {
  if (!a.intrinsics.empty()) {
    Camera c = Camera::from_file(a.intrinsics);
    if (c.width() > 0 && c.height() > 0 && (c.width() != width || c.height() != height)) {
      const double sx = static_cast<double>(width) / c.width();
      const double sy = static_cast<double>(height) / c.height();
      if (std::abs(sx / sy - 1.0) < 0.01) {
        notes << "picture_normals: note: calibration was made at " << c.width() << "x" << c.height()
              << " px; K scaled by " << sx << " for the " << width << "x" << height << " px picture\n";
        return c.scaled(sx, sy);
      }
      notes << "picture_normals: note: calibration was made at " << c.width() << "x" << c.height()
            << " px, the picture is " << width << "x" << height << " px (cropped?); K used as is\n";
    }
    return c;
  }
  const glm::dvec2 centre = a.centre ? *a.centre : Camera::image_centre(width, height);
  if (a.focal) return Camera::from_focal(*a.focal, centre);
  // focal lengths from the faces' right angles, kept when plausible
  // (0.3 to 10 times the picture's longer side)
  const double longest = std::max(width, height);
  std::vector<double> focals;
  for (std::size_t i = 0; i < a.faces.size(); ++i) {
    std::optional<double> focal;
    try {
      focal = focal_from_rectangle(a.faces[i], centre);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("face " + std::to_string(i + 1) + ": " + e.what());
    }
    if (focal && *focal > 0.3 * longest && *focal < 10.0 * longest) focals.push_back(*focal);
  }
  if (!focals.empty()) {
    std::nth_element(focals.begin(), focals.begin() + static_cast<long>(focals.size() / 2), focals.end());
    const double f = focals[focals.size() / 2];
    notes << "picture_normals: note: no --intrinsics or --focal; focal length estimated from "
             "the faces' "
             "right angles: "
          << f << " px\n";
    return Camera::from_focal(f, centre);
  }
  notes << "picture_normals: note: no --intrinsics or --focal; focal length guessed from a 60 degree "
           "horizontal field of view\n";
  return Camera::from_field_of_view(60.0, width, height);
}

void draw_overlay(const std::string& path, const cv::Mat& image, const Camera& camera,
                  const std::vector<std::vector<glm::dvec2>>& faces, const std::vector<FacePose>& poses) {
  cv::Mat out = image.clone();
  const std::vector<cv::Scalar> tints{{60, 60, 230}, {230, 120, 40}, {60, 200, 60}, {200, 60, 200}, {40, 200, 220}};
  cv::Mat tinted = out.clone();
  for (std::size_t f = 0; f < faces.size(); ++f) {
    std::vector<cv::Point> poly;
    for (auto p : faces[f])
      poly.emplace_back(cvRound(p.x * 16), cvRound(p.y * 16));
    cv::fillPoly(tinted, std::vector<std::vector<cv::Point>>{poly}, tints[f % tints.size()], cv::LINE_AA, 4);
  }
  cv::addWeighted(out, 0.6, tinted, 0.4, 0.0, out);
  const int thick = std::max(2, image.cols / 400);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    std::vector<cv::Point> poly;
    for (auto p : faces[f])
      poly.emplace_back(cvRound(p.x * 16), cvRound(p.y * 16));
    cv::polylines(out, std::vector<std::vector<cv::Point>>{poly}, true, tints[f % tints.size()], thick, cv::LINE_AA, 4);
    // the normal as a 3D arrow from the face centre, half the face's size long
    const FacePose& pose = poses[f];
    const double length = 0.5 * std::sqrt(pose.width * pose.height);
    const cv::Vec3d centre = pose.R * cv::Vec3d(pose.width / 2, pose.height / 2, 0.0) + pose.t;
    const cv::Vec3d tip = centre + length * cv::Vec3d(pose.normal.x, pose.normal.y, pose.normal.z);
    std::vector<cv::Point2d> projected;
    cv::projectPoints(std::vector<cv::Point3d>{{centre[0], centre[1], centre[2]}, {tip[0], tip[1], tip[2]}},
                      cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(camera.matrix()),
                      camera.has_distortion() ? cv::Mat(camera.distortion()) : cv::Mat(), projected);
    cv::arrowedLine(out, projected[0], projected[1], cv::Scalar(255, 255, 255), thick + 3, cv::LINE_AA, 0, 0.2);
    cv::arrowedLine(out, projected[0], projected[1], cv::Scalar(20, 20, 20), thick, cv::LINE_AA, 0, 0.2);
    char label[96];
    std::snprintf(label, sizeof label, "(%.2f, %.2f, %.2f)", pose.normal.x + 0.0, pose.normal.y + 0.0,
                  pose.normal.z + 0.0);
    const double scale = std::max(0.45, image.cols / 2000.0);
    int baseline = 0;
    const cv::Size text = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, thick, &baseline);
    const cv::Point at(cvRound(projected[0].x) - text.width / 2, cvRound(projected[0].y) + 2 * text.height + 8);
    cv::putText(out, label, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(255, 255, 255), thick + 2, cv::LINE_AA);
    cv::putText(out, label, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(20, 20, 20), thick, cv::LINE_AA);
  }
  if (!cv::imwrite(path, out)) throw FileError("--overlay: cannot write '" + path + "'");
}

void draw_force_map(const std::string& path, const cv::Mat& image, const NormalField& field) {
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  cv::Mat out;
  cv::cvtColor(gray, out, cv::COLOR_GRAY2BGR);
  const glm::dvec2 velocity{100.0 * field.mapping().px_per_mm(), 0.0};  // 100 mm/s to the right [px/s]
  const double limit = field.options().max_force;
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const double fx = field.image_force({x, y}, velocity).x / limit;  // -1 resist .. +1 assist
      if (fx == 0.0) continue;
      cv::Vec3b& px = out.at<cv::Vec3b>(y, x);
      const double a = std::min(1.0, std::abs(fx));
      const cv::Vec3d tint = fx < 0.0 ? cv::Vec3d(40, 40, 230) : cv::Vec3d(40, 200, 40);
      for (int c = 0; c < 3; ++c)
        px[c] = cv::saturate_cast<uchar>((1.0 - 0.8 * a) * px[c] + 0.8 * a * tint[c]);
    }
  if (!cv::imwrite(path, out)) throw FileError("--force-map: cannot write '" + path + "'");
}

void evaluate_probes(const Args& a, NormalField& field) {
  const auto rows = cli::read_csv<4>(a.probes, {.columns = "x,y,vx,vy", .what = "probes", .finite_only = true});
  std::ofstream out(a.forces);
  if (!out) throw FileError("--forces: cannot write '" + a.forces + "'");
  out << "x,y,fx,fy\n";  // the header line, as tangible_image writes it
  for (const auto& r : rows) {
    field.reset();  // each probe on its own: the filter starts from its velocity
    const glm::dvec3 f = field.force(field.probe_at({r[0], r[1]}, {r[2], r[3]}));
    const glm::dvec2 fi = field.to_image_axes(f);
    char buf[160];
    std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g,%.9g\n", r[0], r[1], fi.x + 0.0,
                  fi.y + 0.0);  // + 0.0: no "-0"
    out << buf;
  }
  if (!out) throw FileError("--forces: cannot write '" + a.forces + "'");
}

int run(const Args& a) {
  cv::Mat image;
  try {  // the pixel limit is checked from the header, before decoding
    image = cli::to_bgr8(cli::quiet_stderr([&] { return load_image(a.image, a.max_pixels); }));
  } catch (const ImageError& e) {
    throw ImageError(cli::name_limit_flag(e.what(), "--max-mpx"));  // the user's flag, not the library's
  }
  std::ostringstream notes;
  const Camera camera = make_camera(a, image.cols, image.rows, notes);
  std::vector<FacePose> poses;
  std::vector<ImageFace> faces;
  for (std::size_t f = 0; f < a.faces.size(); ++f) {
    std::optional<glm::dvec2> size;
    if (!a.sizes.empty()) size = a.sizes.size() == 1 ? a.sizes[0] : a.sizes[f];
    try {
      poses.push_back(estimate_rectangle_pose(camera, a.faces[f], size));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("face " + std::to_string(f + 1) + ": " + e.what());
    }
    faces.push_back({a.faces[f], poses.back().normal});
  }
  for (std::size_t f = 0; f < poses.size(); ++f) {
    const glm::dvec3 n = poses[f].normal;
    std::printf("normal: %.6f %.6f %.6f\n", n.x, n.y, n.z);
    if (a.verbose)
      std::fprintf(stderr,
                   "face %zu: reprojection rms %.3f px (closed form %.3f px), size %.4g x %.4g%s, "
                   "distance %.4g, |cos(r1,r2)| before orthogonalisation %.2e\n",
                   f + 1, poses[f].rms_reprojection_px, poses[f].closed_form_rms_px, poses[f].width, poses[f].height,
                   poses[f].aspect_recovered ? " (aspect recovered)" : " mm", cv::norm(poses[f].t),
                   poses[f].orthogonality);
  }
  std::fflush(stdout);
  if (!a.overlay.empty()) draw_overlay(a.overlay, image, camera, a.faces, poses);
  if (!a.probes.empty() || !a.force_map.empty()) {
    NormalFieldConfig options;
    if (a.gradient) options.mode = NormalForceMode::gradient;
    options.shading_cell_px = a.shading;
    NormalField field(image.cols, image.rows, faces, options);
    if (!a.probes.empty()) evaluate_probes(a, field);
    if (!a.force_map.empty()) draw_force_map(a.force_map, image, field);
  }
  std::cerr << notes.str();  // only on success: a failure prints one line
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // errors are reported once, by us
  return cli::main("picture_normals", usage, argc, argv, [](cli::Parser& p) { return run(parse(p)); });
}
