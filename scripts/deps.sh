#!/usr/bin/env bash
# Installs the Debian 12 packages hapticfield builds with, when any is missing.
# Needs root (or sudo) only when something has to be installed.
set -euo pipefail

packages=(g++ clang libclang-rt-14-dev cmake make pkg-config libglm-dev libopencv-dev libhidapi-dev libpugixml-dev catch2
          libasound2-dev libsndfile1-dev libtinygltf-dev libtinyobjloader-dev
          pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib python3-mypy python3-venv
          libusb-1.0-0-dev libmujoco-dev nlohmann-json3-dev python3-distributed)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "hapticfield: installing ${missing[*]}" >&2
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
