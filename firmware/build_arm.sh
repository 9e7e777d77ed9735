#!/usr/bin/env bash
# Builds the firmware core (firmware/core_build.cpp) for Cortex-M0+ (RP2040)
# and Cortex-M7 (Teensy 4) with Debian's arm-none-eabi-g++ and prints the
# object's size (text / data / bss [bytes]). Usage: firmware/build_arm.sh [outdir]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build-arm}
mkdir -p "$out"
flags=(-std=c++20 -Os -ffreestanding -fno-exceptions -fno-rtti -ffunction-sections -fdata-sections
       -Wall -Wextra -Wpedantic -Werror -Iinclude)
build() {
  local name=$1; shift
  arm-none-eabi-g++ "${flags[@]}" "$@" -c firmware/core_build.cpp -o "$out/core_$name.o"
  echo "$name ($*):"
  arm-none-eabi-size "$out/core_$name.o"
}
build cortex-m0plus -mcpu=cortex-m0plus -mthumb
build cortex-m7 -mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard
