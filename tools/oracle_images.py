"""Check 3 of the Mitsuba oracle (issue 7): shlight's PRT images vs Mitsuba renders.

bench/oracle_export (C, the PRT harness) renders a scene at each lmax and exports the
receivers, camera, lights, the receiver triangle seen at each pixel centre and two exact
references from Lambert's closed form (bench/common/lambert.c, independent of the
library's SH code):
    G  per-vertex exact radiance resolved through the same raster (PRT at lmax = infinity),
    P  the closed form at each pixel's own point and interpolated normal.
Here Mitsuba (llvm_ad_rgb) traces one camera ray through each pixel centre (the
raster's camera model), and at the hit estimates the unshadowed outgoing radiance
    L_o = albedo / pi * sum over samples of L_e cos+(n, w) / pdf
with Scene.sample_emitter_direction(..., test_visibility=False) (area sampling of the
emitters; Mitsuba's area emitters light their front side: one-sided lights are one
Mitsuba emitter, two-sided lights two with opposite windings).  R independent passes
give the estimate and its standard error per pixel.  Only pixels where Mitsuba's hit
is the receiver triangle the raster saw are compared.  The same sampling at the
vertices, with the clamped cosine replaced by its truncation to bands 0..L, estimates
exactly what PRT at lmax L computes per vertex (run_scene: tests (i) and (ii)).
"""
import json
import math
import os
import subprocess
import tempfile
import time
from statistics import NormalDist

import numpy as np
import drjit as dr
import mitsuba as mi
from drjit.llvm.ad import Float, UInt32

LANES = 1 << 21          # Dr.Jit lanes per kernel launch (bounds memory)


# ---------------------------------------------------------------------------
# Export and Mitsuba scene
# ---------------------------------------------------------------------------
def export(exe, scene_file, out_dir, w, h, lmaxes):
    os.makedirs(out_dir, exist_ok=True)
    env = dict(os.environ, SHLIGHT_THREADS=os.environ.get("SHLIGHT_THREADS", "2"))
    subprocess.run([exe, scene_file, out_dir, str(w), str(h)] + [str(l) for l in lmaxes], check=True, env=env)
    with open(os.path.join(out_dir, "scene.json")) as f:
        ex = json.load(f)
    nv, nt, npix = ex["nv"], ex["nt"], w * h
    raw = np.fromfile(os.path.join(out_dir, "mesh.bin"), dtype=np.uint8)
    f8 = np.frombuffer(raw[:8 * (6 * nv + 3 * nt)], dtype=np.float64)
    ex["pos"] = f8[:3 * nv].reshape(nv, 3)
    ex["nrm"] = f8[3 * nv:6 * nv].reshape(nv, 3)
    ex["albedo"] = f8[6 * nv:6 * nv + 3 * nt].reshape(nt, 3)
    ex["tri"] = np.frombuffer(raw[8 * (6 * nv + 3 * nt):], dtype=np.int32).reshape(nt, 3)
    ex["pixel_tri"] = np.fromfile(os.path.join(out_dir, "pixel_tri.bin"), dtype=np.int32)

    def img(name, n=npix):
        return np.fromfile(os.path.join(out_dir, name), dtype=np.float32).astype(np.float64).reshape(n, 3)

    def vimg(name):
        return img(name, nv)
    ex["prt_seconds"] = {int(e["lmax"]): e["seconds"] for e in ex["prt"]}
    ex["prt"] = {int(e["lmax"]): img("prt_%d.bin" % e["lmax"]) for e in ex["prt"]}
    ex["vertex"] = {l: vimg("vertex_%d.bin" % l) for l in ex["prt"]}
    ex["lambert_vertices"] = vimg("lambert_vertices.bin")
    ex["G"] = img("lambert_vertex.bin")
    ex["P"] = img("lambert_pixel.bin")
    return ex


def _write_ply(path, pos, nrm, faces):
    v = np.hstack([pos, nrm]).astype("<f4")
    f = np.empty(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    f["n"], f["i"] = 3, faces
    with open(path, "wb") as fh:
        fh.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
                  "property float x\nproperty float y\nproperty float z\n"
                  "property float nx\nproperty float ny\nproperty float nz\n"
                  "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
                  % (len(v), len(f))).encode())
        fh.write(v.tobytes())
        fh.write(f.tobytes())


