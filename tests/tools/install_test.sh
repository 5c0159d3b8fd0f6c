#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's install command works: `cmake --install BUILD --prefix P` puts the `strike` tool,
# libstrike, strike.h, the CMake package and the pkg-config file (and the LV2 bundle when it was
# built) under P, and a C program builds and runs against that tree with no LD_LIBRARY_PATH:
# through pkg-config, through find_package(strike), and through pkg-config again after the tree
# was moved (the .pc file is relocatable).
# Usage: install_test.sh BUILD_DIR WORK_DIR LIBDIR LV2(0|1) C_COMPILER CMAKE_GENERATOR
set -euo pipefail
build=$1 work=$2 libdir=$3 lv2=$4 cc=$5 generator=$6
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$prefix" >"$work/install.log" || { cat "$work/install.log"; fail "cmake --install"; }
for f in bin/strike include/strike/strike.h "$libdir/libstrike.so" "$libdir/libstrike_static.a" \
         "$libdir/cmake/strike/strikeConfig.cmake" "$libdir/cmake/strike/strikeConfigVersion.cmake" "$libdir/pkgconfig/strike.pc"; do
  [ -e "$prefix/$f" ] || fail "$f is not installed"
done
if [ "$lv2" = 1 ]; then
  for f in strike_lv2.so manifest.ttl strike.ttl strike.modes; do
    [ -e "$prefix/$libdir/lv2/strike.lv2/$f" ] || fail "$libdir/lv2/strike.lv2/$f is not installed"
  done
fi

# The tool links libstrike (0.4): it must find the installed copy through its RUNPATH
# ($ORIGIN/../LIBDIR), not the build tree's or one elsewhere on the system.
uses_own_libstrike() {  # $1: the strike binary, $2: the tree it must load libstrike from
  local resolved
  resolved=$(env -u LD_LIBRARY_PATH ldd "$1" | awk '/libstrike\.so/ {print $3}')
  [ -n "$resolved" ] || return 0  # linked statically: nothing to resolve
  case "$(readlink -f "$resolved")" in
    "$(readlink -f "$2")"/*) return 0 ;;
    *) echo "FAIL: $1 loads libstrike from $resolved, not from $2" >&2; return 1 ;;
  esac
}
uses_own_libstrike "$prefix/bin/strike" "$prefix" || fail "the installed strike does not load its own libstrike"

# The installed tool runs and teaches.
env -u LD_LIBRARY_PATH "$prefix/bin/strike" --help >"$work/help.txt" || fail "installed strike --help failed"
grep -q 'usage: strike COMMAND' "$work/help.txt" || fail "installed strike --help does not print its usage"

# A tiny C program: the header and the loaded library agree, and a context renders silence.
cat >"$work/main.c" <<'C'
#include <stdio.h>
#include <strike/strike.h>
int main(void) {
  strike_context_config cfg = strike_context_config_default();
  strike_context ctx = NULL;
  float left[64], right[64];
  float* out[2] = {left, right};
  if (strike_get_version() != STRIKE_VERSION) return 2;
  if (strike_context_create(&cfg, &ctx) != STRIKE_OK) return 3;
  if (strike_render(ctx, out, 2, 64) != STRIKE_OK || left[0] != 0.0f) return 4;
  strike_context_destroy(ctx);
  printf("libstrike %u.%u.%u ok\n", STRIKE_VERSION_MAJOR, STRIKE_VERSION_MINOR, STRIKE_VERSION_PATCH);
  return 0;
}
C

build_with_pkg_config() {  # $1: the prefix, $2: the program
  local flags
  flags=$(PKG_CONFIG_PATH=$1/$libdir/pkgconfig pkg-config --cflags --libs strike) || fail "pkg-config does not find strike under $1"
  # shellcheck disable=SC2086  # flags are words
  "$cc" -std=c99 -Wall -Werror "$work/main.c" $flags -o "$2" || fail "cc with pkg-config flags: $flags"
  env -u LD_LIBRARY_PATH "$2" || fail "the pkg-config build does not run without LD_LIBRARY_PATH ($flags)"
}
build_with_pkg_config "$prefix" "$work/main_pkg_config"

mkdir -p "$work/consumer"
cat >"$work/consumer/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.22)
project(strike_consumer C)
find_package(strike 0.4 REQUIRED)
add_executable(main ../main.c)
target_link_libraries(main PRIVATE strike::strike)
CMAKE
cmake -S "$work/consumer" -B "$work/consumer/build" -G "$generator" -DCMAKE_C_COMPILER="$cc" \
      -DCMAKE_PREFIX_PATH="$prefix" >"$work/consumer.log" 2>&1 || { cat "$work/consumer.log"; fail "find_package(strike 0.4)"; }
cmake --build "$work/consumer/build" >>"$work/consumer.log" 2>&1 || { cat "$work/consumer.log"; fail "building against strike::strike"; }
env -u LD_LIBRARY_PATH "$work/consumer/build/main" || fail "the find_package build does not run"

# Relocated: the same tree moved elsewhere still works through pkg-config.
mv "$prefix" "$work/moved"
build_with_pkg_config "$work/moved" "$work/main_moved"
uses_own_libstrike "$work/moved/bin/strike" "$work/moved" || fail "the moved strike does not load its own libstrike"
env -u LD_LIBRARY_PATH "$work/moved/bin/strike" --version || fail "the moved strike does not run"
echo "install tree: strike, libstrike, strike.h, CMake package, pkg-config$([ "$lv2" = 1 ] && echo ", LV2 bundle") all work"
