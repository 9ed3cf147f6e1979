#!/usr/bin/env python3
"""Write the seed corpora tests/fuzz/corpus/<target>/ (hard cases, in the input
format decoded by tests/fuzz/fuzz_common.h and each target; see README.md).

    python3 tests/fuzz/make_seeds.py        # rewrites the seed files it owns

Seeds are named seed-<what>; other files in the corpus directories (e.g. inputs
added from fuzzing runs) are left alone."""
import math
import os
import struct

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")

NAN, INF = float("nan"), float("inf")


def u8(v):
    return bytes([v & 0xFF])


def u16(v):
    return struct.pack("<H", v & 0xFFFF)


def i16(v):
    return struct.pack("<h", v)


def u64(v):
    return struct.pack("<Q", v & 0xFFFFFFFFFFFFFFFF)


def real(v):
    """fz_real: exact doubles as 8 raw bytes; NaN, infinities and zeros by selector."""
    if isinstance(v, float) and math.isnan(v):
        return u8(0)
    if v in (INF, -INF):
        return u8(1 | (0x20 if v < 0 else 0))
    if v == 0.0:
        return u8(2 | (0x20 if math.copysign(1.0, v) < 0 else 0))
    return u8(8) + struct.pack("<d", float(v))


def lmax(l):
    return u8(l if 0 <= l <= 30 else {31: 0xFF, -1: 0xFE}[l])


def count(n):
    if 3 <= n <= 64:
        return u8(n - 3)
    return u8({2: 0xFF, 65: 0xFE, 0: 0xFD, -1: 0xFC, 1: 0xFB}[n])