def mitsuba_scene(ex, tmp):
    """Receivers (vertex normals = the harness's) and one area emitter per lit side."""
    d = {"type": "scene"}
    path = os.path.join(tmp, "receivers.ply")
    _write_ply(path, ex["pos"], ex["nrm"], ex["tri"])
    d["receivers"] = {"type": "ply", "filename": path}
    for j, q in enumerate(ex["polygons"]):
        v = np.asarray(q["v"], dtype=np.float64).reshape(-1, 3)
        fan = np.array([[0, k, k + 1] for k in range(1, len(v) - 1)])
        for side in range(2 if q["two_sided"] else 1):
            p = os.path.join(tmp, "light%d_%d.ply" % (j, side))
            f = fan if side == 0 else fan[:, ::-1]
            nrm = np.cross(v[1] - v[0], v[2] - v[0]) * (1 if side == 0 else -1)
            _write_ply(p, v, np.tile(nrm / np.linalg.norm(nrm), (len(v), 1)), f)
            d["light%d_%d" % (j, side)] = {"type": "ply", "filename": p, "face_normals": True,
                                           "emitter": {"type": "area",
                                                       "radiance": {"type": "rgb", "value": q["rgb"]}}}
    return mi.load_dict(d)


def camera_rays(ex, pix):
    """Rays through the centres of pixels pix (flat indices): the raster's camera
    (bench/common/raster.c: focal = h / 2 / tan(fov / 2), up +y, y down the rows)."""
    w, h = ex["width"], ex["height"]
    eye, tgt = np.asarray(ex["eye"]), np.asarray(ex["target"])
    fwd = (tgt - eye) / np.linalg.norm(tgt - eye)
    right = np.cross(fwd, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    focal = 0.5 * h / math.tan(0.5 * math.radians(ex["fov_deg"]))
    px = (pix % w) + 0.5
    py = (pix // w) + 0.5
    d = fwd[None, :] + np.outer((px - 0.5 * w) / focal, right) + np.outer((0.5 * h - py) / focal, up)
    d /= np.linalg.norm(d, axis=1)[:, None]
    return mi.Ray3f(mi.Point3f(*[np.full(len(pix), eye[k], dtype=np.float32) for k in range(3)]),
                    mi.Vector3f(*[d[:, k].astype(np.float32) for k in range(3)]))


def clamped_cosine_factors(lmax):
    """A_l, l = 0..lmax: the clamped cosine max(cos, 0) = sum_l A_l (2l+1)/(4 pi) P_l(cos)
    (Ramamoorthi & Hanrahan 2001: A_0 = pi, A_1 = 2 pi / 3, odd l > 1: 0, even l:
    2 pi (-1)^(l/2-1) / ((l+2)(l-1)) * l! / (2^l ((l/2)!)^2)); closed form, not shlight's."""
    a = []
    for l in range(lmax + 1):
        if l <= 1:
            a.append(math.pi if l == 0 else 2 * math.pi / 3)
        elif l % 2:
            a.append(0.0)
        else:
            lg = math.lgamma(l + 1) - l * math.log(2) - 2 * math.lgamma(l / 2 + 1)
            a.append(2 * math.pi * (-1) ** (l // 2 - 1) / ((l + 2) * (l - 1)) * math.exp(lg))
    return a


def band_limited_cosine(t, lmax):
    """K_L(t) = sum_{l <= L} A_l (2l+1)/(4 pi) P_l(t): the SH truncation of max(t, 0) at
    band L, so that integral L(w) K_L(n.w) dw = sum_{l <= L} A_l sum_m L_lm Y_lm(n) is
    exactly the irradiance that PRT at lmax L computes.  P_l by Bonnet's recurrence."""
    a = clamped_cosine_factors(lmax)
    p0, p1 = 1.0 + 0.0 * t, t
    k = a[0] / (4 * math.pi) * p0 + a[1] * 3 / (4 * math.pi) * p1
    for l in range(1, lmax):
        p0, p1 = p1, ((2 * l + 1) * t * p1 - l * p0) / (l + 1)
        if a[l + 1] != 0.0:
            k = k + a[l + 1] * (2 * l + 3) / (4 * math.pi) * p1
    return k


class MitsubaOracle:
    """Primary hits of the compared pixels, and unshadowed emitter sampling at any points."""

    def __init__(self, ex, tmp):
        self.scene = mitsuba_scene(ex, tmp)
        pix = np.nonzero(ex["pixel_tri"] >= 0)[0]
        si = self.scene.ray_intersect(camera_rays(ex, pix))
        recv = si.is_valid() & ~si.shape.is_emitter()
        prim = np.where(recv.numpy(), si.prim_index.numpy().astype(np.int64), -1)
        same = prim == ex["pixel_tri"][pix]
        self.pix_raster = len(pix)
        self.pix = pix[same]
        self.pix_p = si.p.numpy()[:, same].T
        self.pix_n = si.sh_frame.n.numpy()[:, same].T
        self.pix_albedo = ex["albedo"][ex["pixel_tri"][self.pix]]
        tri = ex["tri"][ex["pixel_tri"][self.pix]]
        self.verts = np.unique(tri)                        # vertices the compared pixels interpolate
        valb = np.zeros((ex["nv"], 3))
        valb[ex["tri"].ravel()] = np.repeat(ex["albedo"], 3, axis=0)
        self.vert_albedo = valb[self.verts]

    def _pass(self, pts, nrm, albedo, spp, seed, lmax):
        npt = len(pts)
        per = max(1, LANES // spp)
        out = np.empty((npt, 3))
        for a in range(0, npt, per):
            m = min(per, npt - a)
            lanes = m * spp
            idx = dr.arange(UInt32, lanes) // dr.opaque(UInt32, spp)
            it = dr.zeros(mi.Interaction3f, lanes)
            it.p = mi.Point3f(*[dr.gather(Float, Float(np.ascontiguousarray(pts[a:a + m, k], np.float32)), idx)
                                for k in range(3)])
            n = mi.Vector3f(*[dr.gather(Float, Float(np.ascontiguousarray(nrm[a:a + m, k], np.float32)), idx)
                              for k in range(3)])
            sampler = mi.load_dict({"type": "independent"})
            sampler.seed(dr.opaque(UInt32, (seed * 1000003 + a) & 0xFFFFFFFF), lanes)
            ds, spec = self.scene.sample_emitter_direction(it, sampler.next_2d(), False)
            c = dr.dot(n, ds.d)
            e = spec * (dr.maximum(c, 0.0) if lmax is None else band_limited_cosine(c, lmax))
            s = [dr.block_sum(e[k], spp) for k in range(3)]
            dr.eval(*s)
            out[a:a + m] = np.stack([np.asarray(t.numpy(), dtype=np.float64) for t in s], axis=1) / spp
        return out * albedo / math.pi

    def estimate(self, pts, nrm, albedo, passes, spp, seed, lmax=None):
        """Outgoing radiance albedo/pi * integral L(w) k(n.w) dw at pts (k = max(cos, 0), or
        K_lmax): passes independent passes of spp samples per point.  Returns (mean,
        standard error, seconds per spp for all points); the first pass also compiles the
        kernels, so the time is the median of the others."""
        imgs, secs = [], []
        for r in range(passes):
            t = time.time()
            imgs.append(self._pass(pts, nrm, albedo, spp, seed + r, lmax))
            secs.append(time.time() - t)
        imgs = np.stack(imgs)
        sec_spp = float(np.median(secs[1:] if passes > 1 else secs) / spp)
        return imgs.mean(0), imgs.std(0, ddof=1) / math.sqrt(passes), sec_spp

    def render(self, passes, spp, seed):
        return self.estimate(self.pix_p, self.pix_n, self.pix_albedo, passes, spp, seed)


# ---------------------------------------------------------------------------
# Statistics
# ---------------------------------------------------------------------------
def excess_z(d, se):
    """Excess of the mean square of d over Mitsuba's noise, as a z score.  Per point
    q = sum over channels of (d^2 - se^2): se^2 is an unbiased estimate of the variance of
    Mitsuba's mean, so if d is Mitsuba's noise alone E q = 0, and a systematic error adds
    its square.  Points are independent (each has its own samples; channels of a point
    share them, hence the sum per point), so mean(q) / (std(q) / sqrt(N)) is
    asymptotically standard normal."""
    q = np.sum(d * d - se * se, axis=1)
    return float(q.mean() / (q.std(ddof=1) / math.sqrt(len(q))))


def max_t(d, se, use):
    """Largest |d| / se over the points use (bool per point) and channels with se > 0."""
    m = (se > 0) & use[:, None]
    return float(np.max(np.abs(d[m]) / se[m])), int(np.sum(m))


def errors(a, b, se=None):
    """MAE, RMSE and -- when b is Mitsuba's estimate with standard errors se -- the RMSE
    with Mitsuba's noise removed, sqrt(max(0, mean(d^2 - se^2))), with its standard error."""
    d = a - b
    mae = float(np.mean(np.abs(d)))
    rmse = float(np.sqrt(np.mean(d * d)))
    if se is None:
        return mae, rmse, rmse, 0.0
    q = np.mean(d * d - se * se, axis=1)
    ms, u = float(q.mean()), float(q.std(ddof=1) / math.sqrt(len(q)))
    deb = math.sqrt(max(ms, 0.0))
    return mae, rmse, deb, u / (2 * deb) if deb > 0 else math.sqrt(u)


def to_png(path, rows, exposure):
    """Grid of (label, image (h, w, 3) linear) panels: exposure, then sRGB; label below each."""
    from PIL import Image, ImageDraw
    h, w = rows[0][0][1].shape[:2]
    gap, lab = 4, 14
    ncol = max(len(r) for r in rows)
    canvas = Image.new("RGB", (ncol * (w + gap) - gap, len(rows) * (h + lab + gap) - gap), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    for j, row in enumerate(rows):
        for i, (text, img) in enumerate(row):
            x = np.clip(img * exposure, 0, 1)
            srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
            x0, y0 = i * (w + gap), j * (h + lab + gap)
            canvas.paste(Image.fromarray((255 * srgb + 0.5).astype(np.uint8)), (x0, y0))
            draw.text((x0 + 2, y0 + h + 1), text, fill=(0, 0, 0))
    canvas.save(path)


def run_scene(exe, scene_file, size, lmaxes, lhi, llow, render, vertex, seed, alpha, sidak_t, png=None):
    """Export a scene, render it in Mitsuba (render = (passes, spp) per pixel) and estimate the
    band-limited radiance at the vertices the compared pixels use (vertex = (passes, spp)).
    Tests, each at false-alarm rate alpha:
      (i)  Mitsuba's image vs P (closed form per pixel): the excess mean square over Mitsuba's
           noise (excess_z, one-sided) and the largest |t| (Sidak over the pixels);
      (ii) shlight's per-vertex radiance at lhi vs Mitsuba's estimate of
           albedo/pi * integral L(w) K_lhi(n.w) dw at the same vertices: the same two statistics.
    Power self-checks: the same tests must reject deliberately wrong inputs."""
    w, h = size
    with tempfile.TemporaryDirectory(prefix="shl_oracle_img_") as tmp:  # Mitsuba keeps the meshes in memory
        ex = export(exe, scene_file, os.path.join(tmp, "export"), w, h, sorted(set(lmaxes) | {lhi, llow}))
        O = MitsubaOracle(ex, tmp)
    M, se, sec_spp = O.render(render[0], render[1], seed)
    pix = O.pix
    P, G = ex["P"][pix], ex["G"][pix]
    zq = NormalDist().inv_cdf(1.0 - alpha)
    r = {"name": ex["name"], "size": size, "pix_raster": O.pix_raster, "pix": len(pix), "nverts": len(O.verts),
         "render": render, "vertex": vertex, "sec_spp": sec_spp, "mean": float(M.mean()), "z_alpha": zq,
         "prt_seconds": ex["prt_seconds"], "threads": dr.thread_count()}
    r["se_rms"] = float(np.sqrt(np.mean(se * se)))
    r["sigma1"] = r["se_rms"] * math.sqrt(render[0] * render[1])

    def tests(d, s, passes, use):
        t, n = max_t(d, s, use)
        return {"excess_z": excess_z(d, s), "max_t": t, "t_alpha": sidak_t(alpha, n, passes - 1)}

    def passed(t):
        return t["excess_z"] <= zq and t["max_t"] <= t["t_alpha"]

    # Pixels darker than 1% of the mean are left to the excess test: there the lit part of a
    # light is a sliver above the horizon, hit by few samples, and t is far from normal.
    bright = P.max(axis=1) >= 0.01 * P.mean()
    r["i"] = tests(P - M, se, render[0], bright)
    Pimg = ex["P"].reshape(h, w, 3)
    r["i_power"] = [(name, passed(tests(bad - M, se, render[0], bright))) for name, bad in (
        ("closed form one pixel to the right", np.roll(Pimg, 1, axis=1).reshape(-1, 3)[pix]),
        ("closed form x 1.01", P * 1.01))]
    V, vse, _ = O.estimate(ex["pos"][O.verts], ex["nrm"][O.verts], O.vert_albedo, vertex[0], vertex[1],
                           seed + 7919, lmax=lhi)
    Sv = ex["vertex"][lhi][O.verts]
    r["vse_rel"] = float(np.sqrt(np.mean(vse * vse)) / np.mean(V))
    allv = np.ones(len(V), bool)
    r["ii"] = tests(Sv - V, vse, vertex[0], allv)
    r["ii_power"] = [(name, passed(tests(bad - V, vse, vertex[0], allv))) for name, bad in (
        ("shlight at lmax %d" % llow, ex["vertex"][llow][O.verts]),
        ("shlight x 1.005", Sv * 1.005))]
    r["ok"] = passed(r["i"]) and passed(r["ii"]) and not any(p for _, p in r["i_power"] + r["ii_power"])
    rows = []
    for L in lmaxes:
        S = ex["prt"][L][pix]
        mae, rmse, deb, u = errors(S, M, se)
        rows.append(("PRT lmax %d" % L, mae, rmse, deb, u, errors(S, G)[1], errors(S, P)[1],
                     sec_spp * (r["sigma1"] / deb) ** 2 if deb > 0 else float("inf"), ex["prt_seconds"][L]))
    for name, A in (("closed form per vertex (lmax = inf)", G), ("closed form per pixel", P)):
        mae, rmse, deb, u = errors(A, M, se)
        rows.append((name, mae, rmse, deb, u, errors(A, G)[1], errors(A, P)[1], None, None))
    r["rows"] = rows
    if png:
        def full(a):
            img = np.zeros((w * h, 3))
            img[pix] = a
            return img.reshape(h, w, 3)
        lum = M @ np.array([0.2126, 0.7152, 0.0722])
        expo = 0.9 / max(float(np.percentile(lum, 97)), 1e-12)
        k = 10
        lo = min(lmaxes)
        to_png(png, [[("shlight PRT lmax %d" % lo, full(ex["prt"][lo][pix])),
                      ("shlight PRT lmax %d" % lhi, full(ex["prt"][lhi][pix])),
                      ("Mitsuba, %d spp" % (render[0] * render[1]), full(M))],
                     [("%dx |lmax %d - Mitsuba|" % (k, lo), full(k * np.abs(ex["prt"][lo][pix] - M))),
                      ("%dx |lmax %d - Mitsuba|" % (k, lhi), full(k * np.abs(ex["prt"][lhi][pix] - M))),
                      ("%dx |closed form - Mitsuba|" % k, full(k * np.abs(P - M)))]], expo)
    return r


def summary_line(r):
    return ("  image %s %dx%d: %d pixels, Mitsuba %d x %d spp (noise %.1e = %.2f%% of the mean), "
            "(i) excess z %.2f max|t| %.2f / %.2f, (ii) excess z %.2f max|t| %.2f / %.2f, power %s -> %s (%.0f s)"
            % (r["name"], r["size"][0], r["size"][1], r["pix"], r["render"][0], r["render"][1], r["se_rms"],
               100 * r["se_rms"] / r["mean"], r["i"]["excess_z"], r["i"]["max_t"], r["i"]["t_alpha"],
               r["ii"]["excess_z"], r["ii"]["max_t"], r["ii"]["t_alpha"],
               "all rejected" if not any(p for _, p in r["i_power"] + r["ii_power"]) else "NOT all rejected",
               "pass" if r["ok"] else "FAIL", r["seconds"]))


def _t(x):
    if x is None:
        return "-"
    return "below the noise" if math.isinf(x) else ("%.3g s" % x if x < 100 else "%.0f s" % x)


def report(results, alpha):
    """Markdown lines of the image section of bench/ORACLE.md."""
    L = ["## Check 3: images (shlight's PRT render vs Mitsuba)", ""]
    r0 = results[0]
    L.append("How it is done (tools/oracle_images.py, bench/oracle_export.c):")
    L.append("")
    L.append("- The harness (bench/common) renders each scene with PRT exactly as `make demo` does -- per-vertex "
             "analytic lighting (`shl_lights_eval_batch`) dotted with the unshadowed diffuse transfer, "
             "interpolated by the software raster -- at lmax 2..14 (transfer at lmax 14, lighting truncated).  "
             "Only scenes with `effects direct` and polygon lights are used (harness scenes that need no "
             "file outside the repository): no interreflection, no shadows, so Mitsuba's integrator samples "
             "the emitters without a visibility test.")
    L.append("- Mitsuba (%s) gets the same receivers (float32 vertices and the harness's vertex normals, PLY), "
             "one `area` emitter per lit side of each light (one-sided lights emit toward their "
             "counter-clockwise side in both; two-sided lights are two emitters of opposite winding), and one "
             "ray through each pixel centre with the raster's camera (focal = h / 2 / tan(fov / 2), up +y): no "
             "reconstruction filter, no tonemapping, linear radiance.  Pixels are compared only where "
             "Mitsuba's hit is the receiver triangle the raster drew (all of them, below)." % mi.variant())
    L.append("- At the hit, a vectorized integrator (Dr.Jit, llvm): `Scene.sample_emitter_direction(si, "
             "sample, test_visibility=False)`, outgoing radiance = albedo / pi x mean of L_e max(n.w, 0) / pdf, "
             "n the interpolated shading normal.  R independent passes (independent sampler seeds): the "
             "estimate is their mean, its standard error per pixel their standard deviation / sqrt(R).")
    L.append("- Exact references from Lambert's closed form for polygon irradiance (bench/common/lambert.c, "
             "no SH, not the library): 'closed form per vertex' -- the exact per-vertex radiance resolved "
             "through the same raster, i.e. the PRT render at lmax = infinity; 'closed form per pixel' -- "
             "evaluated at each pixel's own point and normal, i.e. what Mitsuba estimates.  Their difference "
             "is the error floor of per-vertex shading (Gouraud interpolation over the meshes' triangles), "
             "which no lmax removes.")
    L.append("- Errors over the compared pixels and the 3 channels, linear radiance.  Against Mitsuba the "
             "mean square contains Mitsuba's noise: 'noise removed' is sqrt(mean(d^2 - SE^2)) (SE^2 is an "
             "unbiased estimate of the noise variance of each pixel), with its standard error.  'Mitsuba "
             "time to this error': the measured seconds per sample per pixel for the whole image x the "
             "samples per pixel at which Mitsuba's own RMS noise, sigma_1 / sqrt(spp), equals that error "
             "(sigma_1 measured from the passes; Mitsuba has no other error here).  'shlight time': "
             "lighting + shading + resolve of the harness (%d threads)." % r0["threads"])
    L.append("")
    L.append("Tests (each at false-alarm rate %g; `make oracle-check` runs them on a 64x64 image):" % alpha)
    L.append("")
    L.append("- (i) conventions: Mitsuba's image vs the closed form per pixel.  Excess test: per pixel "
             "q = sum over channels of (d^2 - SE^2) has mean 0 if d is Mitsuba's noise alone and gains the "
             "square of any systematic error; pixels are independent, so z = mean(q) / (sd(q) / sqrt(N)) "
             "is asymptotically normal, and the test requires z <= %.2f (one-sided).  Local test: the largest "
             "|d| / SE over pixels and channels within the Sidak threshold (Student's t, R - 1 degrees of "
             "freedom) for that many comparisons; pixels darker than 1%% of the mean are left to the excess "
             "test (there a light's lit part is a sliver above the horizon that few samples hit, and t is far "
             "from normal)." % r0["z_alpha"])
    L.append("- (ii) shlight: its per-vertex radiance at lmax 14 (the values the image interpolates, at every "
             "vertex of a compared pixel's triangle) vs Mitsuba's estimate of exactly that quantity, "
             "albedo / pi x integral L(w) K_14(n.w) dw, K_14 the clamped cosine truncated to bands 0..14 "
             "(sum over l <= 14 of A_l (2l+1)/(4 pi) P_l, A_l in closed form -- Ramamoorthi & Hanrahan 2001; "
             "PRT at lmax L computes this integral exactly), sampled like (i), same two statistics.  No "
             "tolerance: a correct library differs from this by Mitsuba's noise only (and float storage, "
             "1e-7 relative).")
    L.append("- Power: the same tests must reject deliberately wrong inputs: (i) the closed form shifted by "
             "one pixel, or x 1.01; (ii) shlight's lmax-8 values in place of lmax 14, or lmax 14 x 1.005.")
    L.append("")
    L.append("| scene | size | pixels | vertices | Mitsuba spp per pixel (R x spp) | noise RMS / mean "
             "| (i) excess z | (i) max abs t / threshold | (ii) spp per vertex | (ii) noise / mean "
             "| (ii) excess z | (ii) max abs t / threshold | power: rejected | result |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        pw = r["i_power"] + r["ii_power"]
        L.append("| %s | %dx%d | %d | %d | %d x %d | %.2e | %.2f | %.2f / %.2f | %d x %d | %.2e | %.2f "
                 "| %.2f / %.2f | %d / %d | %s |" % (
                     r["name"], r["size"][0], r["size"][1], r["pix"], r["nverts"], r["render"][0],
                     r["render"][1], r["se_rms"] / r["mean"], r["i"]["excess_z"], r["i"]["max_t"],
                     r["i"]["t_alpha"], r["vertex"][0], r["vertex"][1], r["vse_rel"], r["ii"]["excess_z"],
                     r["ii"]["max_t"], r["ii"]["t_alpha"], sum(not p for _, p in pw), len(pw),
                     "pass" if r["ok"] else "FAIL"))
    L.append("")
    for r in results:
        L.append("### %s, %dx%d" % (r["name"], r["size"][0], r["size"][1]))
        L.append("")
        L.append("%d pixels compared (raster: %d), mean radiance %.4g; Mitsuba %d x %d samples per pixel in "
                 "%.0f s (%.3g s per sample per pixel for the image, sigma_1 = %.3g), noise RMS %.2e "
                 "(%.2f%% of the mean)." % (
                     r["pix"], r["pix_raster"], r["mean"], r["render"][0], r["render"][1],
                     r["sec_spp"] * r["render"][0] * r["render"][1], r["sec_spp"], r["sigma1"], r["se_rms"],
                     100 * r["se_rms"] / r["mean"]))
        L.append("")
        L.append("| image | MAE vs Mitsuba | RMSE vs Mitsuba | RMSE, noise removed | rel. | RMSE vs closed "
                 "form per vertex (SH truncation) | RMSE vs closed form per pixel | Mitsuba time to this error "
                 "| shlight time |")
        L.append("|---|---|---|---|---|---|---|---|---|")
        for name, mae, rmse, deb, u, eg, ep, tm, ts in r["rows"]:
            L.append("| %s | %.3e | %.3e | %.3e +- %.1e | %.2e | %.2e | %.2e | %s | %s |" % (
                name, mae, rmse, deb, u, deb / r["mean"], eg, ep, _t(tm), _t(ts)))
        L.append("")
        if r["png"]:
            L.append("![%s: shlight PRT and Mitsuba, differences x10](%s)" % (r["name"], r["png"]))
            L.append("")
            L.append("Top: shlight PRT at the lowest and highest lmax, Mitsuba.  Bottom: 10 x |difference| "
                     "at the same exposure (the last one is Mitsuba's noise plus nothing else: the closed form "
                     "per pixel is what Mitsuba estimates).")
            L.append("")
    return L
