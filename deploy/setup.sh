#!/usr/bin/env bash
# Installs every Debian 12 package Keel's build, tests, benchmarks and demo need.
# Non-interactive and idempotent: packages already present are skipped by apt.
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config git clang-format
  # product libraries (see docs/design.md "Layers")
  libboost-dev libboost-system-dev libboost-filesystem-dev libboost-regex-dev
  libboost-iostreams-dev libboost-program-options-dev libboost-thread-dev
  libeigen3-dev libceres-dev libpcl-dev libopencv-dev libcgal-dev libnanoflann-dev
  libdraco-dev draco libsqlite3-dev nlohmann-json3-dev libcli11-dev
  libspdlog-dev libyaml-cpp-dev libssl-dev libarchive-dev
  # WGS 84 <-> the world frame's local ENU (core/geodesy.h)
  libproj-dev
  # PNG and JPEG camera images (worker/io/image_codec.cc)
  libpng-dev libjpeg-dev
  # PostgreSQL store for several replicas (issue 14); tests start a private server
  libpqxx-dev postgresql
  # deploy/ checks (tests/deploy): systemd-analyze, nginx -t
  systemd nginx-light
  # single-node Slurm for deploy/slurm_workers; iproute2 for the multi-host test's namespaces
  slurm-wlm munge iproute2
  # ROS1 bag chunks: Keel reads bags itself (worker/io/bag/ros1_bag.h), bz2 through libbz2 and
  # lz4 through liblz4 (below)
  libbz2-dev
  # keel-sim and tests only: ROS1's C++ bag library and messages, the independent writer of
  # keel-sim's bags and of the message tests (keel, keel-worker, keel-server do not link them)
  librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev
  libtf2-msgs-dev libstd-msgs-dev libroslz4-dev
  # ROS 2 bags (MCAP chunk compression; lz4 ROS1 chunks too) and their fuzzers (clang 14's libFuzzer)
  libzstd-dev liblz4-dev clang libclang-rt-14-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-rosbag python3-sensor-msgs python3-nav-msgs python3-geometry-msgs
  python3-tf2-msgs python3-numpy curl
  # reference tool for the C2C distance test (compare/cloudcompare_c2c)
  cloudcompare
  # the web dashboard's browser tests
  chromium
  # fuzzing (tests/fuzz: libFuzzer with ASan/UBSan) and the TLS tests' openssl command
  clang libclang-rt-14-dev openssl
)
# Node.js and npm for web/'s packages: Debian's, unless the machine already has a Node.js with
# npm (e.g. NodeSource's nodejs, which bundles npm and conflicts with Debian's npm package).
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "keel setup: all ${#packages[@]} packages present"
else
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  echo "keel setup: installing ${#missing[@]} packages: ${missing[*]}"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  echo "keel setup: done"
fi

# three.js, uPlot, 3d-tiles-renderer and playwright-core for web/, as package-lock.json pins them (the
# build copies what the pages load from web/node_modules; nothing is fetched at build time).
web="$(cd "$(dirname "$0")/../web" && pwd)"
if [ ! -f "$web/node_modules/.package-lock.json" ] ||
   [ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]; then
  echo "keel setup: npm ci in web/"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
fi

# The Kubernetes and KEDA schemas that tests/deploy checks deploy/k8s against, as pinned.
checks="$(cd "$(dirname "$0")/../tests/deploy" && pwd)"
if [ ! -f "$checks/node_modules/.package-lock.json" ] ||
   [ "$checks/package-lock.json" -nt "$checks/node_modules/.package-lock.json" ]; then
  echo "keel setup: npm ci in tests/deploy/"
  (cd "$checks" && npm ci --no-audit --no-fund --loglevel=error)
fi
