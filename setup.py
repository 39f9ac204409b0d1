"""The extension tightex._tightex for pip, built by the project's own CMake build (the build
scripts/build.sh makes): configured for the interpreter pip runs, only the library and the module
(no tests, tools or benchmarks). TIGHTEX_CMAKE_BUILD_DIR names a build folder to reuse (one already
built with the same interpreter version: the tests use build/). The rest is pyproject.toml."""
import os
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        root = os.path.dirname(os.path.abspath(__file__))
        build = os.environ.get("TIGHTEX_CMAKE_BUILD_DIR") or os.path.join(os.path.abspath(self.build_temp), "cmake")
        if not os.path.isfile(os.path.join(build, "CMakeCache.txt")):
            generator = ["-G", "Ninja"] if shutil.which("ninja") else []
            subprocess.check_call(["cmake", "-S", root, "-B", build, *generator, "-DCMAKE_BUILD_TYPE=Release",
                                   f"-DPython3_EXECUTABLE={sys.executable}", "-DTIGHTEX_BUILD_PYTHON=ON",
                                   "-DTIGHTEX_BUILD_TESTS=OFF", "-DTIGHTEX_BUILD_TOOLS=OFF", "-DTIGHTEX_BUILD_BENCH=OFF"])
        subprocess.check_call(["cmake", "--build", build, "--target", "_tightex", "--parallel", str(os.cpu_count() or 1)])
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(os.path.join(build, "python", "tightex", os.path.basename(target)), target)


setup(ext_modules=[Extension("tightex._tightex", sources=[])], cmdclass={"build_ext": CMakeBuild})
