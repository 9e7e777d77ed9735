// tangible_image: feel a picture with the tangible-images mask method.
//
//   tangible_image IMAGE [--mask prewitt|sobel|scharr|roberts|gauss|emboss]
//                  [--size M] [--sigma S] [--border suspend|clamp|reflect|fade]
//                  [--gray paper|bt601] [--maps DIR [--full-scale F]]
//                  [--probes IN.csv --forces OUT.csv] [--max-mpx N]
//
// --max-mpx raises or lowers the largest picture accepted (default 100 Mpx,
// checked from the file header before decoding).
// --maps writes the force pictures (fx, fy, magnitude, arrows), the float
// planes, maps.png (the three pictures with axes [px] and colour bars,
// drawn by matplotlib when present, else by OpenCV) and maps.txt (what each
// file shows, at what scale). Full colour is the map's largest magnitude,
// or F with --full-scale (the same F makes two maps compare by eye).
// --probes reads x,y per line (pixels, x right, y down, integer = pixel
// centre, a header line allowed) and --forces gets x,y,fx,fy: the
// normalised force (1 = a black/white edge) before any gain, fy down.
// Bad input: one line on stderr and exit status 1 (2 for usage errors).
#include <hapticfield/kernels.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.hpp"
#include "common/csv.hpp"
#include "common/mask_options.hpp"
#include "common/plots.hpp"
#include "common/simple_plot.hpp"

namespace hf = hapticfield;

namespace {

constexpr const char* usage =
    "usage: tangible_image IMAGE [options]\n"
    "Feels a picture with the tangible-images mask method.\n"
    "  IMAGE                 picture file (any format OpenCV reads)\n"
    "  --mask KIND           prewitt (default), sobel, scharr, roberts, gauss or emboss\n"
    "  --size M              mask size [px]: prewitt/gauss/emboss odd 3..129 (default 17),\n"
    "                        sobel odd 3..31 (default 3), scharr 3, roberts 2\n"
    "  --sigma S             Gaussian-derivative sigma [px], in (0, 1000] (default: size / 6)\n"
    "  --border B            suspend (default, the paper's), clamp, reflect or fade\n"
    "  --gray W              gray weights: paper (0.3 R + 0.59 G + 0.11 B, default) or bt601\n"
    "  --maps DIR            write fx, fy, magnitude and arrow pictures, float planes, maps.png\n"
    "                        (axes and colour bars) and maps.txt (the scale) into DIR\n"
    "  --full-scale F        force at full colour in the --maps pictures, in (0, 1e6]\n"
    "                        (default: each map's own largest magnitude)\n"
    "  --probes IN.csv       x,y per line [px] (x right, y down, integer = pixel centre;\n"
    "                        a header line allowed), at most 1000000 lines; needs --forces\n"
    "  --forces OUT.csv      x,y,fx,fy per probe: the normalised force (1 = black/white edge), fy down\n"
    "  --max-mpx N           largest picture accepted [megapixels], in (0, 1e6] (default 100),\n"
    "                        read from the file header before anything is decoded\n"
    "  -h, --help            this text\n"
    "Exit status: 0 done, 1 bad input (files, pictures), 2 usage error.\n";

struct Arguments {
  std::string image;
  hf::TangibleConfig options;
  hf::GrayWeights gray = hf::GrayWeights::paper;
  std::uint64_t max_pixels = hf::default_max_pixels;  ///< largest picture loaded [px]
  std::optional<std::string> maps;
  double full_scale = 0.0;  ///< full colour in the --maps pictures (0: the map's largest magnitude)
  std::optional<std::string> probes;
  std::optional<std::string> forces;
};

Arguments parse(hf::cli::Parser& p) {
  Arguments a;
  hf::cli::Input image("IMAGE");
  hf::cli::MaskOptions mask;
  while (p.next()) {
    if (mask.take(p)) continue;  // --mask, --size, --border
    if (p.is("--sigma")) {
      a.options.sigma = p.real(hf::cli::open_closed(0.0, 1000.0));
    } else if (p.is("--gray")) {
      a.gray = p.choice<hf::GrayWeights>("gray weights",
                                         {{"paper", hf::GrayWeights::paper}, {"bt601", hf::GrayWeights::bt601}});
    } else if (p.is("--max-mpx")) {
      a.max_pixels = p.megapixels();
    } else if (p.is("--full-scale")) {
      a.full_scale = p.real(hf::cli::open_closed(0.0, 1e6));
    } else if (p.is("--maps")) {
      a.maps = p.output_dir();
    } else if (p.is("--probes")) {
      a.probes = p.value();
    } else if (p.is("--forces")) {
      a.forces = p.output_file();
    } else {
      p.input_or_unknown(image);
    }
  }
  a.image = image.required();
  if (a.probes.has_value() != a.forces.has_value()) throw hf::cli::UsageError("--probes and --forces go together");
  if (a.full_scale > 0.0 && !a.maps) throw hf::cli::UsageError("--full-scale needs --maps");
  a.options = mask.apply(a.options);
  p.finish();
  return a;
}

void write_forces(const std::string& path, const std::vector<std::array<double, 2>>& probes,
                  const hf::TangibleImage& image) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw std::runtime_error("cannot write forces file '" + path + "'");
  std::fprintf(out, "x,y,fx,fy\n");
  for (const auto& [x, y] : probes) {
    const glm::dvec2 f = image.at(x, y);
    std::fprintf(out, "%.17g,%.17g,%.17g,%.17g\n", x, y, f.x, f.y);
  }
  if (std::fclose(out) != 0) throw std::runtime_error("cannot write forces file '" + path + "'");
}

