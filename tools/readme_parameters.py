"""Rewrite the node's parameter table in README.md from mkcollision_ros.node_parameters.PARAMETERS.

    . tools/env.sh && python tools/readme_parameters.py
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from mkcollision_ros.node_parameters import parameter_table  # noqa: E402

README = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "README.md")
HEAD = "| parameter | type | default |"

text = open(README, encoding="utf-8").read()
start = text.index(HEAD)
end = text.index("\n\n", start) + 1
with open(README, "w", encoding="utf-8") as f:
    f.write(text[:start] + parameter_table() + text[end:])
