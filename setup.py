"""setuptools front of `pip install .`: builds the extension with the project's CMake (only the
gradel_python target; GRADEL_BUILD_PYTHON, every other component off) and packages it with the
pure-Python files of python/gradel/.

Environment:
  GRADEL_CMAKE_BUILD_DIR  an already configured gradel build tree to reuse (it must have the
                          Python component for this interpreter's version; only its
                          gradel_python target is brought up to date). Default: a build tree of
                          its own under build/python-package/cmake.
  GRADEL_CMAKE_ARGS       extra CMake arguments for that own tree.
  GRADEL_PORTABLE=1       a portable engine even on an AVX2 + FMA host. By default the own tree is
                          compiled for x86-64-v3 when /proc/cpuinfo shows avx2 and fma (as
                          scripts/setup does): the element kernels run about 5x faster, and the
                          package runs only on such CPUs.
  CMAKE_BUILD_PARALLEL_LEVEL  jobs (default: CMake's).

Progress: the build prints "gradel: ..." lines and CMake's "[done/total]" steps; pip shows them
with `pip install -v .`. Without -v pip hides them, so on an interactive terminal (/dev/tty) the
"gradel: ..." lines and a "[done/total]" counter are written there too.
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


def host_has_v3():
    """True when this CPU has AVX2 and FMA (the parts of x86-64-v3 the engine's kernels use)."""
    try:
        flags = Path("/proc/cpuinfo").read_text().split()
    except OSError:
        return False
    return "avx2" in flags and "fma" in flags


def open_terminal():
    """The user's terminal when pip hides our output (stderr is not one), else None."""
    if sys.stderr.isatty():
        return None
    try:
        return open("/dev/tty", "w")
    except OSError:
        return None


TERMINAL = open_terminal()


def say(text):
    print(f"gradel: {text}", file=sys.stderr, flush=True)
    if TERMINAL:
        TERMINAL.write(f"\rgradel: {text}\033[K\n")
        TERMINAL.flush()


def build_with_progress(command):
    """Runs CMake's build, its lines to stderr (pip -v shows them); without -v, on a terminal, its
    "[done/total]" counter on one line."""
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        for line in proc.stdout:
            sys.stderr.write(line)
            if TERMINAL and line.startswith("["):
                TERMINAL.write(f"\rgradel: {line.split(' ', 1)[0]} compiling\033[K")
                TERMINAL.flush()
        if TERMINAL:
            TERMINAL.write("\n")
    if proc.returncode != 0:
        raise subprocess.CalledProcessError(proc.returncode, command)


def cached_option(tree, name):
    """The value of NAME in TREE's CMakeCache.txt, or None."""
    try:
        for line in (tree / "CMakeCache.txt").read_text().splitlines():
            if line.startswith(name + ":"):
                return line.split("=", 1)[1]
    except OSError:
        pass
    return None


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        reuse = os.environ.get("GRADEL_CMAKE_BUILD_DIR")
        if reuse:
            tree = Path(reuse).resolve()
            v3 = cached_option(tree, "GRADEL_X86_64_V3") or "OFF"
            say(f"reusing the build tree {tree} (GRADEL_X86_64_V3={v3})")
            if v3 != "ON" and host_has_v3():
                say("that tree is portable although this CPU has AVX2 + FMA: the element kernels run "
                    "about 5x slower than with -DGRADEL_X86_64_V3=ON")
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
            portable = os.environ.get("GRADEL_PORTABLE", "") not in ("", "0")
            v3 = "ON" if host_has_v3() and not portable else "OFF"
            args += [f"-DGRADEL_X86_64_V3={v3}"]
            args += shlex.split(os.environ.get("GRADEL_CMAKE_ARGS", ""))
            if v3 == "ON":
                say("this CPU has AVX2 + FMA: building the engine for x86-64-v3 (GRADEL_PORTABLE=1 for a portable one)")
            else:
                say("building a portable engine" + (" (GRADEL_PORTABLE=1)" if portable else " (no AVX2 + FMA on this CPU)"))
            if cached_option(tree, "GRADEL_X86_64_V3") != v3 or os.environ.get("GRADEL_CMAKE_ARGS"):
                say(f"configuring {tree}")
                subprocess.run(args, check=True, stdout=sys.stderr)
        say("compiling the engine and its Python module (a few minutes on 2 cores; [done/total] below)")
        build_with_progress(["cmake", "--build", str(tree), "--target", "gradel_python"])
        say("module built")
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
