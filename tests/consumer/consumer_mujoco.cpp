// A MuJoCo bridge user: hapticfield::mujoco brings MuJoCo's headers and libmujoco.
#include <hapticfield/physics/mujoco_bridge.hpp>

#include <cstdio>
#include <type_traits>

int main() {
  static_assert(std::is_class_v<hapticfield::MujocoBridge>);
  const int version = mj_version();  // 222 for MuJoCo 2.2.2: libmujoco is linked and loads
  std::printf("consumer_mujoco: MuJoCo %d\n", version);
  return version > 0 ? 0 : 1;
}
