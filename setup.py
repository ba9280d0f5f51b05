"""Builds the compiled module of the Python package with CMake; pyproject.toml has the rest.

CMake configures the source tree for the interpreter that runs this (sys.executable): Release,
without MPI, tests or benchmarks, and builds the target rp_python alone, in build-pip/ beside
CMakeLists.txt (RAYPACK_PIP_BUILD_DIR to change it). Compiles go through ccache when it is
installed (CMakeLists.txt), whose keys take this tree's paths relative to it: a build folder one
level down, as build/ and build-pip/ both are, compiles each file with the same command line and
so reuses what another build of the same source compiled. Jobs: CMAKE_BUILD_PARALLEL_LEVEL, else
one per core.
"""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
BUILD = Path(os.environ.get("RAYPACK_PIP_BUILD_DIR", ROOT / "build-pip")).resolve()


def cmake_version():
    """The version of project(raypack VERSION x.y.z) in CMakeLists.txt: the one version."""
    found = re.search(r"project\(raypack VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())
    if not found:
        sys.exit("setup.py: CMakeLists.txt has no project(raypack VERSION ...)")
    return found.group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        configure = ["cmake", "-S", str(ROOT), "-B", str(BUILD), f"-DPython_EXECUTABLE={sys.executable}",
                     "-DCMAKE_BUILD_TYPE=Release", "-DRAYPACK_MPI=OFF", "-DRAYPACK_BUILD_TESTS=OFF",
                     "-DRAYPACK_BUILD_BENCH=OFF", "-DRAYPACK_BUILD_PYTHON=ON"]
        try:  # pybind11 from pip (an isolated build) brings its CMake package; Debian's is found as it is
            import pybind11
            configure.append(f"-Dpybind11_DIR={pybind11.get_cmake_dir()}")
        except ImportError:
            pass
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        subprocess.run(configure, check=True)
        subprocess.run(["cmake", "--build", str(BUILD), "--target", "rp_python", "-j", jobs], check=True)
        built = sorted((BUILD / "python" / "raypack").glob("_raypack*.so"))
        if len(built) != 1:
            sys.exit(f"setup.py: expected one _raypack*.so in {BUILD / 'python' / 'raypack'}, found {built}")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


BUILD.mkdir(parents=True, exist_ok=True)
setup(version=cmake_version(), ext_modules=[Extension("raypack._raypack", sources=[])],
      cmdclass={"build_ext": CMakeBuild},
      # setuptools' own folders beside CMake's, not in build/ (the documented CMake build) nor python/.
      options={"build": {"build_base": str(BUILD)}, "egg_info": {"egg_base": str(BUILD)}})