/// The figure's title: what the maps show.
std::string maps_title(const Arguments& args) {
  return std::filesystem::path(args.image).filename().string() + ", mask " + hf::to_string(args.options.mask) + " " +
         std::to_string(args.options.size) + ", border " + hf::to_string(args.options.border) +
         ": normalised force (1 = a black/white edge), fy down";
}

/// maps.txt: what each file of --maps shows, and at what scale.
void write_maps_caption(const std::string& dir, const Arguments& args, double scale, const std::string& note,
                        const std::string& drawn_by) {
  const std::string path = (std::filesystem::path(dir) / "maps.txt").string();
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw hf::FileError("--maps: cannot write '" + path + "'");
  std::fprintf(out,
               "%s\n"
               "full scale: %.6g (%s)\n"
               "fx.png, fy.png: red where the component is positive (x right, y down), blue where negative,\n"
               "  brightness |component| / %.6g, one pixel per picture pixel\n"
               "magnitude.png: |F| / %.6g as gray, white = %.6g\n"
               "arrows.png: the force every 16 px over the dimmed picture, 16 px long at %.6g\n"
               "fx.tiff, fy.tiff: the components as 32-bit floats, unscaled\n"
               "maps.png: fx, fy and |F| with axes [px] and colour bars (%s)\n",
               maps_title(args).c_str(), scale, note.c_str(), scale, scale, scale, scale, drawn_by.c_str());
  if (std::fclose(out) != 0) throw hf::FileError("--maps: cannot write '" + path + "'");
}

/// maps.png drawn with OpenCV: fx, fy and |F| side by side, each with axes
/// in pixels of the picture and a colour bar from -scale to +scale (0 to
/// scale for |F|), in the colours of fx.png and magnitude.png.
cv::Mat simple_maps_figure(const hf::ForceMap& map, double scale, const std::string& title, const std::string& note) {
  namespace plot = hf::plots;
  const int side = 300;  // the longer side of each panel [px]
  const double zoom = double(side) / std::max(map.width, map.height);
  const int pw = std::max(1, static_cast<int>(std::lround(map.width * zoom)));
  const int ph = std::max(1, static_cast<int>(std::lround(map.height * zoom)));
  const int left = 60, top = 70, cell = pw + 150;
  cv::Mat figure(top + ph + 60, 3 * cell + 20, CV_8UC3, cv::Scalar(255, 255, 255));
  plot::text(figure, title, {10, 20}, 0.45);
  plot::text(figure, "full colour = " + plot::tick_text(scale) + " (" + note + ")", {10, 40}, 0.45);
  const cv::Mat fx = hf::component_picture(map, hf::ForceComponent::x, scale);
  const cv::Mat fy = hf::component_picture(map, hf::ForceComponent::y, scale);
  cv::Mat magnitude;
  cv::cvtColor(hf::magnitude_picture(map, scale), magnitude, cv::COLOR_GRAY2BGR);
  const auto signed_colour = [scale](double v) {
    const auto level = static_cast<unsigned char>(std::clamp(std::abs(v) / scale, 0.0, 1.0) * 255.0 + 0.5);
    return v >= 0.0 ? cv::Vec3b(0, 0, level) : cv::Vec3b(level, 0, 0);
  };
  const auto gray_colour = [scale](double v) {
    const auto level = static_cast<unsigned char>(std::clamp(v / scale, 0.0, 1.0) * 255.0 + 0.5);
    return cv::Vec3b(level, level, level);
  };
  const cv::Mat* panels[3] = {&fx, &fy, &magnitude};
  const char* names[3] = {"fx (red +x right, blue -x)", "fy (red +y down, blue -y)", "|F|"};
  for (int k = 0; k < 3; ++k) {
    const cv::Rect box(k * cell + left, top, pw, ph);
    cv::Mat shown;
    cv::resize(*panels[k], shown, box.size(), 0, 0, zoom >= 1.0 ? cv::INTER_NEAREST : cv::INTER_AREA);
    shown.copyTo(figure(box));
    const plot::Axes axes(box, 0.0, map.width, 0.0, map.height, true);
    axes.draw(figure, std::string(names[k]) + "   x [px]", "y [px]", false);
    const cv::Rect bar(box.x + pw + 12, top, 16, ph);
    if (k < 2)
      plot::colour_bar(figure, bar, -scale, scale, signed_colour, "force");
    else
      plot::colour_bar(figure, bar, 0.0, scale, gray_colour, "force");
  }
  return figure;
}

