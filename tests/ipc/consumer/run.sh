#!/usr/bin/env bash
# Installs the handtrack_client component of BUILD into a scratch prefix, then builds and runs
# applications against it with find_package(handtrack) and with pkg-config.
#   run.sh BUILD_DIR WORK_DIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="$1" work="$2"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
cmake --install "$build" --component handtrack_client --prefix "$prefix" >/dev/null
libdir="$(dirname "$(find "$prefix" -name 'libhandtrack_client.so' | head -n1)")"
cmake -S "$here" -B "$work/build" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/build" >/dev/null
LD_LIBRARY_PATH="$libdir" "$work/build/consumer_cpp"
LD_LIBRARY_PATH="$libdir" "$work/build/consumer_c"
# pkg-config, the way a Makefile would build a C client
export PKG_CONFIG_PATH="$libdir/pkgconfig"
cc -std=c11 -Wall -Wextra -Werror "$here/consumer.c" $(pkg-config --cflags --libs handtrack) -o "$work/consumer_pc"
LD_LIBRARY_PATH="$libdir" "$work/consumer_pc"
test -x "$prefix/bin/handtrack-cat"
test -f "$prefix/lib/python3/dist-packages/handtrack/__init__.py"
echo "installed package ok"
