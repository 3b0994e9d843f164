"""Builds the Python package fivebar with CMake (pyproject.toml; docs/install.md "Python").

`pip install --no-build-isolation .` configures build-python/cmake (Release, no tests) and builds
the target fivebar_python there; FIVEBAR_CMAKE_BUILD_DIR names an already configured build tree to
build it in instead (a developer's build/, the ctest `python_pip_install`). The wheel holds the
package (python/fivebar/), the extension, and the OpenSCAD library in fivebar/share/fivebar/scad,
where the library finds it beside the extension (lib/include/fivebar/share.hpp)."""
import os
import pathlib
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


def project_version():
    """The one version of the project: CMakeLists.txt's project(fivebar VERSION x.y.z)."""
    text = (ROOT / "CMakeLists.txt").read_text()
    m = re.search(r"project\(fivebar\s+VERSION\s+([0-9]+\.[0-9]+\.[0-9]+)", text)
    if not m:
        raise RuntimeError("CMakeLists.txt: no project(fivebar VERSION x.y.z)")
    return m.group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("FIVEBAR_CMAKE_BUILD_DIR") or ROOT / "build-python" / "cmake")
        if not (build_dir / "CMakeCache.txt").exists():
            generator = ["-G", "Ninja"] if shutil.which("ninja") else []
            subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build_dir), *generator, "-DCMAKE_BUILD_TYPE=Release",
                            "-DFIVEBAR_BUILD_TESTS=OFF", "-DFIVEBAR_PYTHON=ON", f"-DPython3_EXECUTABLE={sys.executable}"],
                           check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build_dir), "--target", "fivebar_python", "-j", jobs], check=True)
        built = sorted((build_dir / "python" / "fivebar").glob("_fivebar*.so"))
        if not built:
            raise RuntimeError(f"{build_dir}/python/fivebar: no _fivebar*.so after the build")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[-1], target)
        scad = target.parent / "share" / "fivebar" / "scad"
        scad.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / "scad" / "fivebar.scad", scad / "fivebar.scad")


(ROOT / "build-python").mkdir(exist_ok=True)  # setuptools' build and metadata (ignored by git: /build*/)
setup(
    version=project_version(),
    packages=["fivebar"],
    package_dir={"": "python"},
    package_data={"fivebar": ["__init__.pyi", "runtime.pyi", "py.typed"]},
    ext_modules=[Extension("fivebar._fivebar", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(ROOT / "build-python" / "setuptools")},
             "egg_info": {"egg_base": str(ROOT / "build-python")}},
    zip_safe=False,
)
