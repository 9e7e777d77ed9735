// false_texture IMAGE [--out DIR] [--levels N]
//
// False texturing and data visualisation (Fritz & Barner 1996): the picture's
// gray levels are cut into N bands (default 4) and each band gets its own
// texture; separately, the brightness modulates friction. The program fits
// the picture into a 100 x 100 mm workspace, strokes it along three
// horizontal lines at 50 mm/s and writes
//   false_texture.png  the picture tinted by texture region, with a legend and
//                      the force along the middle stroke (axes in mm and N)
//   strokes.csv        position, region, false-texture force, brightness-
//                      modulated friction and data-modulated texture per tick
//   regions.csv        region, gray range, texture name and colour (the legend)
//   strokes.png        the three strokes with axes and a legend (matplotlib,
//                      when python3-matplotlib is present)
// to DIR (default out/false_texture). No device is driven.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.hpp"
#include "common/picture.hpp"
#include "common/plots.hpp"
#include "common/simple_plot.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/image_maps.hpp"

using namespace hapticfield;
using namespace hapticfield::texture;
namespace fs = std::filesystem;

namespace {

constexpr const char* usage =
    "usage: false_texture IMAGE [--out DIR] [--levels N] [--max-mpx N]\n"
    "False texturing and data visualisation: a texture per gray band of the picture and\n"
    "friction modulated by brightness, stroked along three lines at 50 mm/s.\n"
    "  IMAGE        picture file (any format OpenCV reads), fitted into 100 x 100 mm\n"
    "  --out DIR    output folder for false_texture.png, strokes.csv, regions.csv and (with\n"
    "               matplotlib) strokes.png, created if needed (default out/false_texture)\n"
    "  --levels N   gray bands, each with its own texture, 2..8 (default 4)\n"
    "  --max-mpx N  largest picture accepted [megapixels], in (0, 1e6] (default 100), read from\n"
    "               the header before decoding\n"
    "  -h, --help   this text\n"
    "Exit status: 0 done, 1 bad input (picture, output folder), 2 usage error.\n";

int run(const std::string& image_path, const fs::path& out, int levels, std::uint64_t max_pixels) {
  {
    cv::Mat image;
    try {  // the library's loader: ImageError naming the file; the pixel limit read from the header
      image = cli::to_bgr8(cli::quiet_stderr([&] { return load_image(image_path, max_pixels); }));
    } catch (const ImageError& e) {
      throw ImageError(cli::name_limit_flag(e.what(), "--max-mpx"));  // the user's flag, not the library's
    }
    const PlaneMapping mapping = PlaneMapping::fit(image.cols, image.rows, 100.0);
    const LabelMap labels = label_map_from_gray_levels(image, levels, mapping);

    // one texture per gray band, darkest first: rough to smooth
    std::vector<AnyField> textures;
    std::vector<std::string> names;
    for (int l = 0; l < levels; ++l) {
      const double t = levels == 1 ? 0.0 : double(l) / (levels - 1);  // 0 dark .. 1 bright
      const TextureConfig params{0.6 * (1.0 - t) + 0.05, 1e-3, true, glm::dvec3{1.0, 1.0, 0.0}};
      if (l == levels - 1) {
        textures.emplace_back();  // brightest: smooth
        names.push_back("smooth");
      } else if (l % 2 == 0) {
        const double grain = 0.5e-3 + 1.5e-3 * (1.0 - t);  // coarser where darker
        textures.emplace_back(TextureField(
            SpatialSource(NoiseLattice<GaussianNoise, 2>(GaussianNoise(1.0), static_cast<std::uint32_t>(l + 1),
                                                         glm::dvec3{grain}, Interpolation::cubic)),
            params));
        names.push_back("Gaussian lattice " + std::to_string(grain * 1e3).substr(0, 4) + " mm");
      } else {
        const double period = 0.5e-3 + 1.5e-3 * (1.0 - t);
        textures.emplace_back(
            TextureField(SpatialSource(FourierSynthesis(
                             {{Waveform::square, 1.0, 1.0 / period, 0.0, glm::dvec3{1, 0, 0}}}, glm::dvec3{1, 0, 0})),
                         params));
        names.push_back("square grating " + std::to_string(period * 1e3).substr(0, 4) + " mm");
      }
    }
    // the picture lies on the plane z = 0 (1000 N/m): each field is
    // F = Fc + part, the part seeing |Fc| and the plane's normal of the tick
    const PlaneConstraint picture(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1000.0, 0.0});
    auto false_texture = contact(picture, FalseTexture(labels, std::move(textures)));
    // data visualisation: brightness (0..1) raises friction from mu = 0.1 to
    // 0.6, and darkness raises the amplitude of a fine Gaussian texture
    const ScalarMap brightness = scalar_map_from_image(image, mapping);
    auto friction = contact(picture, DataModulated(Friction(FrictionConfig{1.0, 0.0, 0.0, 2e-3, true, glm::dvec3{0.0}}),
                                                   brightness, 0.1, 0.5));
    auto data_texture =
        contact(picture, DataModulated(TextureField(SpatialSource(NoiseLattice<GaussianNoise, 2>(GaussianNoise(1.0), 99,
                                                                                                 glm::dvec3{0.4e-3})),
                                                    TextureConfig{0.3, 1e-3, true, glm::dvec3{1.0, 1.0, 0.0}}),
                                       brightness, 1.0, -1.0));  // amplitude 1 - brightness

    fs::create_directories(out);
    std::ofstream csv(out / "strokes.csv");
    csv << "stroke,x_mm,y_mm,region,ft_x_N,ft_y_N,ff_x_N,data_texture_x_N\n";
    const double rate = 1000.0, speed = 0.05;
    std::vector<double> middle_ft, middle_ff;
    std::vector<int> middle_region;
    for (int s = 0; s < 3; ++s) {
      const double y = (-25.0 + 25.0 * s) * 1e-3;
      false_texture.reset();
      for (int i = 0; i * speed / rate < 0.1; ++i) {
        Probe p;
        p.position = glm::dvec3{-0.05 + i * speed / rate, y, -1e-3};  // pressed 1 mm: |Fc| = 1 N
        p.velocity = glm::dvec3{speed, 0.0, 0.0};
        p.time = i / rate;
        const glm::dvec3 ft = false_texture.force(p);
        const glm::dvec3 ff = friction.force(p);
        const glm::dvec3 fd = data_texture.force(p);
        const int region = false_texture.part<0>().region(p.position);
        csv << s << ',' << p.position.x * 1e3 << ',' << y * 1e3 << ',' << region << ',' << ft.x << ',' << ft.y << ','
            << ff.x << ',' << fd.x << '\n';
        if (s == 1) middle_ft.push_back(ft.x), middle_ff.push_back(ff.x), middle_region.push_back(region);
      }
    }

    // picture: gray image tinted by region, legend, middle-stroke trace
    const cv::Scalar palette[] = {{40, 40, 220},  {40, 180, 40},  {220, 120, 30}, {200, 200, 200},
                                  {200, 40, 200}, {30, 200, 220}, {120, 80, 20},  {90, 90, 90}};
    cv::Mat gray;
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
    cv::Mat tinted(image.rows, image.cols, CV_8UC3);
    for (int y = 0; y < image.rows; ++y)
      for (int x = 0; x < image.cols; ++x) {
        const int l = gray.at<std::uint8_t>(y, x) * levels / 256;
        const cv::Scalar c = palette[l];
        const double g = gray.at<std::uint8_t>(y, x) / 255.0;
        tinted.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<std::uint8_t>(0.5 * c[0] + 0.5 * 255 * g),
                                               cv::saturate_cast<std::uint8_t>(0.5 * c[1] + 0.5 * 255 * g),
                                               cv::saturate_cast<std::uint8_t>(0.5 * c[2] + 0.5 * 255 * g));
      }
    const int legend_h = 22 * levels + 10, plot_h = 250;
    const int canvas_w = std::max(image.cols, 520);
    cv::Mat canvas(image.rows + legend_h + plot_h, canvas_w, CV_8UC3, cv::Scalar(255, 255, 255));
    tinted.copyTo(canvas(cv::Rect(0, 0, image.cols, image.rows)));
    for (int s = 0; s < 3; ++s) {  // the strokes
      const glm::dvec2 a = mapping.to_image(glm::dvec3{-0.05, (-25.0 + 25.0 * s) * 1e-3, 0.0});
      const glm::dvec2 b = mapping.to_image(glm::dvec3{0.05, (-25.0 + 25.0 * s) * 1e-3, 0.0});
      cv::line(canvas, cv::Point(int(a.x), int(a.y)), cv::Point(int(b.x), int(b.y)), cv::Scalar(0, 0, 0),
               s == 1 ? 2 : 1);
    }
    for (int l = 0; l < levels; ++l) {
      const int y = image.rows + 8 + 22 * l;
      cv::rectangle(canvas, cv::Rect(8, y, 16, 16), palette[l], cv::FILLED);
      const std::string text = "gray " + std::to_string(l * 256 / levels) + ".." +
                               std::to_string((l + 1) * 256 / levels - 1) + ": " + names[static_cast<std::size_t>(l)];
      cv::putText(canvas, text, {32, y + 13}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    // the middle stroke (thick line above) against x [mm], force [N] on a
    // stated scale, the region under the probe as a colour strip
    const int top = image.rows + legend_h;
    plots::text(canvas, "middle stroke (thick line), 50 mm/s, 1 N: force along x; strip: region under the probe",
                {8, top + 14}, 0.38);
    const std::size_t n = middle_ft.size();
    double peak = 1e-9;
    for (std::size_t i = 0; i < n; ++i)
      peak = std::max({peak, std::fabs(middle_ft[i]), std::fabs(middle_ff[i])});
    const plots::Axes axes(cv::Rect(60, top + 52, canvas_w - 80, plot_h - 108), -50.0, 50.0, -1.05 * peak, 1.05 * peak);
    axes.draw(canvas, "x along the stroke [mm]", "force [N]");
    std::vector<double> x_mm;
    for (std::size_t i = 0; i < n; ++i)
      x_mm.push_back(-50.0 + 100.0 * static_cast<double>(i) / static_cast<double>(std::max<std::size_t>(n - 1, 1)));
    for (std::size_t i = 0; i + 1 < n; ++i) {  // region strip just above the axes
      const int r = middle_region[i];
      if (r < 0) continue;
      const cv::Point a = axes.at(x_mm[i], 0.0), b = axes.at(x_mm[i + 1], 0.0);
      cv::rectangle(canvas, cv::Rect(a.x, top + 22, std::max(1, b.x - a.x), 6), palette[r], cv::FILLED);
    }
    plots::text(canvas, "region", {8, top + 29}, 0.38);
    const cv::Scalar black(0, 0, 0), red(0, 0, 220);
    axes.line(canvas, x_mm, middle_ft, black);
    axes.line(canvas, x_mm, middle_ff, red);
    plots::legend(canvas, {axes.box().x + 6, axes.box().y + 6},
                  {{black, "false texture Fx [N]"}, {red, "brightness-modulated friction Fx [N]"}});
    if (!csv.flush()) throw FileError("--out: cannot write '" + (out / "strokes.csv").string() + "'");
    csv.close();
    if (!cv::imwrite((out / "false_texture.png").string(), canvas))
      throw FileError("--out: cannot write '" + (out / "false_texture.png").string() + "'");
    {  // the legend as data, for strokes.png
      std::ofstream regions(out / "regions.csv");
      regions << "region,gray_lo,gray_hi,name,colour\n";
      for (int l = 0; l < levels; ++l) {
        char colour[8];  // #rrggbb, the legend's colour
        std::snprintf(colour, sizeof colour, "#%02x%02x%02x", static_cast<int>(palette[l][2]),
                      static_cast<int>(palette[l][1]), static_cast<int>(palette[l][0]));
        regions << l << ',' << l * 256 / levels << ',' << (l + 1) * 256 / levels - 1 << ','
                << names[static_cast<std::size_t>(l)] << ',' << colour << '\n';
      }
      if (!regions) throw FileError("--out: cannot write '" + (out / "regions.csv").string() + "'");
    }
    std::cout << "wrote " << (out / "false_texture.png").string() << ", " << (out / "strokes.csv").string() << " and "
              << (out / "regions.csv").string() << '\n';
    // all three strokes with axes, units and a legend: matplotlib when present
    std::string why;
    if (plots::matplotlib({"strokes", "--dir", out.string()}, why))
      std::cout << "wrote " << (out / "strokes.png").string() << " (drawn with matplotlib)\n";
    else
      std::cout << "no strokes.png (" << why << "); false_texture.png shows the middle stroke\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // errors are reported once, by us
  return cli::main("false_texture", usage, argc, argv, [](cli::Parser& p) {
    cli::Input image("IMAGE");
    std::string out = "out/false_texture";
    bool out_given = false;
    int levels = 4;
    std::uint64_t max_pixels = default_max_pixels;
    while (p.next()) {
      if (p.is("--out"))
        out = p.output_dir(), out_given = true;
      else if (p.is("--levels"))
        levels = static_cast<int>(p.integer(2, 8));  // 8 colours in the legend
      else if (p.is("--max-mpx"))
        max_pixels = p.megapixels();
      else
        p.input_or_unknown(image);
    }
    const std::string& image_path = image.required();
    if (!out_given) p.default_output_dir("--out", out);
    p.finish();
    return run(image_path, out, levels, max_pixels);
  });
}
