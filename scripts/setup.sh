#!/usr/bin/env bash
# Installs what bayon needs (Debian 12 packages, with sudo when not root) and
# builds it in Release. Idempotent: with everything present it only runs an
# incremental build.
#   scripts/setup.sh              build into build/
#   scripts/setup.sh --sanitize   AddressSanitizer + UBSan build with clang into
#                                 build-asan/, with the libFuzzer harnesses of
#                                 tests/fuzz (scripts/fuzz.sh runs them)
#   scripts/setup.sh --target bayon only the `bayon` program (with its viewer
#                                 page), not the tests (scripts/demo.sh)
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=build
sanitize=0
cmake_args=(-DCMAKE_BUILD_TYPE=Release)
targets=()
while [ $# -gt 0 ]; do
  arg=$1
  shift
  case "$arg" in
    --target)
      [ $# -gt 0 ] || { echo "setup.sh: --target needs a target name" >&2; exit 2; }
      targets+=(--target "$1")
      shift ;;
    --sanitize)
      # clang, because libFuzzer comes with it; line tables only, because full
      # debug information doubles the build time and stack traces need no more.
      build_dir=build-asan
      sanitize=1
      cmake_args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DBAYON_SANITIZE=ON
                  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
                  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG"
                  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG"
                  -DBAYON_BUILD_BENCHMARKS=OFF -DBAYON_WERROR=OFF) ;;
    *) echo "setup.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

packages=(
  build-essential cmake ninja-build pkg-config git ccache clang-format
  colmap sqlite3 libsqlite3-dev
  libeigen3-dev libceres-dev libgoogle-glog-dev libopencv-dev
  libpcl-dev libcgal-dev libopenmesh-dev libtbb-dev
  libboost-graph-dev  # mesh's delaunay_graph_cut: Boykov-Kolmogorov max flow
  libcli11-dev nlohmann-json3-dev libexiv2-dev libtinygltf-dev libstb-dev
  libproj-dev  # import_control: survey CRSs into a local projected frame
  libgtest-dev libgmock-dev libbenchmark-dev
  chromium  # viewer_test opens the page of bayon viewer in it
  assimp-utils  # texture_test opens the exported models with Assimp
)
# bayon viewer's page is built with npm (tools/viewer); a Node.js from another
# source (which brings its own npm) is kept.
if ! command -v npm >/dev/null; then packages+=(nodejs npm); fi
# The sanitizer build: clang with its runtimes (ASan, UBSan, libFuzzer).
if [ "$sanitize" = 1 ]; then packages+=(clang libclang-rt-14-dev); fi
missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo=sudo; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

if command -v ccache >/dev/null; then
  # One compiler cache for every clone on this machine (CI builds a fresh
  # clone in another folder): paths under the clone are hashed relative to it
  # (base_dir), the working directory not at all (hash_dir), and __FILE__
  # names files relative to the clone (-ffile-prefix-map), so the same source
  # in another folder hits. The launcher carries the settings, so a later
  # `cmake --build` or `ninja` uses them too.
  launcher="$(command -v cmake);-E;env;CCACHE_BASEDIR=$PWD;CCACHE_NOHASHDIR=1;$(command -v ccache)"
  cmake_args+=("-DCMAKE_CXX_COMPILER_LAUNCHER=$launcher" "-DCMAKE_C_COMPILER_LAUNCHER=$launcher"
               "-DCMAKE_CXX_FLAGS_INIT=-ffile-prefix-map=$PWD/=")
fi
if [ ! -f "$build_dir/build.ninja" ]; then
  cmake -S . -B "$build_dir" -G Ninja "${cmake_args[@]}" >/dev/null
fi
cmake --build "$build_dir" -j"$(nproc)" "${targets[@]}"
echo "setup: bayon is built in $build_dir/ ($build_dir/tools/bayon)"
