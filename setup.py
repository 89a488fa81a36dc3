# SPDX-License-Identifier: Apache-2.0
# The build behind pyproject.toml: CMake configures the project and builds the pybind11 module
# (target impulse_python), which goes into the package `impulse` beside python/impulse/__init__.py
# with the built-in scenes (scenes/*.toml). README "Install with pip".
#
# IMPULSE_CMAKE_BUILD_DIR names a configured CMake build to build the module in (the project's
# own build/: nothing is compiled twice); without it the build goes to build-python/cmake.
# CMAKE_ARGS adds configure options (e.g. -DCMAKE_CXX_COMPILER_LAUNCHER=ccache).
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
(ROOT / "build-python").mkdir(exist_ok=True)  # egg_info's egg_base


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\(impulse VERSION ([0-9.]+)", text).group(1)


def cmake_build_dir():
    given = os.environ.get("IMPULSE_CMAKE_BUILD_DIR")
    return Path(given).resolve() if given else ROOT / "build-python" / "cmake"


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class BuildWithCMake(build_ext):
    """Configures (unless the build directory already is) and builds impulse_python, then copies
    the module where setuptools packs the extension."""

    def build_extension(self, ext):
        build = cmake_build_dir()
        if not (build / "CMakeCache.txt").exists():
            build.mkdir(parents=True, exist_ok=True)
            configure = ["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                         "-DIMPULSE_BUILD_BENCH=OFF", f"-DPython3_EXECUTABLE={sys.executable}"]
            subprocess.run(configure + shlex.split(os.environ.get("CMAKE_ARGS", "")), check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build), "--target", "impulse_python", "-j", jobs], check=True)
        built = sorted((build / "python").glob("impulse.*.so"))
        if not built:
            raise RuntimeError(f"{build}/python: the module impulse_python did not build")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built[-1], target)


class BuildWithScenes(build_py):
    """Puts the built-in scenes in the package (impulse/scenes), where __init__.py points the
    module at them."""

    def run(self):
        super().run()
        scenes = Path(self.build_lib) / "impulse" / "scenes"
        scenes.mkdir(parents=True, exist_ok=True)
        for toml in sorted((ROOT / "scenes").glob("*.toml")):
            shutil.copy2(toml, scenes / toml.name)


setup(
    version=project_version(),
    packages=["impulse"],
    package_dir={"impulse": "python/impulse"},
    ext_modules=[CMakeExtension("impulse.impulse")],
    cmdclass={"build_ext": BuildWithCMake, "build_py": BuildWithScenes},
    options={"build": {"build_base": "build-python/setuptools"},
             "egg_info": {"egg_base": "build-python"}},
    zip_safe=False,
)
