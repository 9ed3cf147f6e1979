"""Thin ctypes binding of shlight (build/libshlight.so) for the Python tools.

Only what the tools need: contexts, the SH basis, polygon and sphere lights
with gradients, the solid angle.  Every call checks the status code and raises
ShlError on a negative one.  Arrays are numpy float64; nothing is compiled.

The library is looked up at $SHLIGHT_LIB, else <repo>/build/libshlight.so.
"""
import ctypes
import os

import numpy as np

__all__ = ["ShlError", "Ctx", "lib", "ncoeffs", "eval_basis", "polygon_solid_angle",
           "build_info", "strerror"]

_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_PATH = os.environ.get("SHLIGHT_LIB") or os.path.join(_ROOT, "build", "libshlight.so")

lib = ctypes.CDLL(_PATH)

_dp = ctypes.POINTER(ctypes.c_double)
_vp = ctypes.c_void_p


def _proto(name, restype, *argtypes):
    f = getattr(lib, name)
    f.restype = restype
    f.argtypes = list(argtypes)
    return f


_proto("shl_strerror", ctypes.c_char_p, ctypes.c_int)
_proto("shl_build_info", ctypes.c_char_p)
_proto("shl_ctx_create", ctypes.c_int, ctypes.c_int, ctypes.POINTER(_vp))
_proto("shl_ctx_destroy", None, _vp)
_proto("shl_ctx_lmax", ctypes.c_int, _vp)
_proto("shl_eval_basis", ctypes.c_int, ctypes.c_int, _dp, _dp)
_proto("shl_polygon", ctypes.c_int, _vp, _dp, _dp, ctypes.c_int, _dp)
_proto("shl_polygon_grad", ctypes.c_int, _vp, _dp, _dp, ctypes.c_int, _dp, _dp)
_proto("shl_polygon_solid_angle", ctypes.c_int, _dp, _dp, ctypes.c_int, _dp)
_proto("shl_sphere", ctypes.c_int, _vp, _dp, _dp, ctypes.c_double, _dp)
_proto("shl_sphere_grad", ctypes.c_int, _vp, _dp, _dp, ctypes.c_double, _dp, _dp)


class ShlError(RuntimeError):
    """A shlight call returned a negative status; .status holds it."""

    def __init__(self, func, status):
        super().__init__("%s: %s (%d)" % (func, strerror(status), status))
        self.status = status


def strerror(status):
    return lib.shl_strerror(int(status)).decode()


def build_info():
    return lib.shl_build_info().decode()


def ncoeffs(lmax):
    return (lmax + 1) * (lmax + 1)


def _check(func, status):
    if status != 0:
        raise ShlError(func, status)


def _vec(a, n=None):
    """Contiguous float64 copy of a and a C pointer to it (keep the array alive)."""
    a = np.ascontiguousarray(np.asarray(a, dtype=np.float64).reshape(-1))
    if n is not None and a.size != n:
        raise ValueError("expected %d values, got %d" % (n, a.size))
    return a, a.ctypes.data_as(_dp)


def eval_basis(lmax, direction):
    """Y_k(direction) for k < (lmax+1)^2 (direction need not be unit length)."""
    d, dp = _vec(direction, 3)
    y = np.zeros(ncoeffs(lmax))
    _check("shl_eval_basis", lib.shl_eval_basis(lmax, dp, y.ctypes.data_as(_dp)))
    return y


def polygon_solid_angle(x, verts):
    xa, xp = _vec(x, 3)
    v, vp = _vec(verts)
    om = ctypes.c_double()
    _check("shl_polygon_solid_angle", lib.shl_polygon_solid_angle(xp, vp, v.size // 3,
                                                                  ctypes.byref(om)))
    return om.value


class Ctx:
    """Evaluation context for bands 0..lmax (closed on close() or garbage collection)."""

    def __init__(self, lmax):
        h = _vp()
        _check("shl_ctx_create", lib.shl_ctx_create(int(lmax), ctypes.byref(h)))
        self._h = h
        self.lmax = int(lmax)
        self.nc = ncoeffs(self.lmax)

    def close(self):
        if getattr(self, "_h", None):
            lib.shl_ctx_destroy(self._h)
            self._h = None

    __del__ = close

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def polygon(self, x, verts):
        """coeffs[k] = integral of Y_k over the polygon's solid angle at x (unit radiance)."""
        xa, xp = _vec(x, 3)
        v, vp = _vec(verts)
        c = np.zeros(self.nc)
        _check("shl_polygon", lib.shl_polygon(self._h, xp, vp, v.size // 3, c.ctypes.data_as(_dp)))
        return c

    def polygon_grad(self, x, verts):
        """(coeffs, grad) with grad[a, k] = d coeffs[k] / d x[a] (shape 3 x nc)."""
        xa, xp = _vec(x, 3)
        v, vp = _vec(verts)
        c = np.zeros(self.nc)
        g = np.zeros(3 * self.nc)
        _check("shl_polygon_grad", lib.shl_polygon_grad(self._h, xp, vp, v.size // 3,
                                                        c.ctypes.data_as(_dp),
                                                        g.ctypes.data_as(_dp)))
        return c, g.reshape(3, self.nc)

    def sphere(self, x, center, radius):
        xa, xp = _vec(x, 3)
        ca, cp = _vec(center, 3)
        c = np.zeros(self.nc)
        _check("shl_sphere", lib.shl_sphere(self._h, xp, cp, float(radius), c.ctypes.data_as(_dp)))
        return c

    def sphere_grad(self, x, center, radius):
        xa, xp = _vec(x, 3)
        ca, cp = _vec(center, 3)
        c = np.zeros(self.nc)
        g = np.zeros(3 * self.nc)
        _check("shl_sphere_grad", lib.shl_sphere_grad(self._h, xp, cp, float(radius),
                                                      c.ctypes.data_as(_dp),
                                                      g.ctypes.data_as(_dp)))
        return c, g.reshape(3, self.nc)
