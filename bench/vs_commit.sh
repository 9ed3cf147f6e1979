#!/bin/sh
# bench/vs_commit.sh OLD_BIN NEW_BIN ROUNDS: run two builds of bench/polygon_call.c
# (lines "lmax ns") alternately, ROUNDS rounds (old first in odd rounds, new first in
# even ones, so neither always runs on a warmer or quieter machine), then print per
# lmax the median ns of each, old / new as the ratio of the medians, and the range of
# the per-round ratios.  Called by `make bench-vs-commit OLD=<rev>`.
set -e
old=$1 new=$2 rounds=${3:-7}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
r=1
while [ "$r" -le "$rounds" ]; do
    if [ $((r % 2)) -eq 1 ]; then
        "$old" | sed "s/^/old $r /" >> "$tmp/all"
        "$new" | sed "s/^/new $r /" >> "$tmp/all"
    else
        "$new" | sed "s/^/new $r /" >> "$tmp/all"
        "$old" | sed "s/^/old $r /" >> "$tmp/all"
    fi
    r=$((r + 1))
done
awk -v rounds="$rounds" '
function median(a, n,   i, j, t) { # insertion sort of a[1..n], then the middle
    for (i = 2; i <= n; ++i) { t = a[i]; for (j = i - 1; j >= 1 && a[j] > t; --j) a[j + 1] = a[j]; a[j + 1] = t }
    return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
}
{ t[$1, $2, $3] = $4; if (!($3 in seen)) { seen[$3] = 1; order[++nl] = $3 } }
END {
    printf "shl_polygon, triangle, ns per call: median of %d alternated rounds\n", rounds
    printf "%5s %10s %10s %10s %16s\n", "lmax", "old ns", "new ns", "old/new", "per-round range"
    for (i = 1; i <= nl; ++i) {
        l = order[i]; lo = 1e300; hi = 0
        for (r = 1; r <= rounds; ++r) {
            o[r] = t["old", r, l]; n[r] = t["new", r, l]; q = o[r] / n[r]
            if (q < lo) lo = q; if (q > hi) hi = q
        }
        mo = median(o, rounds); mn = median(n, rounds)
        printf "%5d %10.1f %10.1f %9.2fx %8.2f-%.2f\n", l, mo, mn, mo / mn, lo, hi
    }
}' "$tmp/all"
