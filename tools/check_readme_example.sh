#!/usr/bin/env bash
# Extract the C example from README.md (the block after "<!-- example -->"),
# install the library into a temporary prefix, compile the example with
# pkg-config against it, and run it.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
awk '/<!-- example -->/{on=1; next} on && /^```c/{grab=1; next} grab && /^```/{exit} grab{print}' README.md > "$tmp/example.c"
test -s "$tmp/example.c" || { echo "no example found in README.md"; exit 1; }
make -s BUILD="$tmp/build" install PREFIX="$tmp/prefix" >/dev/null
export PKG_CONFIG_PATH="$tmp/prefix/lib/pkgconfig"
cc -std=c11 -Wall -Wextra -Werror $(pkg-config --cflags shlight) "$tmp/example.c" -o "$tmp/example" \
   $(pkg-config --libs --static shlight)
LD_LIBRARY_PATH="$tmp/prefix/lib" "$tmp/example"
echo "README example: ok"
