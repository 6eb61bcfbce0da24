"""Scene benchmark: our Pipeline.step vs MuJoCo's collision pass, python-fcl's and coal's
dynamic AABB tree managers, and pybullet, on the same seeded moving scenes.

Scenes (``common.scene``): N bodies cycling through sphere, ellipsoid, box, capsule,
cylinder, cone, convex (8 shared random hulls of 20-30 points), sizes ~0.5 m bounding
radius, uniformly spread in a cube whose edge is calibrated so that the expected number
of touching pairs per body (the *density*) is ``--densities`` (default 0.2 and 2).
Every step moves each body by up to 1 cm and turns it by ~0.01 rad; all engines see the
same pose sequence.  One untimed warm-up step, then ``--steps`` timed steps; medians.

  ours     ``Pipeline(bodies, PipelineConfig()).step(pos, quat, t)``, method auto,
           numba's default thread count; total wall time and ``StepResult.timings``.
           "collision" = bounds + broadphase + filter + narrowphase (the part comparable
           to the peers, which produce no persistent contacts).
  mujoco   free bodies (freejoint) with contype=conaffinity=1 (every pair allowed);
           per step: write ``qpos``, ``mj_kinematics`` (column "kin"), then the timed
           ``mj_collision`` (its broad phase, mid phase and narrow phase).  No cone in
           MuJoCo: a 32-sided inscribed hull mesh.
  fcl      python-fcl ``DynamicAABBTreeCollisionManager``: per step a Python loop of
           ``setTransform`` (column "upload"), then ``update()`` and
           ``collide(CollisionData(enable_contact, num_max_contacts=10**7),
           defaultCollisionCallback)``.
  coal     ``coal.DynamicAABBTreeCollisionManager``: upload as for fcl, ``update()``, then
           ``collide(CollisionCallBackDefault)`` with num_max_contacts=10**7 (broad and
           narrow phase in C++; pairs read back from the contacts).
  pybullet DIRECT mode, one multibody (mass 1, no gravity) per body; upload =
           ``resetBasePositionAndOrientation`` loop; timed ``performCollisionDetection``;
           pairs from ``getContactPoints()`` with distance <= 0.  Ellipsoid and cone are
           inscribed hull meshes (pybullet has neither).

"diff" is the symmetric difference between the engine's touching pairs and ours on the
last step (ours: ``StepResult.pairs``).

Scene operations (``--scene-ops``, ours only, density 0.2): the step with proximity off
and at 0.1 m (proximity pairs per step), and the cost of one edit at each size: add a
body, remove one, replace a body's shape, set the allowed pairs, change a setting
(medians of ``--steps`` edits), and the first step after an add and a remove against a
step without edits.

    PYTHONPATH=. .venv/bin/python bench/pipeline.py [--quick] [--sizes 100 1000 10000]
    PYTHONPATH=. .venv/bin/python bench/pipeline.py --scene-ops --sizes 1000 10000 --engines
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.common import (coal_geometry, coal_transform, fcl_geometry, print_table,  # noqa: E402
                          fcl_transform, move, mujoco_assets_xml, mujoco_geom,
                          pybullet_shape, scene, wxyz)
from mkcollision_ros.pipeline import Pipeline, PipelineConfig  # noqa: E402

COLLISION_PHASES = ("bounds", "broadphase", "filter", "narrowphase")


def _pairs_set(a):
    return {(int(min(i, j)), int(max(i, j))) for i, j in a}


# --- engines: each returns (per-step timing dicts, last step's touching pair set) --------
def run_ours(bodies, poses):
    p = Pipeline(bodies, PipelineConfig())
    p.warm_up()
    times, res = [], None
    for k, (pos, quat) in enumerate(poses):
        t0 = time.perf_counter()
        res = p.step(pos, quat, float(k))
        total = time.perf_counter() - t0
        d = dict(res.timings)
        d["total"] = total
        d["collision"] = sum(res.timings[ph] for ph in COLLISION_PHASES)
        times.append(d)
    return times[1:], _pairs_set(res.pairs), res


def run_mujoco(bodies, poses):
    import mujoco
    assets, xs = {}, []
    for i, b in enumerate(bodies):
        xs.append(f'<body name="b{i}"><freejoint/>{mujoco_geom(b["shape"], f"g{i}", assets)}'
                  f'</body>')
    mem = 64 + len(bodies) * 40 // 1000
    xml = (f'<mujoco><size memory="{mem}M"/><option gravity="0 0 0"/>'
           f'<asset>{mujoco_assets_xml(assets)}</asset>'
           f'<worldbody>{"".join(xs)}</worldbody></mujoco>')
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    times = []
    for pos, quat in poses:
        t0 = time.perf_counter()
        qpos = data.qpos.reshape(-1, 7)
        qpos[:, :3] = pos
        qpos[:, 3:] = wxyz(quat)
        mujoco.mj_kinematics(model, data)
        t1 = time.perf_counter()
        mujoco.mj_collision(model, data)
        t2 = time.perf_counter()
        times.append({"upload": t1 - t0, "collide": t2 - t1, "total": t2 - t0})
    g = data.contact.geom[:data.ncon]
    return times[1:], _pairs_set(g), data.ncon


def run_fcl(bodies, poses):
    import fcl
    geoms = [fcl_geometry(b["shape"]) for b in bodies]
    pos0, quat0 = poses[0]
    objs = [fcl.CollisionObject(g, fcl_transform(pos0[i], quat0[i]))
            for i, g in enumerate(geoms)]
    index = {id(g): i for i, g in enumerate(geoms)}
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(objs)
    manager.setup()
    times, found = [], set()
    for pos, quat in poses:
        t0 = time.perf_counter()
        for i, o in enumerate(objs):
            o.setTransform(fcl_transform(pos[i], quat[i]))
        t1 = time.perf_counter()
        manager.update()
        cdata = fcl.CollisionData(request=fcl.CollisionRequest(num_max_contacts=10 ** 7,
                                                               enable_contact=True))
        manager.collide(cdata, fcl.defaultCollisionCallback)
        t2 = time.perf_counter()
        times.append({"upload": t1 - t0, "collide": t2 - t1, "total": t2 - t0})
        found = {(index[id(c.o1)], index[id(c.o2)]) for c in cdata.result.contacts}
    return times[1:], _pairs_set(found)


def run_coal(bodies, poses):
    import coal
    geoms = [coal_geometry(b["shape"]) for b in bodies]
    pos0, quat0 = poses[0]
    objs = [coal.CollisionObject(g, coal_transform(pos0[i], quat0[i]))
            for i, g in enumerate(geoms)]
    manager = coal.DynamicAABBTreeCollisionManager()
    for o in objs:
        manager.registerObject(o)
    manager.setup()
    for i, g in enumerate(geoms):
        # tag each geometry with its body index (cost_density only matters for octrees)
        # so the contacts of coal's C++ default callback can be mapped back to bodies
        g.cost_density = float(i)
    times, found = [], set()
    for pos, quat in poses:
        t0 = time.perf_counter()
        for i, o in enumerate(objs):
            o.setTransform(coal_transform(pos[i], quat[i]))
        t1 = time.perf_counter()
        manager.update()
        cb = coal.CollisionCallBackDefault()
        cb.data.request.num_max_contacts = 10 ** 7
        manager.collide(cb)
        t2 = time.perf_counter()
        times.append({"upload": t1 - t0, "collide": t2 - t1, "total": t2 - t0})
        found = {(int(c.o1.cost_density), int(c.o2.cost_density))
                 for c in cb.data.result.getContacts()}
    return times[1:], _pairs_set(found)


def run_pybullet(bodies, poses):
    import pybullet as pb
    cid = pb.connect(pb.DIRECT)
    try:
        pb.setGravity(0, 0, 0, physicsClientId=cid)
        pos0, quat0 = poses[0]
        ids = []
        for i, b in enumerate(bodies):
            s = pybullet_shape(pb, cid, b["shape"])
            ids.append(pb.createMultiBody(1.0, s, -1, pos0[i].tolist(), quat0[i].tolist(),
                                          physicsClientId=cid))
        index = {u: i for i, u in enumerate(ids)}
        times, found = [], set()
        for pos, quat in poses:
            t0 = time.perf_counter()
            for i, u in enumerate(ids):
                pb.resetBasePositionAndOrientation(u, pos[i].tolist(), quat[i].tolist(),
                                                   physicsClientId=cid)
            t1 = time.perf_counter()
            pb.performCollisionDetection(physicsClientId=cid)
            t2 = time.perf_counter()
            cps = pb.getContactPoints(physicsClientId=cid)
            t3 = time.perf_counter()
            times.append({"upload": t1 - t0, "collide": t2 - t1, "query": t3 - t2,
                          "total": t3 - t0})
            found = {(index[c[1]], index[c[2]]) for c in cps if c[8] <= 0.0}
        return times[1:], _pairs_set(found)
    finally:
        pb.disconnect(cid)


ENGINES = {"mujoco": run_mujoco, "fcl": run_fcl, "coal": run_coal, "pybullet": run_pybullet}


def _med(times, key):
    return float(np.median([t[key] for t in times]))


def _ms(x):
    return f"{x * 1e3:.2f}"


def bench(sizes, densities, steps, seed, engines, skip_slow_above):
    results = []   # (n, density, engine, total s, collision s, pairs, diff)
    phase_rows, peer_rows = [], []
    for density in densities:
        for n in sizes:
            bodies, pos, quat, side = scene(n, density, seed=seed)
            rng = np.random.default_rng(seed + 1)
            poses = []
            for _ in range(steps + 1):
                pos, quat = move(rng, pos, quat)
                poses.append((pos.copy(), quat.copy()))
            times, ours, res = run_ours(bodies, poses)
            tot, col = _med(times, "total"), _med(times, "collision")
            results.append((n, density, "ours", tot, col, len(ours), 0))
            phase_rows.append([str(n), f"{density:g}", f"{side:.1f}", str(len(ours)),
                               f"{len(ours) / n:.2f}", str(res.n_candidate_pairs),
                               str(res.n_narrowphase_pairs), _ms(tot), _ms(col)]
                              + [_ms(_med(times, ph)) for ph in
                                 ("bounds", "broadphase", "filter", "narrowphase",
                                  "manifold", "arbiters")])
            for name in engines:
                if n > skip_slow_above and name in ("coal", "fcl"):
                    continue
                out = ENGINES[name](bodies, poses)
                t, found = out[0], out[1]
                diff = len(found ^ ours)
                only_them, only_us = len(found - ours), len(ours - found)
                total = _med(t, "total")
                coll = _med(t, "collide")
                results.append((n, density, name, total, coll, len(found), diff))
                peer_rows.append([str(n), f"{density:g}", name, _ms(_med(t, "upload")),
                                  _ms(coll), _ms(total), str(len(found)),
                                  f"{diff} (+{only_them} / -{only_us})",
                                  f"{tot / total:.2f}", f"{col / coll:.2f}"])
            print(f"  done n={n} density={density}", file=sys.stderr, flush=True)

    print("### Our pipeline, median ms per step\n")
    head = ["bodies", "density", "cube edge m", "touching pairs", "pairs/body",
            "broad-phase pairs", "narrow-phase pairs", "total", "collision",
            "bounds", "broadphase", "filter", "narrowphase", "manifold", "arbiters"]
    print_table(head, phase_rows)
    print("\n### Peers, median ms per step (same poses)\n")
    head = ["bodies", "density", "engine", "pose upload", "collide", "total",
            "touching pairs", "diff vs ours (+theirs only / -ours only)",
            "our total / their total", "our collision / their collide"]
    print_table(head, peer_rows)
    print("\n### Growth with body count (log-log slope of ms/step over the sizes run)\n")
    head = ["density", "engine", "slope total", "slope collision / collide"]
    rows = []
    for density in densities:
        for name in ["ours"] + list(engines):
            pts = [(n, t, c) for (n, d, e, t, c, _, _) in results if d == density and e == name]
            if len(pts) < 2:
                continue
            ns = np.log([p[0] for p in pts])
            rows.append([f"{density:g}", name,
                         f"{np.polyfit(ns, np.log([p[1] for p in pts]), 1)[0]:.2f}",
                         f"{np.polyfit(ns, np.log([p[2] for p in pts]), 1)[0]:.2f}"])
    print_table(head, rows)
    if len(densities) > 1:
        print("\n### Growth with contact count (time at the highest density / lowest, "
              "same body count)\n")
        lo, hi = min(densities), max(densities)
        rows = []
        for n in sizes:
            for name in ["ours"] + list(engines):
                a = [r for r in results if r[0] == n and r[1] == lo and r[2] == name]
                b = [r for r in results if r[0] == n and r[1] == hi and r[2] == name]
                if a and b:
                    rows.append([str(n), name, f"{b[0][5] / max(a[0][5], 1):.1f}",
                                 f"{b[0][3] / a[0][3]:.2f}", f"{b[0][4] / a[0][4]:.2f}"])
        print_table(["bodies", "engine", "pairs ratio", "total ratio",
                "collision / collide ratio"], rows)


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def bench_scene_ops(sizes, steps, seed):
    """Proximity off / 0.1 m and one edit at a time, our pipeline only."""
    prox_rows, edit_rows = [], []
    for n in sizes:
        bodies, pos, quat, _ = scene(n, 0.2, seed=seed)
        rng = np.random.default_rng(seed + 1)
        poses = []
        for _ in range(steps + 1):
            pos, quat = move(rng, pos, quat)
            poses.append((pos.copy(), quat.copy()))
        for prox in (0.0, 0.1):
            p = Pipeline(bodies, PipelineConfig(proximity=prox))
            p.warm_up()
            times, n_prox = [], []
            for k, (ps, qs) in enumerate(poses):
                t0 = time.perf_counter()
                res = p.step(ps, qs, float(k))
                times.append({"total": time.perf_counter() - t0, **res.timings})
                n_prox.append(len(res.proximity))
            times = times[1:]
            prox_rows.append([str(n), f"{prox:g}", str(int(np.median(n_prox[1:]))),
                              _ms(_med(times, "total")), _ms(_med(times, "narrowphase")),
                              _ms(_med(times, "classify"))])
        p = Pipeline(bodies, PipelineConfig())
        sc = p.scene
        p.step(*poses[0], 0.0)
        extra = {"name": "extra", "shape": bodies[6]["shape"], "pose": (pos[6], quat[6])}
        ops = {"add a body": [], "remove a body": [], "replace a shape": [],
               "set allowed pairs": [], "change a setting": [],
               "step after add + remove": [], "step without edits": []}
        for k in range(steps):
            ops["add a body"].append(_timed(lambda: sc.add_body(extra)))
            ops["remove a body"].append(_timed(lambda: sc.remove_body("extra")))
            ops["step after add + remove"].append(_timed(lambda: p.step(stamp=k)))
            ops["step without edits"].append(_timed(lambda: p.step(stamp=k)))
            shape = bodies[(2 * k) % n]["shape"]
            ops["replace a shape"].append(_timed(lambda: sc.replace_body(
                {"name": "b1", "shape": shape})))
            ops["set allowed pairs"].append(_timed(lambda: sc.set_allowed_pairs(
                [["b0", "b2"], ["b3", f"b{n - 1}"]])))
            ops["change a setting"].append(_timed(lambda: p.configure(
                contact_margin=0.001 + 1e-4 * (k % 2))))
        edit_rows.append([str(n)] + [_ms(float(np.median(v))) for v in ops.values()])
    print("\n### Proximity pairs, our pipeline, median ms per step (density 0.2)\n")
    print_table(["bodies", "proximity m", "proximity pairs", "total", "narrowphase",
            "classify"], prox_rows)
    print("\n### One scene edit, median ms\n")
    print_table(["bodies"] + list(ops), edit_rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 10000])
    ap.add_argument("--densities", type=float, nargs="+", default=[0.2, 2.0],
                    help="expected touching pairs per body")
    ap.add_argument("--steps", type=int, default=5, help="timed steps (median)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--engines", nargs="*", default=list(ENGINES), choices=list(ENGINES))
    ap.add_argument("--skip-slow-above", type=int, default=10 ** 9,
                    help="skip the Python-callback engines (coal, fcl) above this size")
    ap.add_argument("--quick", action="store_true", help="sizes 100 and 300, 2 steps")
    ap.add_argument("--scene-ops", action="store_true",
                    help="proximity and scene-edit costs instead of the peer comparison")
    args = ap.parse_args()
    if args.quick:
        args.sizes, args.steps = [100, 300], 2
    if args.scene_ops:
        print(f"## Scene operations: sizes {args.sizes}, {args.steps} timed steps (median)")
        bench_scene_ops(args.sizes, args.steps, args.seed)
        return
    print(f"## Pipeline: sizes {args.sizes}, densities {args.densities}, "
          f"{args.steps} timed steps (median)\n")
    bench(args.sizes, args.densities, args.steps, args.seed, args.engines,
          args.skip_slow_above)


if __name__ == "__main__":
    main()
