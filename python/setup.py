"""pip install ./python: the pure-Python modules and the C++ module _afford.

_afford is built by the project's CMake tree, in $AFFORD_BUILD (default: the
checkout's build/, configured first if it is not), and copied into the
package. The toolchain and the Debian packages of scripts/setup.sh are needed.
"""
import os
import shutil
import subprocess
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent.parent


class BuildWithCMake(build_py):
    def run(self):
        super().run()
        build = Path(os.environ.get("AFFORD_BUILD", ROOT / "build"))
        if not (build / "CMakeCache.txt").exists():
            subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release"], check=True)
        subprocess.run(["cmake", "--build", str(build), "--target", "afford_python", "-j", str(os.cpu_count() or 1)],
                       check=True)
        built = list((build / "python" / "afford").glob("_afford*.so"))
        if not built:
            raise RuntimeError(f"the build in {build} made no _afford module")
        for so in built:
            shutil.copy2(so, Path(self.build_lib) / "afford" / so.name)


setup(cmdclass={"build_py": BuildWithCMake})
