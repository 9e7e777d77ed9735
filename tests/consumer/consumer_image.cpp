// Uses the whole library through the umbrella header: loads a picture and
// feels it at its centre.
#include <hapticfield/hapticfield.hpp>

#include <cstdio>

int main(int argc, char** argv) {
  namespace hf = hapticfield;
  if (argc != 2) return 2;
  const hf::GrayImage gray = hf::load_gray(argv[1]);
  hf::TangibleImageField<> field(hf::TangibleImage(gray, {}), hf::PlaneMapping::kim_kwon(gray.width(), gray.height()),
                                 1.0);
  hf::AnyField any = hf::clamp(std::move(field), 3.3);
  double largest = 0.0;
  hf::Probe probe;
  for (int i = -20; i <= 20; ++i) {
    probe.position = {i * 1e-3, 0.0, 0.0};  // a 40 mm stroke across the picture
    largest = std::max(largest, glm::length(any.force(probe)));
  }
  std::printf("consumer_image: %d x %d px, largest force %.3f N\n", gray.width(), gray.height(), largest);
  return largest > 0.0 && largest <= 3.3 ? 0 : 1;
}
