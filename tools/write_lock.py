"""Print every installed distribution of this venv as name==version (pip constraints).
Only real distributions (.dist-info) count: the ROS wheels also carry .egg-info folders
under their own module names, which are not installable names on PyPI."""
import importlib.metadata as md

rows = {f"{d.metadata['Name']}=={d.version}" for d in md.distributions()
        if str(getattr(d, "_path", "")).endswith(".dist-info")}
print("# Every package the setup installs, resolved and pinned (used as pip constraints).")
print("# Regenerate: bash tools/setup.sh --relock")
for row in sorted(rows, key=str.lower):
    print(row)
