#!/usr/bin/env bash
# Run README.md's commands exactly as written, the way a new user would, and
# compile every C block in it.  Markers (HTML comments, on the line just before
# the opening fence; GitHub does not render them):
#
#   <!-- file: NAME.c -->  + ```c   a program: saved as NAME.c in the repository
#                                   root before any command runs; some run block
#                                   must name it (that block compiles and runs it).
#   <!-- file: NAME.h -->  + ```c   declarations quoted from include/shlight.h:
#                                   compiled after shlight.h, so a prototype that
#                                   differs from the header fails.
#   <!-- run -->           + ```sh  commands: every run block, in README order, in
#                                   one `bash -e` session started in the repository
#                                   root, verbatim (so `export` carries over).
#
# Every ```c block must carry a file marker.  The session runs in a fresh copy of
# the working tree (tracked and untracked, not ignored, files: no build/), with an
# empty HOME and a bare environment (env -i, PATH=/usr/local/bin:/usr/bin:/bin), as
# user nobody when started as root: the commands must work without root.  Each
# block's last status is checked too (bash -e does not stop inside `a && b`).
# Afterwards no file or symlink may be left under HOME (README's own `make uninstall` must
# remove what its `make install` wrote).  Every C block is also compiled with
# -std=c11 -Wall -Wextra -Wpedantic -Werror (extra check, not a README command).
# Also: the Layout section names every file of src/ and tools/ and each simd/*.h.
# Usage: tools/check_readme.sh [MARKDOWN]   (default README.md)
set -euo pipefail
md=README.md
[ $# -eq 0 ] || md=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
repo=$tmp/shlight
mkdir -p "$repo" "$tmp/home" "$tmp/blocks"

# Parse: C blocks into $tmp/blocks/NAME, run blocks into $tmp/session.sh.
awk -v blocks="$tmp/blocks" -v session="$tmp/session.sh" -v md="$md" '
function fail(msg) { printf "%s:%d: %s\n", md, NR, msg > "/dev/stderr"; bad = 1 }
BEGIN { nrun = 0 }
mode == "c" && /^```[[:space:]]*$/ { mode = ""; close(out); next }
mode == "c" { print > out; next }
mode == "sh" && /^```[[:space:]]*$/ {
    mode = ""
    printf "__st=$?; [ $__st -eq 0 ] || { echo \"check_readme: run block at %s:%d exited with $__st\" >&2; exit 1; }\n", md, start > session
    next
}
mode == "sh" { print > session; next }
{ marker = pending; pending = "" }
/^<!-- file: [A-Za-z0-9_.-]+\.[ch] -->[[:space:]]*$/ { pending = "file"; name = $3; next }
/^<!-- run -->[[:space:]]*$/ { pending = "run"; next }
/^```c[[:space:]]*$/ {
    if (marker != "file") { fail("```c block without a <!-- file: NAME.c|NAME.h --> marker on the line before"); mode = "c"; out = "/dev/null"; next }
    if (name in seen) fail("file name " name " used twice")
    seen[name] = 1
    mode = "c"; out = blocks "/" name; printf "" > out; next
}
/^```sh[[:space:]]*$/ && marker == "run" {
    mode = "sh"; start = NR; ++nrun
    printf "printf \"\\n== %s:%d\\n\"\n", md, NR > session; next
}
marker != "" { fail("marker not followed by its fence (```c for file:, ```sh for run)") }
END {
    if (mode != "") fail("unterminated code block")
    if (nrun == 0) fail("no <!-- run --> block")
    exit bad
}' "$md" || { echo "check_readme: $md: markers or blocks malformed (see above)"; exit 1; }

# README's Layout section names every file of src/ and tools/ and every kernel text of simd/.
layout=$(awk '/^## Layout/{on=1; next} on && /^## /{exit} on' "$md")
for f in src/* tools/* simd/*.h; do
    [ -f "$f" ] || continue
    grep -qF "$(basename "$f")" <<<"$layout" ||
        { echo "check_readme: $md's Layout section does not name $f"; exit 1; }
done

# Every C block compiles warning-free against the header (extra check).
for f in "$tmp"/blocks/*; do
    [ -e "$f" ] || continue
    cc -std=c11 -Wall -Wextra -Wpedantic -Werror -fsyntax-only -Iinclude -include shlight.h -x c "$f" ||
        { echo "check_readme: C block $(basename "$f") does not compile warning-free against include/shlight.h"; exit 1; }
    case $f in
    *.c) grep -qF "$(basename "$f")" "$tmp/session.sh" ||
             { echo "check_readme: no run block names $(basename "$f")"; exit 1; } ;;
    esac
done

# A fresh copy of the working tree, the programs saved in its root.
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    git ls-files -z -co --exclude-standard | tar --null -T - --ignore-failed-read -cf - 2>/dev/null | tar -C "$repo" -xf -
else
    tar --exclude=./build --exclude=./.git -cf - . | tar -C "$repo" -xf -
fi
for f in "$tmp"/blocks/*.c; do [ -e "$f" ] && cp "$f" "$repo/"; done

run=(env -i HOME="$tmp/home" PATH=/usr/local/bin:/usr/bin:/bin bash -e "$tmp/session.sh")
who=$(id -un)
if [ "$(id -u)" -eq 0 ]; then
    chown -R nobody "$tmp"
    run=(setpriv --reuid=nobody --regid="$(id -g nobody)" --clear-groups "${run[@]}")
    who=nobody
fi
echo "== README commands, verbatim, as $who, in a copy of the repository"
(cd "$repo" && "${run[@]}") || { echo "check_readme: README commands failed"; exit 1; }

left=$(cd "$tmp/home" && find . ! -type d)   # files and symlinks
if [ -n "$left" ]; then
    echo "check_readme: README's commands left files under HOME:"; echo "$left"; exit 1
fi
echo "README check: ok ($(ls "$tmp/blocks" | wc -l) C blocks, $(grep -c '^printf "\\n== ' "$tmp/session.sh") run blocks, HOME clean)"
