"""ament_python package: executables go to lib/mkcollision_ros (so `ros2 run` finds them),
config files to share/mkcollision_ros/config, the package marker to the ament index."""
from glob import glob

from setuptools import setup

PACKAGE = "mkcollision_ros"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE, f"{PACKAGE}.kernels", f"{PACKAGE}.kernels.pairs", "msg_adapters"],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml") + glob("config/*.xml")),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="mkcollision maintainers",
    maintainer_email="maintainers@mkcollision.dev",
    description="Collision checking node for ROS 2 with numba narrow-phase kernels.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            f"collision_node = {PACKAGE}.node:main",
            f"demo_publisher = {PACKAGE}.demo:publisher_main",
            f"demo = {PACKAGE}.demo:main",
            f"render_recording = {PACKAGE}.render:main",
        ],
    },
)
