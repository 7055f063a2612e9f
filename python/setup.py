"""The extension module dartspp._dartspp for `pip install ./python` (pyproject.toml beside it): the C library's
sources (the Makefile's LIB_SRC: src/*/*.c except the CLI's main and the MPI cluster) and _dartspp.c, compiled
with the Makefile's flags and linked with its libraries. The sources are found relative to this file (../src),
so the package is installed from a checkout: pip builds a local folder in place."""
import glob
import os
import re
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy
from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
FLAGS = ["-std=c11", "-D_GNU_SOURCE", "-O3", "-fno-math-errno", "-fopenmp", "-fvisibility=hidden",
         "-Wall", "-Wextra"]
LIBS = ["embree3", "OpenEXRCore-3_1", "cjson", "png", "stb", "flann", "m"]


def rel(path):
    """A path relative to this folder, as setuptools wants an extension's sources."""
    return os.path.relpath(path, HERE)


def library_sources():
    src = os.path.join(ROOT, "src")
    if not os.path.isdir(src) or not os.path.isfile(os.path.join(ROOT, "include", "dartspp", "api.h")):
        sys.exit("dartspp setup.py: the library's sources are not at %s (install from a checkout of the "
                 "repository: pip install ./python)" % src)
    skip = {os.path.join(src, "cli", "main.c")}
    files = sorted(glob.glob(os.path.join(src, "*", "*.c")))
    return [f for f in files if f not in skip and os.path.basename(os.path.dirname(f)) != "cluster"]


def version():
    """The Makefile's VERSION, the one place it is written."""
    with open(os.path.join(ROOT, "Makefile")) as f:
        m = re.search(r"^VERSION\s*:?=\s*(\S+)", f.read(), re.M)
    return m.group(1) if m else "0"


class ParallelBuildExt(build_ext):
    """Compiles the library's 120-odd files on every core (setuptools compiles one extension's sources one
    after the other), their objects under the build folder: ../src/a/b.c to <build_temp>/src/a/b.o
    (setuptools would write <build_temp>/../src/a/b.o)."""

    def build_extension(self, ext):
        cc = self.compiler
        serial, names = cc.compile, cc.object_filenames

        def inside(sources, strip_dir=0, output_dir=""):
            return names([s[3:] if s.startswith("../") else s for s in sources], strip_dir, output_dir)

        def parallel(sources, output_dir=None, macros=None, include_dirs=None, debug=0, extra_preargs=None,
                     extra_postargs=None, depends=None):
            def one(s):
                return serial([s], output_dir, macros, include_dirs, debug, extra_preargs, extra_postargs,
                              depends)[0]
            with ThreadPoolExecutor(os.cpu_count() or 1) as pool:
                return list(pool.map(one, sources))

        cc.compile, cc.object_filenames = parallel, inside
        try:
            super().build_extension(ext)
        finally:
            cc.compile, cc.object_filenames = serial, names


ext = Extension(
    "dartspp._dartspp",
    sources=[os.path.join("dartspp", "_dartspp.c")] + [rel(f) for f in library_sources()],
    include_dirs=[os.path.join(ROOT, "include"), "/usr/include/OpenEXR", numpy.get_include()],
    libraries=LIBS,
    extra_compile_args=FLAGS,
    extra_link_args=["-fopenmp"],
)

setup(version=version(), ext_modules=[ext], cmdclass={"build_ext": ParallelBuildExt})
