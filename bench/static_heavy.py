"""Static-heavy scenes (a warehouse: racks and stock that never move, a few robots that
do): our Pipeline.step per phase, at up to 100,000 bodies, with MuJoCo's collision pass
on the same poses where its model builds in reasonable time.

    PYTHONPATH=. .venv/bin/python bench/static_heavy.py [--sizes 10000 100000]
        [--moving 0.01 0.1] [--density 0.2] [--steps 10] [--mujoco-max 20000]

Scene: ``common.scene(N, density)`` (mixed shapes, the pipeline benchmark's), every body
static but a ``--moving`` share of them, spread evenly over the slots.  The moving
bodies move each step as in bench/pipeline.py (up to 1 cm, ~0.01 rad); the static ones
keep their poses.  Static-static pairs are never tested (scene.py), so the narrow phase
only sees pairs with a moving body.  "touching" counts the touching pairs the step
reports, all of them with a moving body.  One untimed step, then ``--steps`` timed steps;
medians, ms.

MuJoCo: the static bodies as geoms of its world body (it never tests two of those, as
we do not), the moving ones free bodies; ``mj_kinematics`` then the timed
``mj_collision``.  Its model build grows fast with the geom count, so it is run up to
``--mujoco-max`` bodies.
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.common import (move, mujoco_assets_xml, mujoco_geom, print_table, scene,  # noqa: E402
                          wxyz)
from mkcollision_ros.pipeline import Pipeline, PipelineConfig  # noqa: E402

PHASES = ("edits", "bounds", "broadphase", "filter", "narrowphase", "classify", "manifold",
          "arbiters")


def moving_slots(n, share):
    """``share`` of the n slots, spread evenly (at least one)."""
    k = max(1, int(round(n * share)))
    return np.unique(np.linspace(0, n - 1, k).astype(np.int64))


def poses(pos, quat, moving, steps, seed):
    """steps + 1 pose sets: the moving rows move, the others stay."""
    rng = np.random.default_rng(seed + 1)
    out = []
    for _ in range(steps + 1):
        p, q = move(rng, pos[moving], quat[moving])
        pos, quat = pos.copy(), quat.copy()
        pos[moving], quat[moving] = p, q
        out.append((pos, quat))
    return out


def run_ours(bodies, moving, sequence):
    static = np.ones(len(bodies), bool)
    static[moving] = False
    scene_bodies = [dict(b, static=bool(s)) for b, s in zip(bodies, static)]
    t0 = time.perf_counter()
    p = Pipeline(scene_bodies, PipelineConfig())
    build = time.perf_counter() - t0
    p.warm_up()
    rows, res = [], None
    for k, (pos, quat) in enumerate(sequence):
        t0 = time.perf_counter()
        res = p.step(pos, quat, float(k))
        row = dict(res.timings)
        row["total"] = time.perf_counter() - t0
        rows.append(row)
    return rows[1:], res, build


def run_mujoco(bodies, moving, sequence):
    import mujoco
    pos, quat = sequence[0]
    is_moving = np.zeros(len(bodies), bool)
    is_moving[moving] = True
    assets, world, free = {}, [], []
    for i, b in enumerate(bodies):
        if is_moving[i]:
            free.append(f'<body name="b{i}"><freejoint/>'
                        f'{mujoco_geom(b["shape"], f"g{i}", assets)}</body>')
        else:
            q = wxyz(quat[i:i + 1])[0]
            attrs = (f'pos="{" ".join(f"{x:.17g}" for x in pos[i])}" '
                     f'quat="{" ".join(f"{x:.17g}" for x in q)}"')
            world.append(mujoco_geom(b["shape"], f"g{i}", assets, attrs))
    mem = 64 + len(bodies) * 40 // 1000
    xml = (f'<mujoco><size memory="{mem}M"/><option gravity="0 0 0"/>'
           f'<asset>{mujoco_assets_xml(assets)}</asset>'
           f'<worldbody>{"".join(world)}{"".join(free)}</worldbody></mujoco>')
    t0 = time.perf_counter()
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    build = time.perf_counter() - t0
    times = []
    for pos, quat in sequence:
        qpos = data.qpos.reshape(-1, 7)
        qpos[:, :3] = pos[moving]
        qpos[:, 3:] = wxyz(quat[moving])
        mujoco.mj_kinematics(model, data)
        t1 = time.perf_counter()
        mujoco.mj_collision(model, data)
        times.append(time.perf_counter() - t1)
    touching = {tuple(sorted(g)) for g in data.contact.geom[:data.ncon].tolist()}
    return times[1:], len(touching), build


def _ms(s):
    return f"{1e3 * s:.2f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--moving", type=float, nargs="+", default=[0.01, 0.1],
                    help="shares of the bodies that move")
    ap.add_argument("--density", type=float, default=0.2,
                    help="expected touching pairs per body (common.scene)")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--mujoco-max", type=int, default=20000,
                    help="largest body count MuJoCo runs at (0: never)")
    args = ap.parse_args()
    head = (["bodies", "moving", "build s", "touching", "broad-phase pairs",
             "narrow-phase pairs", "total"] + list(PHASES) + ["mujoco collide",
                                                              "mujoco touching",
                                                              "ours / mujoco"])
    lines = []
    for n in args.sizes:
        bodies, pos, quat, _ = scene(n, args.density, seed=args.seed)
        for share in args.moving:
            moving = moving_slots(n, share)
            sequence = poses(pos, quat, moving, args.steps, args.seed)
            rows, res, build = run_ours(bodies, moving, sequence)
            med = {k: float(np.median([r[k] for r in rows])) for k in rows[0]}
            cells = [str(n), str(len(moving)), f"{build:.1f}", str(len(res.pairs)),
                     str(res.n_candidate_pairs), str(res.n_narrowphase_pairs),
                     _ms(med["total"])] + [_ms(med[ph]) for ph in PHASES]
            if n <= args.mujoco_max:
                times, touching, _ = run_mujoco(bodies, moving, sequence)
                theirs = float(np.median(times))
                cells += [_ms(theirs), str(touching), f"{med['total'] / theirs:.2f}"]
            else:
                cells += ["not run", "", ""]
            lines.append(cells)
            print(f"  done n={n} moving={len(moving)}", file=sys.stderr, flush=True)
    print(f"## Static-heavy scenes: density {args.density:g}, {args.steps} timed steps "
          "(median ms per step)\n")
    print_table(head, lines)


if __name__ == "__main__":
    main()
