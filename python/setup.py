# SPDX-License-Identifier: MIT
"""Builds the extension strike._strike with CMake for `pip install ./python` (pyproject.toml).

The extension is the CMake target strike_python of the repository one folder up, built in
STRIKE_CMAKE_BUILD_DIR when it is set (an existing build tree, e.g. build/ci: only what changed is
rebuilt) or else in build/pip, configured Release with the Python that runs pip. Its module and
the configured _version.py are copied into the wheel beside the pure-Python files of python/strike.
"""
import importlib.machinery
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def project_version() -> str:
    """The version of the top-level CMakeLists.txt's project() (the bank's and the CLI's)."""
    match = re.search(r"project\(strike VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())
    if not match:
        sys.exit(f"setup.py: no `project(strike VERSION ...)` in {ROOT / 'CMakeLists.txt'}")
    return match.group(1)


def cmake_build_dir() -> Path:
    return Path(os.environ.get("STRIKE_CMAKE_BUILD_DIR") or ROOT / "build" / "pip").resolve()


class CMakeBuild(build_ext):
    def build_extension(self, ext: Extension) -> None:
        build_dir = cmake_build_dir()
        if not (build_dir / "CMakeCache.txt").exists():
            subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                                   "-DSTRIKE_BUILD_TESTS=OFF", "-DSTRIKE_BUILD_PYTHON=ON",
                                   f"-DPython_EXECUTABLE={sys.executable}"])
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "strike_python", "--parallel", jobs])
        built = build_dir / "python" / "strike"
        suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
        module = built / f"_strike{suffix}"
        if not module.exists():
            found = ", ".join(p.name for p in built.glob("_strike*")) or "nothing"
            sys.exit(f"setup.py: {build_dir} built {found}, not _strike{suffix} for this Python "
                     f"({sys.executable}); set STRIKE_CMAKE_BUILD_DIR to an empty folder to build for it")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(module, target)
        shutil.copy2(built / "_version.py", target.parent / "_version.py")


# setuptools' own build files go beside CMake's, not into the source tree.
setuptools_dir = cmake_build_dir() / "setuptools"
setuptools_dir.mkdir(parents=True, exist_ok=True)
setup(version=project_version(), ext_modules=[Extension("strike._strike", sources=[])],
      cmdclass={"build_ext": CMakeBuild},
      options={"build": {"build_base": str(setuptools_dir)}, "egg_info": {"egg_base": str(setuptools_dir)}})
