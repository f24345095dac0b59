#!/usr/bin/env bash
# Installs the system packages aerie needs on Debian/Ubuntu, once: the Vulkan loader, lavapipe
# (Mesa's CPU Vulkan driver), the Khronos validation layer, shaderc/glslang/SPIRV-Tools static
# libraries for the shader build, and Xvfb + the X11 client libraries for windows and their
# tests. Idempotent; uses sudo when not root.
set -euo pipefail

# xvfb + the X11 client libraries winit loads at run time (windowed presentation and its tests).
packages=(libvulkan1 mesa-vulkan-drivers vulkan-validationlayers libshaderc-dev glslang-dev spirv-tools
  xvfb libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0 libxtst6
  gcc g++  # the shared-memory header's C99 and C++11 writer tests, the CIGI Class Library host
  # A big-endian CIGI host (tests/cigi-host, s390x under qemu-user): ~58 MB, ~20 s to install.
  g++-s390x-linux-gnu qemu-user)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all system packages present"
  exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "setup: missing packages ${missing[*]} and no apt-get: install them with your package manager" >&2
  exit 1
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  sudo="sudo"
fi
echo "setup: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
