"""Body configuration from params files: the same keys as the Python API, clear errors."""
import os

import numpy as np
import pytest

from mkcollision_ros.config import bodies_from_flat, bodies_from_params, load_params_file

CONFIG = os.path.join(os.path.dirname(__file__), "..", "config", "collision_node.yaml")


def test_package_config_loads():
    bodies = bodies_from_params(load_params_file(CONFIG))
    kinds = {b["shape"]["type"] for b in bodies}
    assert {"sphere", "ellipsoid"} <= kinds
    assert [b["name"] for b in bodies][:2] == ["ball_0", "ball_1"]
    floor = next(b for b in bodies if b["name"] == "floor")
    assert floor["static"] is True


def test_flat_points_and_body_keys():
    bodies = bodies_from_flat({
        "names": ["hull"], "hull.type": "convex", "hull.group": 2, "hull.mask": 5,
        "hull.points": [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        "hull.position": [1.0, 2.0, 3.0], "hull.orientation": [0.0, 0.0, 0.0, 2.0]})
    b = bodies[0]
    assert b["shape"]["points"][3] == [0.0, 0.0, 1.0]
    assert (b["group"], b["mask"]) == (2, 5)
    np.testing.assert_allclose(b["pose"][1], [0, 0, 0, 1])   # normalised


@pytest.mark.parametrize("flat, message", [
    ({"names": []}, "non-empty"),
    ({"names": ["a", "a"], "a.type": "sphere", "a.radius": 1.0}, "duplicates"),
    ({"names": ["a"], "a.type": "sphere", "a.radius": 1.0, "b.type": "sphere"}, "not listed"),
    ({"names": ["a"], "a.type": "sphere", "a.raduis": 1.0}, "unknown key 'raduis'"),
    ({"names": ["a"], "a.radius": 1.0}, "missing 'type'"),
    ({"names": ["a"], "a.type": "blob"}, "unknown shape type"),
    ({"names": ["a"], "a.type": "sphere", "a.radius": float("nan")}, "finite"),
    ({"names": ["a"], "a.type": "ellipsoid", "a.radii": [1.0, 2.0]}, "3 numbers"),
    ({"names": ["a"], "a.type": "box", "a.size": [1.0, -2.0, 1.0]}, "> 0"),
    ({"names": ["a"], "a.type": "convex", "a.points": [0.0, 1.0]}, "multiple of 3"),
    ({"names": ["a"], "a.type": "sphere", "a.radius": 1.0, "a.static": "yes"}, "true or false"),
    ({"names": ["a"], "a.type": "sphere", "a.radius": 1.0, "a.mask": -1}, "bitmask"),
    ({"names": ["a"], "a.type": "sphere", "a.radius": 1.0,
      "a.orientation": [0.0, 0.0, 0.0, 0.0]}, "zero quaternion"),
])
def test_bad_bodies_name_the_body_and_the_problem(flat, message):
    with pytest.raises(ValueError, match=message):
        bodies_from_flat(flat)


def test_params_file_errors(tmp_path):
    p = tmp_path / "x.yaml"
    p.write_text("- just a list\n")
    with pytest.raises(ValueError, match="not a ROS params file"):
        load_params_file(str(p))
    p.write_text("other_node:\n  ros__parameters: {a: 1}\n")
    with pytest.raises(ValueError, match="no ros__parameters"):
        load_params_file(str(p))
    p.write_text("/**:\n  ros__parameters: {rate_hz: 5.0}\n"
                 "collision_node:\n  ros__parameters: {rate_hz: 7.0}\n")
    assert load_params_file(str(p))["rate_hz"] == 7.0


def test_readme_parameter_table_is_the_nodes():
    from mkcollision_ros.node_parameters import parameter_table
    readme = open(os.path.join(os.path.dirname(__file__), "..", "README.md"),
                  encoding="utf-8").read()
    assert parameter_table() in readme, "run: python tools/readme_parameters.py"
