#!/usr/bin/env bash
# Build TSWAP (Okumura & Defago, https://github.com/Kei18/tswap) from a local checkout of
# its public source, outside this repository.
#
#   benchmarks/tswap/build.sh SRC [BUILD]
#
# SRC: a checkout with its submodules (git clone --recursive
# https://github.com/Kei18/tswap.git SRC): third_party/grid-pathfinding and
# third_party/googletest must be present. BUILD: the build folder (default SRC/build).
# Prints the path of the binary (BUILD/app) on its last line; pass it to adapter.py --bin.
# Nothing of TSWAP is copied into this repository and its source is not modified.
set -euo pipefail

SRC=${1:?usage: build.sh SRC [BUILD]}
SRC=$(cd "$SRC" && pwd)
BUILD=${2:-$SRC/build}

for sub in third_party/grid-pathfinding/graph third_party/googletest; do
  if [ ! -f "$SRC/$sub/CMakeLists.txt" ]; then
    echo "missing $SRC/$sub: check out the submodules (git submodule update --init)" >&2
    exit 1
  fi
done

# Build fixes, each a configure flag (none touches the source):
# - CMAKE_POLICY_VERSION_MINIMUM=3.5: TSWAP and its googletest declare
#   cmake_minimum_required(VERSION 3.1 / 2.x); CMake 4 refuses versions below 3.5 unless
#   this is set (CMake 3.x ignores it).
# - CMAKE_BUILD_TYPE=Release: the upstream lists set -O3 themselves; Release only keeps
#   a debug build type from the environment out.
# - -include cstring: grid-pathfinding's graph.cpp calls std::memset without including
#   <cstring> (the missing include; older standard libraries pulled it in through other
#   headers, GCC 12's do not). Forcing the header in is the same as adding the #include.
cmake -S "$SRC" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  -DCMAKE_CXX_FLAGS="-include cstring" >&2
# only the solver binary; the test targets are not needed
cmake --build "$BUILD" --target app -j "${JOBS:-2}" >&2
echo "$BUILD/app"
