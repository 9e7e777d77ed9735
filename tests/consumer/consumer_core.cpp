// Uses only the core: must compile without OpenCV or hidapi on the include path.
#include <hapticfield/core.hpp>

#include <cstdio>

#ifdef CV_VERSION
#error "the core must not pull in OpenCV"
#endif

int main() {
  using namespace hapticfield;
  struct Spring {
    glm::dvec3 force(const Probe& p) const noexcept { return -100.0 * p.position; }  // 100 N/m
  };
  AnyField field = clamp(sum(Spring{}, ZeroField{}), 1.0);
  Probe probe;
  probe.position = glm::dvec3{0.05, 0.0, 0.0};
  const glm::dvec3 f = field.force(probe);  // 5 N clamped to 1 N
  std::printf("consumer_core: fx = %.3f N\n", f.x);
  return (f.x < -0.999 && f.x > -1.001) ? 0 : 1;
}
