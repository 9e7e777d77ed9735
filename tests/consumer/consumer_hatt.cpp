// A HaTT-only user: reads a model file (pugixml through hapticfield::hatt)
// and renders a short stroke; needs no OpenCV.
#include <hapticfield/texture/hatt.hpp>

#include <cstdio>

int main(int argc, char** argv) {
  namespace tx = hapticfield::texture;
  if (argc != 2) return 2;
  const tx::HattModelSet set = tx::load_hatt_model_set(argv[1]);
  tx::HattTexture<> texture(set, tx::HattConfig{});
  hapticfield::Probe probe;
  probe.velocity = {0.1, 0.0, 0.0};  // [m/s]
  probe.normal_force = 1.0;          // [N]
  double largest = 0.0;
  for (int i = 0; i < 1000; ++i)
    largest = std::max(largest, glm::length(texture.force(probe)));
  std::printf("consumer_hatt: '%s' at %.0f Hz, largest force %.3f N\n", set.name.c_str(), set.sample_rate, largest);
  return largest > 0.0 ? 0 : 1;
}