/// maps.png: by scripts/hapticfield_plots.py (matplotlib) when present, else
/// by OpenCV; then maps.txt.
void write_maps_figure(const Arguments& args, const hf::ForceMap& map, double scale, const std::string& note) {
  const std::string dir = *args.maps;
  const std::string path = (std::filesystem::path(dir) / "maps.png").string();
  char scale_text[32];
  std::snprintf(scale_text, sizeof scale_text, "%.9g", scale);
  std::string why;
  const bool matplotlib = hf::plots::matplotlib(
      {"forcemap", "--dir", dir, "--full-scale", scale_text, "--title", maps_title(args), "--scale-note", note}, why);
  if (!matplotlib) {
    const cv::Mat figure = simple_maps_figure(map, scale, maps_title(args), note);
    if (!cv::imwrite(path, figure)) throw hf::FileError("--maps: cannot write '" + path + "'");
  }
  const std::string drawn_by = matplotlib ? "drawn with matplotlib" : "simple plots: " + why;
  write_maps_caption(dir, args, scale, note, drawn_by);
  std::printf("wrote %s (%s)\nwrote %s\n", path.c_str(), drawn_by.c_str(),
              (std::filesystem::path(dir) / "maps.txt").string().c_str());
}

int run(const Arguments& args) {
  cv::Mat photo;
  try {
    photo = hf::cli::quiet_stderr([&] { return hf::load_image(args.image, args.max_pixels); });
  } catch (const hf::ImageError& e) {
    throw hf::ImageError(hf::cli::name_limit_flag(e.what(), "--max-mpx"));  // the user's flag, not the library's
  }
  const hf::GrayImage gray = hf::to_gray(photo, args.gray);  // decoded once
  const auto start = std::chrono::steady_clock::now();
  const hf::TangibleImage image(gray, args.options);
  const double setup_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s: %d x %d px, mask %s %d x %d, border %s, %s kernel (setup %.1f ms)\n", args.image.c_str(),
              gray.width(), gray.height(), hf::to_string(args.options.mask), args.options.size, args.options.size,
              hf::to_string(args.options.border), image.uses_integral_kernel() ? "O(1) integral" : "direct", setup_ms);

  if (args.probes) {
    const auto probes = hf::cli::read_csv<2>(*args.probes, {.columns = "x,y", .what = "probes"});
    write_forces(*args.forces, probes, image);
    std::printf("forces at %zu probes written to %s\n", probes.size(), args.forces->c_str());
  }
  if (args.maps) {
    const auto t0 = std::chrono::steady_clock::now();
    const hf::ForceMap map =
        args.options.mask == hf::MaskKind::prewitt
            ? hf::prewitt_force_map(gray, args.options.size, args.options.border, args.options.fade_px)
            : hf::force_map(image);
    const double map_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("force map in %.1f ms, largest magnitude %.3f (1 = black/white edge)\n", map_ms, map.max_magnitude());
    const double scale = hf::force_picture_scale(map, args.full_scale);
    const std::string scale_note =
        args.full_scale > 0.0 ? "fixed by --full-scale" : "this map's largest magnitude; --full-scale fixes it";
    std::printf("colour scale: full colour = %.4g (%s)\n", scale, scale_note.c_str());
    for (const std::string& path : hf::write_force_pictures(*args.maps, photo, map, args.full_scale))
      std::printf("wrote %s\n", path.c_str());
    write_maps_figure(args, map, scale, scale_note);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // errors are reported once, by us
  return hf::cli::main("tangible_image", usage, argc, argv, [](hf::cli::Parser& p) { return run(parse(p)); });
}
