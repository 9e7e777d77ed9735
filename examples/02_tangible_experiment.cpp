// tangible_experiment: the tangible-images paper's section 5 as tables.
//
//   tangible_experiment [--size N]
//
// 1. Force noise against mask size on a white-noise picture, measured and
//    as the closed-form law predicts.
// 2. The largest Prewitt mask that still feels two lines 2 mm apart as two,
//    at several picture resolutions.
// 3. The force at a gray edge against its contrast.
#include <hapticfield/kernels.hpp>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "common/cli.hpp"

namespace hf = hapticfield;

namespace {

constexpr const char* usage =
    "usage: tangible_experiment [--size N]\n"
    "Prints the tangible-images paper's section 5 experiments as tables.\n"
    "  --size N     side of the uniform-noise picture [px], 256..8192 (default 2048)\n"
    "  -h, --help   this text\n"
    "Exit status: 0 done, 2 usage error.\n";

int run(int n) {
  std::mt19937 rng(2008);
  std::uniform_real_distribution<double> level(0.0, 255.0);
  hf::GrayImage noise(n, n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      noise.at(x, y) = level(rng);
  const double sigma = 255.0 / std::sqrt(12.0);  // uniform over [0, 255]

  std::printf("1. Force noise on a %d x %d uniform-noise picture (sigma = %.1f gray levels)\n\n", n, n, sigma);
  std::printf("| m | predicted sigma_F | measured fx | measured fy | error | edge SNR (1 / sigma_F) |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (int m : {5, 9, 17, 33, 65}) {
    const double predicted = hf::prewitt_noise_std(m, sigma);
    const glm::dvec2 measured = hf::prewitt_force_noise(noise, m);
    const double error = std::max(std::abs(measured.x / predicted - 1.0), std::abs(measured.y / predicted - 1.0));
    std::printf("| %d | %.4f | %.4f | %.4f | %.1f%% | %.1f |\n", m, predicted, measured.x, measured.y, 100.0 * error,
                1.0 / predicted);
  }

  std::printf("\n2. Largest Prewitt mask that feels two thin lines 2 mm apart as two\n\n");
  std::printf("| resolution [px/mm] | separation [px] | largest m | smallest separation felt by m = 17 [mm] |\n");
  std::printf("|---|---|---|---|\n");
  for (double rho : {2.0, 4.0, 6.4, 8.0, 16.0}) {
    std::printf("| %.1f | %.0f | %d | %.2f |\n", rho, std::floor(2.0 * rho + 1e-9),
                hf::largest_separating_prewitt(2.0, rho), hf::prewitt_min_separation_px(17) / rho);
  }

  std::printf("\n3. Force at a gray edge (levels 127.5 +- 127.5 c) against contrast c, m = 17\n\n");
  std::printf("| contrast c | fx |\n|---|---|\n");
  for (double c = 0.2; c <= 1.0001; c += 0.2) {
    hf::GrayImage edge(64, 64, 127.5 + 127.5 * c);
    for (int y = 0; y < 64; ++y)
      for (int x = 32; x < 64; ++x)
        edge.at(x, y) = 127.5 - 127.5 * c;
    const hf::TangibleImage image(edge, {hf::MaskKind::prewitt, 17});
    std::printf("| %.1f | %.6f |\n", c, image.at(32.0, 32.0).x);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return hf::cli::main("tangible_experiment", usage, argc, argv, [](hf::cli::Parser& p) {
    int n = 2048;
    while (p.next()) {
      if (p.is("--size"))
        n = static_cast<int>(p.integer(256, 8192));
      else
        p.unknown();
    }
    p.finish();
    return run(n);
  });
}
