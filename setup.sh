#!/usr/bin/env bash
# Installs every Debian 12 package Tessera's build, tests and benchmarks need.
# Idempotent; run as root (or with sudo available).
set -euo pipefail
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
PKGS=(
  build-essential cmake pkg-config ninja-build
  libzmq3-dev cppzmq-dev liblzo2-dev liblz4-dev libzstd-dev
  libosmesa6-dev libspdlog-dev libfmt-dev libyaml-cpp-dev libcli11-dev
  libpng-dev libsdl2-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  gnuplot-nox xvfb x11-apps imagemagick clang
  docker-compose
)
missing=()
for p in "${PKGS[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
