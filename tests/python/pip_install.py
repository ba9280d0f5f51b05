"""Python.PipInstallsTheSourceTree: the package installed as a Python user installs it, from a
clean copy of the source, and used from elsewhere.

Usage: pip_install.py SOURCE_DIR WORK_DIR   (CTest runs it with the build's Python_EXECUTABLE)

1. WORK_DIR/src: a copy of the files git tracks in SOURCE_DIR, as they are in its working tree
   (what a clone would hold, with the uncommitted edits a developer is testing: a file left out
   of git is left out here too, and fails the install as it would a clone). A source that is not
   a git checkout is copied whole, less its build* folders.
2. WORK_DIR/venv: `python3 -m venv --system-site-packages`, then `pip install
   --no-build-isolation --no-index` of the copy: offline, with the system's setuptools, wheel,
   pybind11 and numpy. The build goes through ccache (setup.py), so a tree built before from the
   same source compiles nothing anew. CMAKE_BUILD_PARALLEL_LEVEL jobs, 1 unless set (CTest runs
   other tests beside it).
3. From WORK_DIR (neither the copy nor the build tree): import raypack from the venv, its files
   and version, and one ray traced, which must hit triangle 56666 of the default scene.
Any failure exits non-zero with the step's output. Prints each step's seconds.
"""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

source, work = Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()
env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "PIP_REQUIRE_VIRTUALENV")}
env.setdefault("CMAKE_BUILD_PARALLEL_LEVEL", "1")
env.update(PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1")
seconds = {}


def step(name, command, cwd=None):
    start = time.monotonic()
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True)
    seconds[name] = time.monotonic() - start
    if done.returncode != 0:
        sys.exit(f"pip_install: {name} failed ({done.returncode}): {' '.join(map(str, command))}\n"
                 f"{done.stdout[-20000:]}\n{done.stderr[-20000:]}")
    return done.stdout


def tracked_files():
    """The files git tracks in `source` (None when it is not a git checkout's top level)."""
    try:
        top = subprocess.run(["git", "-C", source, "rev-parse", "--show-toplevel"], capture_output=True, text=True)
    except FileNotFoundError:
        return None
    if top.returncode != 0 or Path(top.stdout.strip()).resolve() != source:
        return None
    listed = subprocess.run(["git", "-C", source, "ls-files", "-z"], capture_output=True, text=True, check=True)
    return [name for name in listed.stdout.split("\0") if name]


shutil.rmtree(work, ignore_errors=True)
copy = work / "src"
start = time.monotonic()
files = tracked_files()
if files is None:
    shutil.copytree(source, copy, symlinks=True,
                    ignore=lambda folder, names: [n for n in names if Path(folder) == source and
                                                  (n.startswith("build") or n == ".git")])
else:
    for name in files:
        if (source / name).exists() or (source / name).is_symlink():  # deleted in the working tree: left out
            (copy / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source / name, copy / name, follow_symlinks=False)
seconds["copy"] = time.monotonic() - start

venv = work / "venv"
python = venv / "bin" / "python"
step("venv", [sys.executable, "-m", "venv", "--system-site-packages", venv])
step("pip install", [python, "-m", "pip", "install", "--no-build-isolation", "--no-index", copy])
check = f"""
import importlib.metadata, os, sysconfig
import raypack
here = os.path.realpath(raypack.__file__)
assert here.startswith(os.path.realpath(sysconfig.get_path("purelib")) + os.sep), here
package = os.path.dirname(here)
files = sorted(f for f in os.listdir(package) if f != "__pycache__")
assert len(files) == 4 and files[0] == "__init__.py" and files[1].startswith("_raypack.") and files[1].endswith(".so") \
    and files[2:] == ["_raypack.pyi", "py.typed"], files
assert importlib.metadata.version("raypack") == raypack.__version__, raypack.__version__
hits = raypack.Backend("embree", raypack.load_scene("default")).intersect([0, 3.4, 8.5], [0, -0.27, -1])
assert hits["prim_id"] == 56666, hits
print(raypack.__version__, here)
"""
print("pip_install: imported", step("import", [python, "-c", check], cwd=work).strip())
print("pip_install: seconds:", ", ".join(f"{name} {s:.1f}" for name, s in seconds.items()),
      f"(jobs {env['CMAKE_BUILD_PARALLEL_LEVEL']})")
