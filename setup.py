"""setuptools front of `pip install .`: builds the extension with the project's CMake (only the
gradel_python target; GRADEL_BUILD_PYTHON, every other component off) and packages it with the
pure-Python files of python/gradel/.

Environment:
  GRADEL_CMAKE_BUILD_DIR  an already configured gradel build tree to reuse (it must have the
                          Python component for this interpreter's version; only its
                          gradel_python target is brought up to date). Default: a build tree of
                          its own under build/python-package/cmake.
  GRADEL_CMAKE_ARGS       extra CMake arguments for that own tree, e.g. "-DGRADEL_X86_64_V3=ON".
  CMAKE_BUILD_PARALLEL_LEVEL  jobs (default: CMake's).
"""
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
BUILD_BASE = "build/python-package"


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        reuse = os.environ.get("GRADEL_CMAKE_BUILD_DIR")
        if reuse:
            tree = Path(reuse).resolve()
        else:
            tree = ROOT / BUILD_BASE / "cmake"
            args = [
                "cmake", "-S", str(ROOT), "-B", str(tree), "-DCMAKE_BUILD_TYPE=Release",
                f"-DGRADEL_PYTHON_EXECUTABLE={sys.executable}",
                "-DGRADEL_BUILD_PYTHON=ON", "-DGRADEL_BUILD_CLI=OFF", "-DGRADEL_BUILD_TESTS=OFF",
                "-DGRADEL_BUILD_RENDER=OFF", "-DGRADEL_BUILD_VIEWER=OFF", "-DGRADEL_BUILD_FUZZ=OFF",
                "-DGRADEL_BUILD_BENCH=OFF", "-DGRADEL_BUILD_VALIDATE=OFF", "-DGRADEL_INSTALL=OFF",
            ]
            if shutil.which("ninja"):
                args += ["-G", "Ninja"]
            if shutil.which("ccache"):
                args += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"]
            args += shlex.split(os.environ.get("GRADEL_CMAKE_ARGS", ""))
            if not (tree / "CMakeCache.txt").exists() or os.environ.get("GRADEL_CMAKE_ARGS"):
                subprocess.run(args, check=True)
        subprocess.run(["cmake", "--build", str(tree), "--target", "gradel_python"], check=True)
        built = sorted((tree / "python" / "gradel").glob("gradel.*.so"))
        suffix = self.get_ext_filename("x")[1:]  # e.g. .cpython-311-x86_64-linux-gnu.so
        match = [p for p in built if p.name == "gradel" + suffix]
        if not match:
            raise RuntimeError(f"no gradel{suffix} in {tree / 'python' / 'gradel'} (built for another Python?)")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(match[0], target)


os.makedirs(ROOT / BUILD_BASE, exist_ok=True)
setup(
    packages=["gradel"],
    package_dir={"": "python"},
    package_data={"gradel": ["py.typed", "*.pyi"]},
    ext_modules=[CMakeExtension("gradel.gradel")],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": BUILD_BASE}, "egg_info": {"egg_base": BUILD_BASE}},
    zip_safe=False,
)
