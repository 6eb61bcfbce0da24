"""Rewrite the build machine's Python/numpy include folders in the ROS wheels' exported
CMake files to this interpreter's (CMake rejects non-existent include paths).
Usage: python tools/fix_cmake_paths.py VENV   (idempotent)."""
import glob
import re
import sys
import sysconfig

import numpy

venv = sys.argv[1]
py_inc = sysconfig.get_paths()["include"]
np_inc = numpy.get_include()
py_pat = re.compile(r"/opt/python/cp311-cp311/include/python3\.11")
np_pat = re.compile(r"/opt/python/cp311-cp311/lib/python3\.11/site-packages/numpy/_core/include"
                    r"|/tmp/[^;\"]*?/site-packages/numpy/_core/include"
                    r"|/opt/[^;\"]*?/site-packages/numpy/_core/include")
changed = 0
for path in glob.glob(f"{venv}/share/*/cmake/*.cmake"):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    new = np_pat.sub(np_inc, py_pat.sub(py_inc, text))
    if new != text:
        with open(path, "w", encoding="utf-8") as f:
            f.write(new)
        changed += 1
print(f"[setup] cmake include paths: {changed} file(s) rewritten")
