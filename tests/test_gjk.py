"""GJK's phase of the convex-convex driver (kernels/gjk.py) on cases kept from the seeded
10,000-pair runs of test_gjk_epa.py: the near-touching normal from the final simplex's
plane, and a flat tetrahedron that must not count as holding the origin."""
import oracles as O
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import ST_SEPARATED
from oracles import gjk


# A near-touching ellipsoid-convex pair from the 10,000-pair run (seeded set of
# test_against_coal_near_touching, case 1271): the direction of the tiny closest-point
# difference, taken as GJK's normal, is off enough that the distance reported (8.56e-5)
# is not the separation along it (8.36e-5), 1.3e-6 of the size apart (102 of the 2,000
# cases in that set are so).  The normal comes from the final simplex's plane.
NEAR_TOUCHING_1271 = {"sa": {"type": "ellipsoid", "radii": [0.6492990655265459, 0.5598225563210336, 0.336497499472398]}, "pa": [-1.3961126530908212, 0.30504113127443594, 1.0179549160019699], "qa": [0.9686309404918957, -0.10828596060761372, -0.012094758920499792, -0.22334271571673664], "sb": {"type": "convex", "points": [[0.5124320065544132, 0.4973356154021319, 0.2799130665161494], [0.35477153811359646, 0.6984689962038344, -0.08579057070789468], [-0.1946098853123371, 0.5748125647782905, 0.38004456436885337], [0.47160661906715723, -0.004104415522771491, -0.4935838458853245], [0.3887405738731895, 0.0199253378383855, 0.5289555362729753], [-0.0931878755095858, 0.77150999545536, -0.06578237751362324], [0.39400126494221394, -0.526866421871786, -0.3397702413182035], [0.7827227536591813, -0.24464488521629643, 0.09697915170861075]]}, "pb": [-1.2756496686962688, 0.6959750340610821, 1.342669136096483], "qb": [-0.7201703104102456, 0.3495699894123977, -0.32098080835716875, -0.506089781730678]}


def test_near_touching_normal_certifies_the_distance_case_1271():
    c = NEAR_TOUCHING_1271
    pose_a, pose_b = (c["pa"], c["qa"]), (c["pb"], c["qb"])
    r = gjk(c["sa"], pose_a, c["sb"], pose_b)
    scale = O.bounding_radius(c["sa"]) + O.bounding_radius(c["sb"])
    h = O.cso_support(c["sa"], pose_a, c["sb"], pose_b, r.normal[None, :])[0]
    assert r.status == ST_SEPARATED
    assert abs(r.distance + h) <= 1e-9 * scale
    # separation along any unit u is a lower bound of the distance, and ours is attained
    # along our normal, so it is a proven lower bound; the slow oracle's search must not
    # find a larger separation.  (coal reports 8.30e-5 here: below that proven bound.)
    lb, _ = O.signed_distance_oracle(c["sa"], pose_a, c["sb"], pose_b)
    assert lb <= r.distance + 1e-9 * scale
    assert r.distance - lb <= 1e-6 * scale


# An apart ellipsoid-box pair from the 10,000-pair run (test_against_coal_random
# [ellipsoid-box], case 4093): GJK builds a flat tetrahedron (three nearly equal support
# points) whose rounding-noise face orientations pass the "origin inside" test with the
# origin 0.13 m off its plane.  A flat tetrahedron (6 |volume| <= GJK_FLAT_TOL * longest
# edge^3) never counts as holding the origin, and EPA refuses a start whose faces are not
# consistently oriented instead of expanding it.
FLAT_TETRA_4093 = {"sa": {"type": "ellipsoid", "radii": [0.6519562655995701, 0.5067746184640042, 0.976064801242093]}, "pa": [-0.8733636366997193, 0.8262603567589, -0.24141831864079252], "qa": [0.12045826424626764, 0.5117919536733838, 0.18934968639657723, -0.8292801088844922], "sb": {"type": "box", "size": [1.0424166763047211, 0.7979707585757998, 0.5837698505907359]}, "pb": [0.3373464625092759, 0.7812998460846542, 0.34190541402468067], "qb": [0.17340756053708387, -0.7142966709943437, -0.47665169692163883, 0.48219627080339206]}


def test_gjk_flat_tetrahedron_not_inside_case_4093():
    c = FLAT_TETRA_4093
    pose_a, pose_b = (c["pa"], c["qa"]), (c["pb"], c["qb"])
    scale = O.bounding_radius(c["sa"]) + O.bounding_radius(c["sb"])
    lb, _ = O.signed_distance_oracle(c["sa"], pose_a, c["sb"], pose_b)
    for method in ("gjk_epa", "auto"):
        r = collide(c["sa"], pose_a, c["sb"], pose_b, method=method)
        h = O.cso_support(c["sa"], pose_a, c["sb"], pose_b, r.normal[None, :])[0]
        assert r.status == ST_SEPARATED, method
        assert abs(r.distance + h) <= 1e-9 * scale, method
        assert abs(r.distance - lb) <= 1e-6 * scale, method
    # MPR's distance for an apart pair is a lower bound only (docs/narrowphase-notes.md)
    assert collide(c["sa"], pose_a, c["sb"], pose_b, method="mpr").status == ST_SEPARATED