def expo(e):
    """2-D scale exponent byte: e in [-80, 79], or a multiple of 22 in [-1056, 1034]."""
    if -80 <= e <= 79:
        return u8(e + 80)
    assert e % 22 == 0
    return u8(e // 22 + 208)


def polygon(pts, e=0, h=0.0, hull=False, tilted=None, reverse=False, perm=0, signs=0, rot=0, dups=0, small=False):
    """Structured polygon: 2-D int16 points (ordered by the decoder), scale 2^e, plane Z = h
    or Z = 2^tilted X, axes permuted (perm 0..5) and negated (signs bits 0..2)."""
    mode = (1 if hull else 0) | (4 if tilted is not None else 0) | (8 if reverse else 0)
    mode |= (0x10 if dups else 0) | (0x20 if small else 0)
    b = u8(mode) + count(len(pts)) + expo(e) + u8(perm | (signs << 3))
    b += u8(tilted + 4) if tilted is not None else real(h)
    for (a, c) in pts:
        b += (u8((a + 8) & 15) + u8((c + 8) & 15)) if small else (i16(a) + i16(c))
    b += u8(rot)
    if dups:
        b += u64(dups)
    return b


def raw_polygon(verts, n=None):
    b = u8(3) + count(len(verts) // 3 if n is None else n)
    for v in verts:
        b += real(v)
    return b


def point_any(x):
    return u8(0) + u8(0) + b"".join(real(c) for c in x)


def point_near_vertex(i, off):
    return u8(2) + u8(i) + b"".join(real(c) for c in off)


def point_in_plane(i, du, dv):
    return u8(3) + u8(i) + real(du) + real(dv)


def point_above_plane(i, du, dv, dh):
    return u8(4) + u8(i) + real(du) + real(dv) + real(dh)


def point_near_edge(i, j, off, half=True, k=0):
    t = u8(1) if half else u8(0) + u8(k)
    return u8(5) + u8(i) + u8(j) + t + b"".join(real(c) for c in off)


def point_on_vertex(i):
    return u8(7) + u8(i)


SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
STAR = [(100, 0), (20, 30), (0, 100), (-30, 10), (-100, -100), (10, -20)]
TRI = [(0, 0), (3, 0), (0, 4)]
MANY = [(int(1000 * math.cos(2 * math.pi * k / 64)), int(1000 * math.sin(2 * math.pi * k / 64))) for k in range(64)]
COLLINEAR = [(0, 0), (1, 0), (2, 0), (3, 0), (3, 3), (0, 3)]

# (name, polygon bytes, point bytes): shared by the polygon targets
POLY_CASES = [
    ("square-above", polygon(SQUARE, h=1.0), point_any([0.3, 0.4, 0.0])),
    ("square-in-plane", polygon(SQUARE, h=1.0), point_in_plane(0, 0.25, 0.5)),
    ("square-1e-9-above", polygon(SQUARE, h=1.0), point_above_plane(0, 0.5, 0.5, 1e-9)),
    ("square-1ulp-above", polygon(SQUARE, h=1.0), point_above_plane(0, 0.5, 0.5, 2.0 ** -52)),
    ("square-grazing-outside", polygon(SQUARE, h=1.0), point_above_plane(0, 3.0, 0.5, -1e-9)),
    ("square-near-edge", polygon(SQUARE, h=0.0), point_near_edge(0, 0, [1e-9, 1e-9, 1e-9])),
    ("on-vertex", polygon(TRI), point_on_vertex(1)),
    ("near-vertex", polygon(TRI, h=2.0), point_near_vertex(2, [1e-12, -1e-12, 1e-9])),
    ("tiny-1e-20", polygon(SQUARE, e=-66, h=10.0), point_any([0.0, 0.0, 0.0])),
    ("tiny-2e-200", polygon(STAR, e=-660, h=1.0), point_any([0.0, 0.0, 0.0])),
    ("huge-1e15", polygon(STAR, e=50, h=1.0), point_any([0.5, 0.5, 0.0])),
    ("huge-1e300", polygon(SQUARE, e=990, h=1e300), point_any([0.0, 0.0, 0.0])),
    ("all-lengths-1e-198", polygon(STAR, e=-660, h=2e-198), point_any([0.0, 0.0, 0.0])),
    ("denormal-plane", polygon(TRI, e=0, h=5e-324), point_any([0.25, 0.25, 0.0])),
    ("minus-zero", polygon(TRI, h=-0.0), point_any([-0.0, -0.0, 1.0])),
    ("repeated-vertices", polygon(SQUARE, h=1.0, dups=0b1011), point_any([0.2, 0.7, 0.0])),
    ("collinear-vertices", polygon(COLLINEAR, h=1.0), point_any([1.0, 1.0, -2.0])),
    ("all-collinear", polygon([(0, 0), (1, 1), (2, 2), (5, 5)], h=1.0), point_any([0.0, 1.0, 0.0])),
    ("concave-star", polygon(STAR, h=2.0, e=-6), point_any([0.1, 0.2, 0.5])),
    ("concave-star-hull", polygon(STAR, h=2.0, e=-6, hull=True, reverse=True, rot=3), point_any([0.1, 0.2, 0.5])),
    ("64-vertices", polygon(MANY, e=-10, h=0.5, hull=True), point_any([0.0, 0.0, 0.0])),
    ("tilted-plane", polygon(STAR, tilted=1, perm=3, signs=5), point_any([0.5, -0.25, 2.0])),
    ("tilted-in-plane", polygon(SQUARE, tilted=-2, perm=4), point_in_plane(0, 0.5, 0.5)),
    ("small-coords-many-repeats", polygon([(k % 5 - 2, (k * 3) % 5 - 2) for k in range(20)], small=True, h=1.0),
     point_any([0.0, 0.0, 0.25])),
    ("raw-nan", raw_polygon([0, 0, 1, 1, 0, 1, NAN, 1, 1]), point_any([0, 0, 0])),
    ("raw-inf-point", raw_polygon([0, 0, 1, 1, 0, 1, 0, 1, 1]), point_any([0, INF, 0])),
    ("raw-nonplanar", raw_polygon([0, 0, 1, 1, 0, 1.5, 1, 1, 1, 0, 1, 0.5]), point_any([0.5, 0.5, 0.0])),
    ("raw-huge-mixed", raw_polygon([1e300, 0, 1, -1e300, 0, 1, 0, 1e300, 1]), point_any([0, 0, 0])),
    ("count-2", polygon(TRI), point_any([0, 0, 1])),
    ("grazing-huge-concave", polygon(STAR, e=40, h=0.0), point_above_plane(0, -1e12, 3e11, 284.0)),
]


def write(target, name, data):
    d = os.path.join(ROOT, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


def polygon_targets():
    for name, pb, xb in POLY_CASES:
        if name == "count-2":
            pb = pb[:1] + count(2) + pb[2:]
        for l in (0, 4, 30):
            write("fuzz_polygon", "%s-l%d" % (name, l), lmax(l) + u8(0) + pb + xb)
            write("fuzz_polygon_f", "%s-l%d" % (name, l), lmax(l) + u8(0) + pb + xb)
    write("fuzz_polygon", "lmax-31", lmax(31) + u8(0) + POLY_CASES[0][1] + POLY_CASES[0][2])
    write("fuzz_polygon", "null-x", lmax(0) + u8(1) + POLY_CASES[0][1] + POLY_CASES[0][2])
    # batch: several points per polygon, with and without gradients, both ISAs
    for name, pb, xb in POLY_CASES:
        if name == "count-2":
            continue
        pts = xb + point_in_plane(0, 0.25, 0.25) + point_above_plane(0, 0.5, 0.5, 1e-6) + point_any([3, -2, 7])
        pts += point_any([1e13, 1e13, 1e13])  # farther than 2^40 extents
        for l, flags in ((0, 1), (4, 1 | 4), (14, 0), (30, 1)):
            write("fuzz_batch", "%s-l%d-f%d" % (name, l, flags), lmax(l) + u8(flags) + pb + u8(5) + pts + u8(0))
    pb, xb = POLY_CASES[0][1], POLY_CASES[0][2]
    write("fuzz_batch", "nan-last-point", lmax(3) + u8(1 | 2) + pb + u8(3) + xb * 3 + u8(2) + u8(1) + u8(1))
    write("fuzz_batch", "alloc-failure", lmax(3) + u8(1 | 8) + pb + u8(2) + xb * 2 + u8(0) + u8(0))
    write("fuzz_batch", "npts-negative", lmax(3) + u8(0x10) + pb + u8(1) + xb + u8(3))
    write("fuzz_batch", "zero-points", lmax(3) + u8(1) + pb + u8(0))


def sphere_targets():
    def sph(l, flags, x, c, r):
        return lmax(l) + u8(flags) + u8(0) + b"".join(real(v) for v in x) + b"".join(real(v) for v in c) + real(r)

    def rel(l, flags, x, e, off, relsel, extra=b"", exact345=False):
        mode = 1 | (4 if exact345 else 0)
        b = lmax(l) + u8(flags) + u8(mode) + b"".join(real(v) for v in x) + u8(e & 0xFF)
        b += b"".join(u8(o & 0xFF) for o in off) + u8(relsel) + extra
        return b

    cases = {
        "unit": sph(8, 0, [0, 0, 0], [0, 0, 3], 1.0),
        "tiny-1e-4-at-10": sph(30, 0, [0.25, -0.5, 0.125], [0.25, -0.5, 10.125], 1e-4),
        "distant-1e6": sph(30, 0, [0, 0, 0], [1e6, 0, 0], 1.0),
        "inside": sph(4, 0, [0, 0, 0.5], [0, 0, 0], 1.0),
        "at-centre": sph(4, 0, [1, 2, 3], [1, 2, 3], 0.5),
        "on-surface-345": rel(30, 0, [0.5, 0.25, 0], 0, [3, 4, 0], 5, exact345=True),
        "tangent-outside-2^-50": rel(30, 0, [0, 0, 0], 0, [3, 4, 0], 0, u8(50), exact345=True),
        "tangent-inside-2^-50": rel(30, 0, [0, 0, 0], 0, [3, 4, 0], 1, u8(50), exact345=True),
        "tiny-radius-2^-1000": rel(12, 0, [1, 1, 1], 0, [1, 2, 3], 3, u8(250)),
        "huge-coordinates": sph(6, 0, [1e300, -1e300, 1e300], [1e300, -1e300, 1.5e300], 1e299),
        "denormal": sph(6, 0, [0, 0, 0], [5e-324, 5e-324, 5e-324], 5e-324),
        "radius-minus-zero": sph(2, 0, [0, 0, 0], [0, 0, 3], -0.0),
        "radius-nan": sph(2, 0, [0, 0, 0], [0, 0, 3], NAN),
        "centre-inf": sph(2, 0, [0, 0, 0], [0, INF, 3], 1.0),
        "lmax-0": sph(0, 0, [0, 0, 0], [0, 0, 3], 2.0),
        "lmax-31": sph(31, 0, [0, 0, 0], [0, 0, 3], 1.0),
        "float-unit": sph(8, 1, [0, 0, 0], [0, 0, 3], 1.0),
        "float-tiny": sph(30, 1, [0.25, -0.5, 0.125], [0.25, -0.5, 10.125], 1e-4),
        "float-tangent": rel(30, 1, [0, 0, 0], 0, [3, 4, 0], 0, u8(20), exact345=True),
        "float-overflow-to-inf": sph(3, 1, [0, 0, 0], [1e300, 0, 0], 1.0),
        "null-grad": sph(3, 8, [0, 0, 0], [0, 0, 3], 1.0),
        # the float entry points' set-up in double (src/sphere.c, geom_units_f): a difference
        # beyond FLT_MAX, a denormal distance and radius, 2^110 offsets (gradient scaled),
        # a few ulps outside, a denormal radius far away, non-finite and -0 arguments
        "float-difference-beyond-flt-max": sph(5, 1, [-3e38, 0, 0], [3e38, 1e38, 0], 1e38),
        "float-denormal-distance": sph(4, 1, [0, 0, 0], [2.0 ** -148, 2.0 ** -149, 0], 2.0 ** -149),
        "float-offsets-2^110": sph(8, 1, [1, 2, 3], [2.0 ** 110, 2.0 ** 109, 3], 2.0 ** 108),
        "float-tangent-ulps": rel(12, 1, [0, 0, 0], 0, [3, 4, 0], 0, u8(22), exact345=True),
        "float-denormal-radius": sph(6, 1, [0, 0, 0], [0, 1, 0], 2.0 ** -149),
        "float-x-nan": sph(2, 1, [NAN, 0, 0], [0, 0, 3], 1.0),
        "float-centre-inf": sph(2, 1, [0, 0, 0], [0, -INF, 3], 1.0),
        "float-radius-inf": sph(2, 1, [0, 0, 0], [0, 0, 3], INF),
        "float-radius-minus-zero": sph(2, 1, [0, 0, 0], [0, 0, 3], -0.0),
    }
    for name, data in cases.items():
        write("fuzz_sphere", name, data)


def lights_targets():
    def poly_light(pb, rgb=(16, 8, 4), two_sided=1):
        return u8(0) + b"".join(u8(c) for c in rgb) + pb + u8(two_sided)

    def sphere_light(c, r, rgb=(16, 16, 16)):
        return u8(1) + b"".join(u8(v) for v in rgb) + b"".join(real(v) for v in c) + real(r)

    def lights(l, flags, ls, pts, extra=b""):
        return lmax(l) + u8(flags) + u8(len(ls)) + b"".join(ls) + u8(len(pts) - 1) + b"".join(pts) + extra

    sq = POLY_CASES[0][1]
    star = POLY_CASES[17][1]
    cases = {
        "empty": lights(4, 1, [], [point_any([0, 0, 0])]),
        "one-square": lights(6, 1, [poly_light(sq)], [point_any([0.3, 0.4, 0])]),
        "one-sided-both-sides": lights(6, 1, [poly_light(sq, two_sided=0)],
                                       [point_any([0.3, 0.4, 0]), point_any([0.3, 0.4, 2]), point_in_plane(0, 0.5, 0.5)]),
        "polygons-and-spheres": lights(8, 1, [poly_light(sq), poly_light(star, two_sided=0), sphere_light([0, 0, 3], 0.5),
                                              sphere_light([0, 0, 0], 1.0)],
                                       [point_any([0.1, 0.2, 0.0]), point_above_plane(0, 0.5, 0.5, 1e-9)]),
        "inside-sphere": lights(3, 1, [sphere_light([0, 0, 0], 2.0)], [point_any([0.5, 0, 0])]),
        "bad-two-sided": lights(3, 0, [u8(0) + u8(1) * 3 + sq + u8(250)], [point_any([0, 0, 0])]),
        "bad-radius": lights(3, 0, [sphere_light([0, 0, 0], -1.0), sphere_light([0, 0, 0], NAN)], [point_any([0, 0, 1])]),
        "nan-rgb": lights(3, 0, [u8(2) + real(NAN) + real(1.0) + real(1.0) + sq + u8(1)], [point_any([0, 0, 0])]),
        "huge-rgb": lights(3, 1, [u8(2) + real(1e300) + real(-1e300) + real(1.0) + sq + u8(1)], [point_any([0.3, 0.3, 0])]),
        "nan-batch-point": lights(3, 1 | 2, [poly_light(sq)], [point_any([0, 0, 0]), point_any([1, 1, 1])], u8(1)),
        "alloc-failures": lights(3, 1 | 4, [u8(0) + u8(16) * 3 + u8(0) + sq + u8(1), u8(1) + u8(16) * 3 + u8(1) +
                                             real(0) + real(0) + real(3) + real(1.0)],
                                 [point_any([0, 0, 0])]),
        "null-ctx": lights(3, 8, [poly_light(sq)], [point_any([0, 0, 0])], u8(0)),
        "lmax-30": lights(30, 1, [poly_light(star), sphere_light([1, 1, 1], 0.25)], [point_any([0, 0, 0])]),
        "lmax-0": lights(0, 0, [poly_light(sq)], [point_any([0.5, 0.5, -1])]),
    }
    for name, data in cases.items():
        write("fuzz_lights", name, data)


def grid_targets():
    def axis(lo, hi):
        return u8(1) + real(lo) + real(hi)

    def grid(l, flags, box, res, ls, tb, reqs, idx=(0, 0, 0)):
        b = lmax(l) + u8(flags) + b"".join(axis(a, c) for a, c in box) + b"".join(u8(r - 2) for r in res)
        b += u8(len(ls)) + b"".join(ls) + u8(tb) + b"".join(u8(i) for i in idx) + u8(len(reqs) - 1) + b"".join(reqs)
        return b

    def poly_light(pb, two_sided=1):
        return u8(2 * two_sided) + u8(16) * 3 + pb

    def sphere_light(c, r):
        return u8(1) + u8(16) * 3 + b"".join(real(v) for v in c) + real(r)

    def req(method, pts, b=None):
        mb = method + (0x40 if b is not None else 0)
        out = u8(mb) + (real(b) if b is not None else b"") + u8(len(pts))
        for mode, vals in pts:
            out += u8(mode) + b"".join(real(v) if mode == 0 else u8(v) for v in vals)
        return out

    unit = [(-1.0, 1.0)] * 3
    sq = polygon(SQUARE, h=3.0, e=-1)
    pts = [(2, (0, 1, 2)), (1, (128, 64, 200)), (0, (5.0, -5.0, 0.0)), (0, (1e300, -1e300, 0.25))]
    cases = {
        "square-all-methods": grid(4, 1, unit, (3, 3, 3), [poly_light(sq)], 0,
                                   [req(0, pts), req(1, pts, 2.0), req(2, pts)]),
        "float-storage": grid(4, 0, unit, (2, 3, 4), [poly_light(sq), sphere_light([0, 0, 5], 1.0)], 0,
                              [req(2, pts), req(1, pts)]),
        "light-through-box": grid(3, 1, unit, (4, 4, 4), [poly_light(polygon(SQUARE, h=0.0, e=-2))], 0,
                                  [req(2, pts), req(0, pts)]),
        "sphere-inside-box": grid(2, 0, unit, (3, 3, 3), [sphere_light([0.1, 0.2, 0.3], 0.5)], 0, [req(2, pts)]),
        "tiny-box": grid(2, 1, [(1.0, 1.0 + 2.0 ** -40)] * 3, (2, 2, 2), [poly_light(sq)], 0, [req(2, pts)]),
        "denormal-box": grid(2, 1, [(0.0, 5e-324)] * 3, (2, 3, 2), [poly_light(sq)], 0, [req(1, pts, 0.5)]),
        "offset-box": grid(2, 1, [(1e10, 1e10 + 1e-3)] * 3, (3, 2, 2), [poly_light(sq)], 0, [req(2, pts)]),
        "huge-box": grid(1, 1, [(-1e300, 1e300)] * 3, (2, 2, 2), [], 0, [req(0, pts)]),
        "lo-equals-hi": grid(2, 1, [(1.0, 1.0)] * 3, (2, 2, 2), [], 0, [req(0, pts)]),
        "nan-lo": grid(2, 1, [(NAN, 1.0)] * 3, (2, 2, 2), [], 0, [req(0, pts)]),
        "bad-nthreads": grid(2, 1, unit, (2, 2, 2), [poly_light(sq)], 250, [req(0, pts)]),
        "taylor-b-bad": grid(2, 1, unit, (2, 2, 2), [poly_light(sq)], 0, [req(1, pts, -1.0), req(1, pts, NAN)]),
        "alloc-failures": grid(2, 3, unit, (2, 2, 2), [poly_light(sq)], 0, [req(0, pts)]),
        "set-node": grid(2, 5, unit, (2, 3, 2), [poly_light(sq)], 0, [req(2, pts)], idx=(1, 2, 1)),
        "lmax-6": grid(6, 1, unit, (2, 2, 2), [poly_light(sq), sphere_light([2, 2, 2], 0.5)], 0, [req(2, pts)]),
    }
    for name, data in cases.items():
        write("fuzz_grid", name, data)


def sh_targets():
    def basis(l, d):
        return lmax(l) + u8(0) + u8(0) + b"".join(real(v) for v in d) + bytes(range(40))

    def zh(l, vals, axis):
        return lmax(l) + u8(1) + b"".join(u8(1) + real(v) for v in vals) + u8(0) + b"".join(real(v) for v in axis)

    def rot_perm(l, p, signs, vals):
        return lmax(l) + u8(2) + u8(0 | (p << 2) | (signs << 5)) + u8(0) + b"".join(u8(v & 0xFF) for v in vals)

    def rot_raw(l, R, vals, fail=False):
        return lmax(l) + u8(2) + u8(3) + b"".join(real(v) for v in R) + u8(2 if fail else 0) + b"".join(
            u8(v & 0xFF) for v in vals)

    def rot_quat(l, q, refl, vals):
        return lmax(l) + u8(2) + u8(1 | (4 if refl else 0)) + b"".join(u16(v) for v in q) + u8(0) + b"".join(
            u8(v & 0xFF) for v in vals)

    n30 = 31 * 31
    vals = [(7 * k) % 256 - 128 for k in range(n30)]
    cases = {
        "basis-pole": basis(30, [0, 0, 1]),
        "basis-south-pole": basis(30, [0, 0, -1]),
        "basis-denormal": basis(30, [5e-324, 0, 5e-324]),
        "basis-huge": basis(30, [1.7e308, -1.7e308, 1.7e308]),
        "basis-zero": basis(4, [0, -0.0, 0]),
        "basis-nan": basis(4, [0, NAN, 1]),
        "basis-lmax-0": basis(0, [1, 2, 3]),
        "zh-to-sh-pole": zh(30, [1.0] * 31, [0, 0, 1]),
        "zh-to-sh-tiny-axis": zh(10, [1.0] * 11, [1e-300, 1e-300, 0]),
        "zh-to-sh-huge": zh(5, [1e300] * 6, [1, 1, 1]),
        "zh-to-sh-zero-axis": zh(5, [1.0] * 6, [0, 0, 0]),
        "rotate-identity": rot_perm(30, 0, 0, vals),
        "rotate-reflection": rot_perm(30, 3, 0b101, vals),
        "rotate-quaternion": rot_quat(30, [100, 200, 300, 400], False, vals),
        "rotate-quaternion-reflection": rot_quat(12, [1000, 7, 65000, 3], True, vals),
        "rotate-not-orthogonal": rot_raw(4, [1, 0, 0, 0, 1, 0, 0, 0, 1.00001], vals),
        "rotate-nearly-orthogonal": rot_raw(4, [1, 0, 0, 0, 1, 0, 0, 0, 1 + 4e-7], vals),
        "rotate-nan": rot_raw(4, [1, 0, 0, 0, NAN, 0, 0, 0, 1], vals),
        "rotate-alloc-failure": rot_raw(4, [1, 0, 0, 0, 1, 0, 0, 0, 1], vals, fail=True),
        "lmax-31": lmax(31) + u8(0),
    }
    for name, data in cases.items():
        write("fuzz_sh", name, data)


def hvl_targets():
    def raw(a, c, c2=None, up=0, null=False):
        b = u8(1 if null else 0) + u8(0) + real(a) + real(c) + u8(up)
        return b + (real(c2 if c2 is not None else 0.0) if up == 0 else b"")

    def structured(mode, k, m, ulps=0, f=None, up=1, zero_a=False):
        """a = (0.5 + m / 43690) 2^-k (capped at pi/2); mode 1: c = sin(f / 4096 a),
        2: c = sin(a) (+4: -sin(a)) moved by ulps, 3: c = 1 (+4: 0, +8: -1) moved by ulps."""
        b = u8(0) + u8(mode) + u16(k) + u16(m) + u8(0 if zero_a else 1) + u8(ulps & 0xFF)
        return b + (i16(f) if mode % 4 == 1 else b"") + u8(up)

    cases = {
        # issue 20's table
        "issue20-up-1.2e-16": raw(1.2e-16, 1.0),
        "issue20-up-1e-15": raw(1e-15, 1.0),
        "issue20-above-1e-16": raw(1e-16, 0.5),
        "issue20-up-1e-300": raw(1e-300, 1.0),
        "issue20-horizon-1e-9": raw(1e-9, 0.0, up=1),
        "issue20-half-band-1e-6": raw(1e-6, 5e-7, up=3),
        "half-pi-up": raw(0.5 * math.pi, 1.0),
        "half-pi-down": raw(0.5 * math.pi, -1.0, up=1),
        "denormal-cap": raw(5e-324, 5e-324, c2=-5e-324),
        "denormal-cap-horizon": raw(1e-323, 5e-324, c2=0.0),
        "point-horizon": raw(0.0, 0.0, c2=-0.0),
        "point-tiny-above": raw(0.0, 5e-324, c2=-5e-324),
        "nan": raw(0.3, NAN),
        "inf-a": raw(INF, 0.5),
        "c-above-1": raw(0.3, 1.0000000000000002),
        "a-negative-denormal": raw(-5e-324, 0.5),
        "a-above-half-pi": raw(1.5707963267948968, 0.5),
        "null": raw(0.3, 0.5, null=True),
        # edges, 1..4 ulps either side, for caps from pi/2 to 2^-1000
        "edge-up-a1": structured(2, 0, 21845, ulps=1),
        "edge-up-inside-a1": structured(2, 0, 21845, ulps=-1),
        "edge-down-a1": structured(2 | 4, 0, 21845, ulps=-1),
        "edge-down-inside-a1": structured(2 | 4, 0, 21845, ulps=1),
        "edge-down-inside-2^-1000": structured(2 | 4, 1000, 21845, ulps=2),
        "edge-up-2^-60": structured(2, 60, 1234, ulps=-4),
        "edge-a-half-pi": structured(2, 0, 65535, ulps=-2),
        # the middle of the band, where a plain smoothstep is not monotone
        "middle-minus-0.1": structured(1, 0, 21845, f=-410, up=1),
        # a pair 1 ulp apart where w^2 (3 - 2w) in plain doubles steps down (test_hvl.c's sweep)
        "plain-smoothstep-steps-down": raw(0.5 * math.pi, math.nextafter(float.fromhex("-0x1.4060b67a858bfp-3"), -2.0), up=1),
        "middle-plus-0.02": structured(1, 1, 30000, f=82, up=7),
        "middle-tiny-cap": structured(1, 900, 100, f=-2048, up=1),
        "near-1-wide-cap": structured(3, 0, 65535, ulps=-100, up=50),
        "near-0": structured(3 | 4, 3, 5000, ulps=-3, up=6),
        "structured-point": structured(3 | 4, 0, 0, ulps=1, zero_a=True),
    }
    for name, data in cases.items():
        write("fuzz_hvl", name, data)


if __name__ == "__main__":
    polygon_targets()
    sphere_targets()
    lights_targets()
    grid_targets()
    sh_targets()
    hvl_targets()
    for t in sorted(os.listdir(ROOT)):
        print("%-16s %3d seeds" % (t, len([f for f in os.listdir(os.path.join(ROOT, t)) if f.startswith("seed-")])))
