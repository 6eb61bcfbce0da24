"""The layering rules of STYLE.md, enforced: kernels import only numpy, numba and the
standard library; the core library imports no rclpy, rerun or test peers; the rerun
modules import rerun only inside their functions (so "off" never imports it)."""
import ast
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
KERNEL_OK = {"numpy", "numba", "math", "__future__"}
# jit.py and numba_speedups.py, the compile machinery, alone may use the standard library:
# to place numba's cache, to raise the garbage collector's thresholds while numba
# compiles, to load a separate kernel's module and for the compile-time measures (see
# their docstrings)
JIT_EXTRA = {"os", "hashlib", "gc", "threading", "concurrent", "importlib"}
JIT_FILES = {"jit.py", "numba_speedups.py"}
FORBIDDEN_CORE = {"rclpy", "rerun", "coal", "mujoco", "fcl", "pybullet", "mkcollision_msgs",
                  "geometry_msgs", "visualization_msgs", "msg_adapters", "std_msgs"}
ROS_MODULES = {"node.py", "node_parameters.py", "demo.py"}
RERUN_MODULES = {"rerun_log.py", "rerun_recorder.py", "render.py"}


def imports(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name.split(".")[0], node.lineno
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            yield node.module.split(".")[0], node.lineno


def test_kernels_import_only_numpy_numba_math():
    paths = sorted((ROOT / "mkcollision_ros" / "kernels").rglob("*.py"))
    assert any(path.parent.name == "pairs" for path in paths)
    for path in paths:
        allowed = KERNEL_OK | (JIT_EXTRA if path.name in JIT_FILES else set())
        for module, line in imports(path):
            assert module in allowed, f"{path.name}:{line} imports {module}"


def test_core_library_is_free_of_ros_and_peers():
    for path in sorted((ROOT / "mkcollision_ros").glob("*.py")):
        if path.name in ROS_MODULES:
            continue
        allowed = {"rerun"} if path.name in RERUN_MODULES else set()
        for module, line in imports(path):
            assert module not in FORBIDDEN_CORE - allowed, \
                f"{path.name}:{line} imports {module}"


def test_rerun_is_imported_only_inside_functions():
    for name in sorted(RERUN_MODULES):
        tree = ast.parse((ROOT / "mkcollision_ros" / name).read_text())
        for node in tree.body:
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                         else [node.module or ""])
                assert not any(n.split(".")[0] == "rerun" for n in names), \
                    f"{name}:{node.lineno} imports rerun at module level"


def test_import_without_ros_on_the_path():
    code = ("import sys; sys.modules['rclpy'] = None; sys.modules['rerun'] = None\n"
            "import mkcollision_ros, mkcollision_ros.pipeline\n"
            "r = mkcollision_ros.collide({'type': 'sphere', 'radius': 1.0}, ([0, 0, 0], [0, 0, 0, 1]),"
            " {'type': 'sphere', 'radius': 1.0}, ([1.5, 0, 0], [0, 0, 0, 1]))\n"
            "assert abs(r.depth - 0.5) < 1e-12, r\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, timeout=600)
    assert out.returncode == 0, out.stderr
