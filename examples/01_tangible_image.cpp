// tangible_image: feel a picture with the tangible-images mask method.
//
//   tangible_image IMAGE [--mask prewitt|sobel|scharr|roberts|gauss|emboss]
//                  [--size M] [--sigma S] [--border suspend|clamp|reflect|fade]
//                  [--gray paper|bt601] [--maps DIR] [--probes IN.csv --forces OUT.csv]
//                  [--max-mpx N]
//
// --max-mpx raises or lowers the largest picture accepted (default 100 Mpx,
// checked from the file header before decoding).
// --maps writes the force pictures (fx, fy, magnitude, arrows) and float
// planes; --probes reads x,y per line (pixels, x right, y down, integer =
// pixel centre, a header line allowed) and --forces gets x,y,fx,fy: the
// normalised force (1 = a black/white edge) before any gain, fy down.
// Bad input: one line on stderr and exit status 1 (2 for usage errors).
#include <hapticfield/kernels.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/utils/logger.hpp>

#include "common/cli.hpp"
#include "common/csv.hpp"

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
    "  --maps DIR            write fx, fy, magnitude and arrow pictures and float planes into DIR\n"
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
  bool size_given = false;
  hf::GrayWeights gray = hf::GrayWeights::paper;
  std::uint64_t max_pixels = hf::default_max_pixels;  ///< largest picture loaded [px]
  std::optional<std::string> maps;
  std::optional<std::string> probes;
  std::optional<std::string> forces;
};

Arguments parse(hf::cli::Parser& p) {
  Arguments a;
  while (p.next()) {
    if (p.is("--mask")) {
      a.options.mask = p.named("mask", hf::mask_kinds);
    } else if (p.is("--size")) {
      a.options.size = static_cast<int>(p.integer(1, 1000));
      a.size_given = true;
    } else if (p.is("--sigma")) {
      a.options.sigma = p.real(hf::cli::open_closed(0.0, 1000.0));
    } else if (p.is("--border")) {
      a.options.border = p.named("border", hf::border_kinds);
    } else if (p.is("--gray")) {
      a.gray = p.choice<hf::GrayWeights>("gray weights",
                                         {{"paper", hf::GrayWeights::paper}, {"bt601", hf::GrayWeights::bt601}});
    } else if (p.is("--max-mpx")) {
      a.max_pixels = static_cast<std::uint64_t>(p.real(hf::cli::open_closed(0.0, 1e6)) * 1e6);
    } else if (p.is("--maps")) {
      a.maps = p.output_dir();
    } else if (p.is("--probes")) {
      a.probes = p.value();
    } else if (p.is("--forces")) {
      a.forces = p.output_file();
    } else if (p.positional() && a.image.empty()) {
      a.image = p.token();
    } else if (p.positional()) {
      throw hf::cli::UsageError("more than one IMAGE given ('" + a.image + "', '" + p.token() + "')");
    } else {
      p.unknown();
    }
  }
  if (a.image.empty()) throw hf::cli::UsageError("no IMAGE given");
  if (a.probes.has_value() != a.forces.has_value()) throw hf::cli::UsageError("--probes and --forces go together");
  // Without --size each mask takes its own default (a fixed-size mask its only size).
  if (!a.size_given) a.options.size = hf::default_mask_size(a.options.mask);
  try {
    hf::validate_mask_size(a.options.mask, a.options.size);
  } catch (const std::invalid_argument& e) {
    throw hf::cli::UsageError(std::string("--size: ") + e.what());
  }
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
    for (const std::string& path : hf::write_force_pictures(*args.maps, photo, map))
      std::printf("wrote %s\n", path.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // errors are reported once, by us
  return hf::cli::main("tangible_image", usage, argc, argv, [](hf::cli::Parser& p) { return run(parse(p)); });
}
