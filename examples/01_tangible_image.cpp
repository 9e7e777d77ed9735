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

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace hf = hapticfield;

namespace {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

constexpr const char* usage =
    "usage: tangible_image IMAGE [--mask prewitt|sobel|scharr|roberts|gauss|emboss] [--size M]\n"
    "                      [--sigma S] [--border suspend|clamp|reflect|fade] [--gray paper|bt601]\n"
    "                      [--maps DIR] [--probes IN.csv --forces OUT.csv] [--max-mpx N]\n";

struct Arguments {
  std::string image;
  hf::TangibleOptions options;
  bool size_given = false;
  hf::GrayWeights gray = hf::GrayWeights::paper;
  std::uint64_t max_pixels = hf::default_max_pixels;  ///< largest picture loaded [px]
  std::optional<std::string> maps;
  std::optional<std::string> probes;
  std::optional<std::string> forces;
};

int parse_int(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  int value = 0;
  try {
    value = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty()) throw UsageError(flag + " expects an integer, got '" + text + "'");
  return value;
}

double parse_double(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') throw UsageError(flag + " expects a number, got '" + text + "'");
  return value;
}

Arguments parse(int argc, char** argv) {
  Arguments a;
  std::vector<std::string> args(argv + 1, argv + argc);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    const auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw UsageError(arg + " needs a value");
      return args[++i];
    };
    if (arg == "--help" || arg == "-h") {
      std::cout << usage;
      std::exit(0);
    } else if (arg == "--mask") {
      const std::string m = value();
      if (m == "prewitt") a.options.mask = hf::MaskKind::prewitt;
      else if (m == "sobel") a.options.mask = hf::MaskKind::sobel;
      else if (m == "scharr") a.options.mask = hf::MaskKind::scharr;
      else if (m == "roberts") a.options.mask = hf::MaskKind::roberts;
      else if (m == "gauss") a.options.mask = hf::MaskKind::gaussian;
      else if (m == "emboss") a.options.mask = hf::MaskKind::emboss;
      else throw UsageError("unknown mask '" + m + "' (prewitt, sobel, scharr, roberts, gauss, emboss)");
    } else if (arg == "--size") {
      a.options.size = parse_int(arg, value());
      a.size_given = true;
    } else if (arg == "--sigma") {
      a.options.sigma = parse_double(arg, value());
      if (!std::isfinite(a.options.sigma) || a.options.sigma <= 0.0)
        throw UsageError("--sigma must be a positive number of pixels");
    } else if (arg == "--border") {
      const std::string b = value();
      if (b == "suspend") a.options.border = hf::Border::suspend;
      else if (b == "clamp") a.options.border = hf::Border::clamp;
      else if (b == "reflect") a.options.border = hf::Border::reflect;
      else if (b == "fade") a.options.border = hf::Border::fade;
      else throw UsageError("unknown border '" + b + "' (suspend, clamp, reflect, fade)");
    } else if (arg == "--gray") {
      const std::string g = value();
      if (g == "paper") a.gray = hf::GrayWeights::paper;
      else if (g == "bt601") a.gray = hf::GrayWeights::bt601;
      else throw UsageError("unknown gray weights '" + g + "' (paper, bt601)");
    } else if (arg == "--max-mpx") {
      const double mpx = parse_double(arg, value());
      if (!std::isfinite(mpx) || mpx <= 0.0 || mpx > 1e6)
        throw UsageError("--max-mpx must be a number of megapixels in (0, 1e6]");
      a.max_pixels = static_cast<std::uint64_t>(mpx * 1e6);
    } else if (arg == "--maps") {
      a.maps = value();
    } else if (arg == "--probes") {
      a.probes = value();
    } else if (arg == "--forces") {
      a.forces = value();
    } else if (!arg.empty() && arg[0] == '-') {
      throw UsageError("unknown option '" + arg + "'");
    } else if (a.image.empty()) {
      a.image = arg;
    } else {
      throw UsageError("more than one IMAGE given ('" + a.image + "', '" + arg + "')");
    }
  }
  if (a.image.empty()) throw UsageError("no IMAGE given");
  if (a.probes.has_value() != a.forces.has_value()) throw UsageError("--probes and --forces go together");
  // Fixed-size masks take their only size unless one was given.
  if (!a.size_given && a.options.mask == hf::MaskKind::roberts) a.options.size = 2;
  if (!a.size_given && (a.options.mask == hf::MaskKind::scharr || a.options.mask == hf::MaskKind::sobel))
    a.options.size = 3;
  return a;
}

