#!/usr/bin/env python3
"""Find a libLLVM that Dr.Jit 1.5's LLVM backend can use (make oracle-llvm, tools/oracle.py).

Dr.Jit loads libLLVM at run time: the file DRJIT_LIBLLVM_PATH names, else whatever its own
search finds first.  Dr.Jit 1.5 emits llvm.maximum / llvm.minimum, which LLVM 15 and 16 cannot
select on x86-64: the process dies inside LLVM ("LLVM ERROR: Cannot select ... fmaximum",
exit 134).  Debian 12 ships libLLVM 15 by default; `apt-get install libllvm19` adds 19.

    python3 tools/find_libllvm.py    prints the newest libLLVM >= MIN_MAJOR, or says how to
                                     install one and exits with status 1

Standard library only, nothing is loaded: versions are read off the file names
(libLLVM-15.so.1, libLLVM.so.19.1, libLLVM-19.so; a symlink such as libLLVM.so is resolved).
Directories searched: SHLIGHT_LLVM_DIRS (colon-separated) if set, else the multiarch library
directory (/usr/lib/x86_64-linux-gnu, /usr/lib/aarch64-linux-gnu, ...), /usr/lib64, /usr/lib,
/usr/local/lib and /usr/lib/llvm-*/lib.  A DRJIT_LIBLLVM_PATH already set is kept if it exists
and is not known to be too old.

tools/oracle.py also runs probe() on the choice before it imports Dr.Jit: a child process
compiles Dr.Jit kernels that use maximum / minimum, so that a libLLVM that still cannot (an
untested version, another architecture) fails there with a message, not in the oracle.
"""
import glob
import os
import platform
import re
import shutil
import signal
import subprocess
import sys
import sysconfig

MIN_MAJOR = 17           # tested here: 15 and 16 abort, 19 passes; 17, 18 untested (probe() guards)
APT_PACKAGE = "libllvm19"

_NAME = re.compile(r"^libLLVM(?:-(\d+)(?:\.\d+)*\.so(?:\.\d+)*|\.so\.(\d+)(?:\.\d+)*)$")


def major_version(path):
    """LLVM major version from the library's file name (symlinks resolved), or None."""
    m = _NAME.match(os.path.basename(os.path.realpath(path)))
    return int(m.group(1) or m.group(2)) if m else None


def _multiarch():
    tuple_ = sysconfig.get_config_var("MULTIARCH")
    if not tuple_ and shutil.which("gcc"):
        r = subprocess.run(["gcc", "-dumpmachine"], capture_output=True, text=True)
        tuple_ = r.stdout.strip() if r.returncode == 0 else None
    return tuple_ or "%s-linux-gnu" % platform.machine()


def search_dirs():
    env = os.environ.get("SHLIGHT_LLVM_DIRS")
    if env is not None:
        return [d for d in env.split(":") if d]
    return (["/usr/lib/" + _multiarch(), "/usr/lib64", "/usr/lib", "/usr/local/lib"]
            + sorted(glob.glob("/usr/lib/llvm-*/lib")))


def candidates():
    """[(major, path)] of every libLLVM found, newest first, one path per real file."""
    seen, out = set(), []
    for d in search_dirs():
        for p in sorted(glob.glob(os.path.join(d, "libLLVM*.so*"))):
            real = os.path.realpath(p)
            v = major_version(p)
            if v is None or real in seen or not os.path.isfile(real):
                continue
            seen.add(real)
            out.append((v, p))
    out.sort(key=lambda c: -c[0])
    return out


def install_hint():
    if shutil.which("apt-get"):
        how = "apt-get install %s   (as root; Debian 12/13, Ubuntu 24.04)" % APT_PACKAGE
    else:
        how = "install LLVM >= %d's shared library (libLLVM-<N>.so) with the system's package manager" % MIN_MAJOR
    return ("  Fix: %s\n  or point DRJIT_LIBLLVM_PATH at a libLLVM >= %d, e.g.\n"
            "  DRJIT_LIBLLVM_PATH=/usr/lib/%s/libLLVM.so.19.1 make oracle-check"
            % (how, MIN_MAJOR, _multiarch()))


def locate():
    """Path of the libLLVM to use.  Raises SystemExit with what to do when there is none."""
    user = os.environ.get("DRJIT_LIBLLVM_PATH")
    if user:
        v = major_version(user)
        if not os.path.exists(user):
            raise SystemExit("oracle: DRJIT_LIBLLVM_PATH=%s does not exist.\n%s" % (user, install_hint()))
        if v is not None and v < MIN_MAJOR:
            raise SystemExit("oracle: DRJIT_LIBLLVM_PATH=%s is LLVM %d; Dr.Jit 1.5 needs LLVM >= %d "
                             "(older ones abort on fmaximum).\n%s" % (user, v, MIN_MAJOR, install_hint()))
        return user
    found = candidates()
    usable = [p for v, p in found if v >= MIN_MAJOR]
    if usable:
        return usable[0]
    seen = ", ".join("%s (LLVM %d)" % (p, v) for v, p in found) or "none"
    raise SystemExit("oracle: no libLLVM >= %d found for Dr.Jit 1.5's LLVM backend (older ones abort "
                     "on fmaximum).\n  Searched: %s\n  Found: %s\n%s"
                     % (MIN_MAJOR, ":".join(search_dirs()), seen, install_hint()))


_PROBE = """
import drjit as dr
from drjit.llvm import Float, Float64
for T in (Float, Float64):
    x = dr.arange(T, 37) - 18.5
    y = dr.maximum(x, -x) + dr.minimum(x, 0.5 * x)
    dr.eval(y)
    assert abs(dr.sum(y)[0] - sum(abs(v - 18.5) + min(v - 18.5, 0.5 * (v - 18.5)) for v in range(37))) < 1e-3
"""


def probe(path):
    """Compile and run Dr.Jit kernels with maximum / minimum against `path` in a child process.
    Returns None if they work, else how the child ended and its first lines of output (it may abort in LLVM)."""
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=path)
    r = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True)
    if r.returncode == 0:
        return None
    head = [l for l in (r.stderr + r.stdout).splitlines() if l.strip()][:3]
    how = ("killed by %s" % signal.Signals(-r.returncode).name if r.returncode < 0
           else "exit status %d" % r.returncode)
    return "%s: %s" % (how, " | ".join(head))


if __name__ == "__main__":
    print(locate())
