#!/usr/bin/env bash
# The public/internal boundary (README "Layout"), checked on a build and on the sources:
#  1. BUILD/libshlight.so exports exactly the functions include/shlight.h declares, all
#     shl_[a-z]* (no internal shl__* symbol, no stray global);
#  2. its SONAME is libshlight.so.MAJOR, and libshlight.so -> libshlight.so.MAJOR ->
#     libshlight.so.X.Y.Z, the version being SHL_VERSION_STRING of include/shlight.h;
#  3. under bench/ and tests/, library internals are reached only through the allowed
#     internal headers below: no other src/ or simd/ header is included, no file declares
#     a shl__ symbol itself, every shl__ name used is declared in an allowed header, and a
#     file that names one includes an allowed header (directly or through a header of
#     bench/ or tests/);
#  4. no program built under BUILD/tests, BUILD/bench or BUILD/tools loads libshlight.so:
#     they link the static archive or the objects, where hidden shl__ symbols resolve.
# Usage: tools/check_symbols.sh [BUILD]   (default build; `make check-symbols` builds first)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}

# The internal headers bench/ and tests/ may include (only in programs linked statically).
allowed=(src/internal.h src/zh_tables.h src/sh_basis.h src/sphere.h src/sh_rotate.h src/quad.h src/brdf.h src/polygon.h src/parallel.h src/grid.h src/agrid.h simd/kernel_api.h simd/isa_list.h)

fail=0
err() { echo "check_symbols: $*" >&2; fail=1; }

# ---- 1, 2: the shared library
version=$(sed -n 's/^#define SHL_VERSION_STRING "\([0-9.]*\)"$/\1/p' include/shlight.h)
soname=libshlight.so.${version%%.*}
lib=$build/libshlight.so
[ -n "$version" ] || { echo "check_symbols: no SHL_VERSION_STRING in include/shlight.h" >&2; exit 1; }
[ -e "$lib" ] || { echo "check_symbols: $lib not built (make $lib)" >&2; exit 1; }

exported=$(nm -D --defined-only "$lib" | awk '{print $NF}' | sort -u)
declared=$(${CC:-cc} -E -P -Iinclude include/shlight.h | grep -o '\bshl_[a-z][a-z0-9_]*[[:space:]]*(' |
           tr -d '( \t' | sort -u)
bad=$(grep -v '^shl_[a-z]' <<<"$exported" || true)
[ -z "$bad" ] || err "$lib exports symbols outside shl_[a-z]*: $(echo $bad)"
missing=$(comm -13 <(echo "$exported") <(echo "$declared"))
[ -z "$missing" ] || err "declared in shlight.h but not exported: $(echo $missing)"
extra=$(comm -23 <(echo "$exported") <(echo "$declared"))
[ -z "$extra" ] || err "exported but not declared in shlight.h: $(echo $extra)"

got=$(readelf -d "$lib" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
[ "$got" = "$soname" ] || err "$lib: SONAME '$got', expected '$soname'"
[ "$(readlink "$build/libshlight.so")" = "$soname" ] || err "$build/libshlight.so is not a symlink to $soname"
[ "$(readlink "$build/$soname")" = "libshlight.so.$version" ] ||
    err "$build/$soname is not a symlink to libshlight.so.$version"
[ -f "$build/libshlight.so.$version" ] && [ ! -L "$build/libshlight.so.$version" ] ||
    err "$build/libshlight.so.$version is not a regular file"

# ---- 3: sources of bench/ and tests/
is_allowed() { local a; for a in "${allowed[@]}"; do [ "$1" = "$a" ] && return 0; done; return 1; }
# The library header (src/X or simd/X) that `#include "NAME"` in FILE names, if any.
lib_header() {
    local name=$1 file=$2 p
    case $name in ../src/* | ../simd/* | ../../src/* | ../../simd/*) p=${name##*../}; [ -f "$p" ] && echo "$p"; return ;; esac
    [ -f "$(dirname "$file")/$name" ] && return   # a header next to FILE (bench/common, tests)
    for p in "src/$name" "simd/$name"; do [ -f "$p" ] && { echo "$p"; return; }; done
    return 0
}
# Quoted includes of FILE, followed through headers of bench/ and tests/ (depth <= 4):
# prints the library headers reached.
lib_includes() {
    local file=$1 depth=${2:-0} name h local_h
    [ "$depth" -le 4 ] || return 0
    for name in $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$file"); do
        h=$(lib_header "$name" "$file")
        if [ -n "$h" ]; then echo "$h"; continue; fi
        local_h=$(dirname "$file")/$name
        [ -f "$local_h" ] && lib_includes "$local_h" $((depth + 1))
    done
    return 0
}

allowed_text=$(cat "${allowed[@]}")
while IFS= read -r f; do
    direct=$(for name in $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$f"); do
                 lib_header "$name" "$f"; done)
    for h in $direct; do is_allowed "$h" || err "$f includes $h, not an allowed internal header"; done
    code=$(perl -0777 -pe 's{/\*.*?\*/}{}gs; s{//[^\n]*}{}g' "$f")   # mentions in comments do not count
    grep -q 'shl__' <<<"$code" || continue
    decl=$(grep -E '^[[:space:]]*extern[^;(]*\bshl__|^[A-Za-z_].*[[:space:]*]shl__[A-Za-z0-9_]*[[:space:]]*\([^)]*\)[[:space:]]*;' <<<"$code" || true)
    [ -z "$decl" ] || err "$f declares a shl__ symbol itself (declare it in an internal header): $(head -1 <<<"$decl")"
    for s in $(grep -o 'shl__[A-Za-z0-9_]*' <<<"$code" | sort -u); do
        grep -qw "$s" <<<"$allowed_text" || err "$f uses $s, which no allowed internal header declares"
    done
    reached=$(lib_includes "$f" | sort -u)
    ok=0
    for h in $reached; do is_allowed "$h" && ok=1; done
    [ $ok -eq 1 ] || err "$f names shl__ symbols without including an allowed internal header"
done < <(find bench tests -type f \( -name '*.c' -o -name '*.h' \) | sort)

# ---- 4: programs built from bench/, tests/, tools/ do not load the shared library
for d in "$build/tests" "$build/bench" "$build/tools"; do
    [ -d "$d" ] || continue
    while IFS= read -r prog; do
        if readelf -d "$prog" 2>/dev/null | grep -q 'NEEDED.*\[libshlight\.so'; then
            err "$prog loads libshlight.so; link the static archive (internals are hidden in the .so)"
        fi
    done < <(find "$d" -type f -perm -u+x)
done

[ $fail -eq 0 ] || exit 1
echo "symbols check: ok ($(wc -l <<<"$exported") exported, all shl_[a-z]* and declared in shlight.h;" \
     "SONAME $soname; bench/ and tests/ reach shl__ only through ${allowed[*]})"