/// Reads x,y probe positions [px]; a first line that is not numeric is a header.
std::vector<glm::dvec2> read_probes(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open probes file '" + path + "'");
  std::vector<glm::dvec2> probes;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    const auto comma = line.find(',');
    const auto parse_field = [](const std::string& s, double& out) {
      const auto first = s.find_first_not_of(" \t");
      const auto last = s.find_last_not_of(" \t");
      if (first == std::string::npos) return false;
      const std::string t = s.substr(first, last - first + 1);
      char* end = nullptr;
      out = std::strtod(t.c_str(), &end);
      return *end == '\0';
    };
    double x = 0.0;
    double y = 0.0;
    const bool ok = comma != std::string::npos && parse_field(line.substr(0, comma), x) &&
                    parse_field(line.substr(comma + 1), y);
    if (!ok) {
      if (probes.empty() && number == 1) continue;  // header line
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected 'x,y', got '" + line + "'");
    }
    probes.push_back({x, y});
  }
  return probes;
}

void write_forces(const std::string& path, const std::vector<glm::dvec2>& probes, const hf::TangibleImage& image) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw std::runtime_error("cannot write forces file '" + path + "'");
  std::fprintf(out, "x,y,fx,fy\n");
  for (const glm::dvec2& p : probes) {
    const glm::dvec2 f = image.at(p.x, p.y);
    std::fprintf(out, "%.17g,%.17g,%.17g,%.17g\n", p.x, p.y, f.x, f.y);
  }
  if (std::fclose(out) != 0) throw std::runtime_error("cannot write forces file '" + path + "'");
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  try {
    args = parse(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "tangible_image: " << e.what() << " (--help shows the usage)\n";
    return 2;
  }
  try {
    const cv::Mat photo = hf::load_image(args.image, args.max_pixels);
    const hf::GrayImage gray = hf::to_gray(photo, args.gray);
    const auto start = std::chrono::steady_clock::now();
    const hf::TangibleImage image(gray, args.options);
    const double setup_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    std::printf("%s: %d x %d px, mask %s %d x %d, border %s, %s kernel (setup %.1f ms)\n", args.image.c_str(),
                gray.width(), gray.height(), hf::to_string(args.options.mask), args.options.size, args.options.size,
                hf::to_string(args.options.border), image.uses_integral_kernel() ? "O(1) integral" : "direct",
                setup_ms);

    if (args.probes) {
      const std::vector<glm::dvec2> probes = read_probes(*args.probes);
      write_forces(*args.forces, probes, image);
      std::printf("forces at %zu probes written to %s\n", probes.size(), args.forces->c_str());
    }
    if (args.maps) {
      const auto t0 = std::chrono::steady_clock::now();
      const hf::ForceMap map = args.options.mask == hf::MaskKind::prewitt
                                   ? hf::prewitt_force_map(gray, args.options.size, args.options.border,
                                                           args.options.fade_px)
                                   : hf::force_map(image);
      const double map_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      std::printf("force map in %.1f ms, largest magnitude %.3f (1 = black/white edge)\n", map_ms,
                  map.max_magnitude());
      for (const std::string& path : hf::write_force_pictures(*args.maps, photo, map))
        std::printf("wrote %s\n", path.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "tangible_image: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
