"""Path-traced reference of one-bounce indirect light for HVL 2022 Table 2 (make bench-tables).

bench/bench_tables.c (section hvl) writes DIR/scene.json (camera, polygon lights), DIR/mesh.bin
(the receivers, format of bench/oracle_export.c: float64 positions and normals, float64 face
albedo, int32 triangles) and DIR/points.bin (float64 per shading point: position, normal, albedo).
Here Mitsuba 3 (llvm_ad_rgb) estimates at each point the radiance reflected after exactly one
bounce, the quantity HVL, VPL and VSL approximate:
    L_ind(x) = a_x / pi * integral over the hemisphere of L_1(y(w), -w) cos(n_x, w) dw,
    L_1(y, v) = a_y / pi * integral of L_e(w') V(y, w') cos+(n_y, w') dw'
(y(w): the first surface the ray from x meets, with visibility; light from an emitter seen
directly is direct light and left out).  One cosine-weighted direction per sample (pdf cos / pi,
so a sample is a_x L_1(y)), L_1 by Scene.sample_emitter_direction with the visibility test
(area sampling of the emitters).  R independent passes give the estimate and its standard
error per point.  Writes DIR/reference.bin and DIR/reference_se.bin (float32 rgb per point) and
DIR/reference.json.  With --cache C, a result for identical inputs (and this script) is read from / written to C.

usage: hvl_reference.py DIR [--spp N] [--passes R] [--cache C]
"""
import argparse
import hashlib
import json
import math
import os
import shutil
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import find_libllvm  # noqa: E402  (standard library only)

LANES = 1 << 20


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--passes", type=int, default=4)
    ap.add_argument("--cache", default=None)
    a = ap.parse_args()
    files = [os.path.join(a.dir, f) for f in ("scene.json", "mesh.bin", "points.bin")] + [os.path.abspath(__file__)]
    h = hashlib.sha256(("%d %d" % (a.spp, a.passes)).encode())
    for f in files:
        with open(f, "rb") as fh:
            h.update(fh.read())
    key = h.hexdigest()[:24]
    outs = ["reference.bin", "reference_se.bin", "reference.json"]
    if a.cache and all(os.path.exists(os.path.join(a.cache, key, o)) for o in outs):
        for o in outs:
            shutil.copyfile(os.path.join(a.cache, key, o), os.path.join(a.dir, o))
        with open(os.path.join(a.dir, "reference.json")) as fh:
            meta = json.load(fh)
        meta["cached"] = 1
        with open(os.path.join(a.dir, "reference.json"), "w") as fh:
            json.dump(meta, fh)
        print("hvl_reference: read from the cache (%s)" % key, file=sys.stderr)
        return

    path = find_libllvm.locate()
    err = find_libllvm.probe(path)
    if err:
        raise SystemExit("hvl_reference: Dr.Jit cannot use %s (%s)" % (path, err))
    os.environ["DRJIT_LIBLLVM_PATH"] = path
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    from drjit.llvm.ad import Float, UInt32
    import oracle_images

    with open(os.path.join(a.dir, "scene.json")) as fh:
        ex = json.load(fh)
    nv, nt = ex["nv"], ex["nt"]
    raw = np.fromfile(os.path.join(a.dir, "mesh.bin"), dtype=np.uint8)
    f8 = np.frombuffer(raw[:8 * (6 * nv + 3 * nt)], dtype=np.float64)
    ex["pos"] = f8[:3 * nv].reshape(nv, 3)
    ex["nrm"] = f8[3 * nv:6 * nv].reshape(nv, 3)
    albedo = f8[6 * nv:6 * nv + 3 * nt].reshape(nt, 3)
    ex["tri"] = np.frombuffer(raw[8 * (6 * nv + 3 * nt):], dtype=np.int32).reshape(nt, 3)
    pts = np.fromfile(os.path.join(a.dir, "points.bin"), dtype=np.float64).reshape(-1, 9)
    npt = len(pts)
    eps = 1e-5 * float(np.max(np.ptp(ex["pos"], axis=0)))

    with tempfile.TemporaryDirectory() as tmp:
        scene = oracle_images.mitsuba_scene(ex, tmp)
        alb = [Float(np.ascontiguousarray(albedo[:, k], np.float32)) for k in range(3)]

        def one_pass(seed):
            spp = a.spp
            per = max(1, LANES // spp)
            out = np.empty((npt, 3))
            for s0 in range(0, npt, per):
                m = min(per, npt - s0)
                lanes = m * spp
                idx = dr.arange(UInt32, lanes) // dr.opaque(UInt32, spp)

                def col(k):
                    return dr.gather(Float, Float(np.ascontiguousarray(pts[s0:s0 + m, k], np.float32)), idx)
                p = mi.Point3f(col(0), col(1), col(2))
                n = dr.normalize(mi.Vector3f(col(3), col(4), col(5)))
                sampler = mi.load_dict({"type": "independent"})
                sampler.seed(dr.opaque(UInt32, (seed * 1000003 + s0) & 0xFFFFFFFF), lanes)
                d = mi.Frame3f(n).to_world(mi.warp.square_to_cosine_hemisphere(sampler.next_2d()))
                si = scene.ray_intersect(mi.Ray3f(p + n * eps, d))
                valid = si.is_valid() & ~si.shape.is_emitter()
                ny = si.sh_frame.n
                ny = dr.select(dr.dot(ny, d) > 0, -ny, ny)       # the side that faces x
                ds, spec = scene.sample_emitter_direction(si, sampler.next_2d(), True, valid)
                c = dr.maximum(dr.dot(ny, ds.d), 0.0)
                prim = dr.select(valid, si.prim_index, 0)
                e = [dr.select(valid, spec[k] * c * dr.gather(Float, alb[k], prim) / math.pi, 0.0) for k in range(3)]
                s = [dr.block_sum(e[k], spp) for k in range(3)]
                dr.eval(*s)
                out[s0:s0 + m] = np.stack([np.asarray(t.numpy(), dtype=np.float64) for t in s], axis=1) / spp
            return out * pts[:, 6:9]

        t0 = time.time()
        runs = [one_pass(20261202 + r) for r in range(a.passes)]
        secs = time.time() - t0
    runs = np.stack(runs)
    mean = runs.mean(0)
    se = runs.std(0, ddof=1) / math.sqrt(a.passes) if a.passes > 1 else np.zeros_like(mean)
    mean.astype(np.float32).tofile(os.path.join(a.dir, "reference.bin"))
    se.astype(np.float32).tofile(os.path.join(a.dir, "reference_se.bin"))
    meta = {"points": npt, "spp": a.spp, "passes": a.passes, "seconds": secs, "cached": 0,
            "mitsuba": mi.__version__, "drjit": dr.__version__, "variant": "llvm_ad_rgb"}
    with open(os.path.join(a.dir, "reference.json"), "w") as fh:
        json.dump(meta, fh)
    if a.cache:
        os.makedirs(os.path.join(a.cache, key), exist_ok=True)
        for o in outs:
            shutil.copyfile(os.path.join(a.dir, o), os.path.join(a.cache, key, o))
    print("hvl_reference: %d points x %d x %d samples in %.1f s" % (npt, a.passes, a.spp, secs), file=sys.stderr)


if __name__ == "__main__":
    main()
