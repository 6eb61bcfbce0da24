"""Narrow-phase benchmark: our batch kernel vs MuJoCo's C narrow phase vs coal from Python.

For every shape-type pair (canonical order, plane last) the same seeded cases
(``common.pair_cases``: about half colliding, a fifth within 1% of touching) are run by

  ours     ``kernels.narrowphase.collide_batch`` on ONE numba thread, methods gjk_epa,
           mpr and auto (closed form where one exists, else GJK/EPA), all with exact
           distances (cutoff inf), and "contacts" = auto with distance cutoff 0, as the
           pipeline runs it: a pair proved apart stops there with a distance lower
           bound (MuJoCo's collision pass likewise reports no distances); median over
           repeats of the whole batch, after a warm-up call, divided by the pair count.
           GJK/EPA and MPR do not take planes (ST_NOT_RUN): plane rows show auto only.
  mujoco   one MJCF model per shape pair: each shape on its own mocap body (poses baked
           in the model), every geom contype=conaffinity=0, and the cases as explicit
           <contact><pair> elements, so mj_collision runs exactly those pairs (its
           bounding-sphere pre-test included, its broad phase finds nothing).  Timed:
           ``mujoco.mj_collision(model, data)`` after one ``mj_kinematics``; divided by
           the pair count.  Convex = MJCF mesh (MuJoCo builds the hull); MuJoCo has no
           cone: n/a.  Run twice: with MuJoCo's defaults (ccd_tolerance 1e-6 m,
           ccd_iterations 35 in 4.0.0) and "tight" (1e-8 m and 255, our EPA_REL_TOL *
           scale and EPA_MAX_ITERS).  Its accuracy against ours is reported on the pairs
           both find penetrating deeper than 1e-3 * scale (mujoco_accuracy): the angle
           between the normals' lines and the depth difference.
  coal     a Python loop of ``coal.collide`` (CollisionRequest with enable_contact,
           num_max_contacts=1) over prebuilt geometries and Transform3s, and separately
           a loop of ``coal.distance`` (signed distance); per pair, loop overhead included.

Agreement = fraction of cases where the peer's "in contact" equals ours (auto).

Each peer's repeats run back to back, so on a machine that slows in spells a row's
ratio can swing by 2x from run to run; for the speed goal's ratio use bench/vs_mujoco.py,
which alternates the two peers round by round.

    PYTHONPATH=. .venv/bin/python bench/narrowphase.py [--n 2000] [--quick]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.common import (KINDS, _fmt, coal_geometry, coal_transform, mujoco_assets_xml,  # noqa: E402
                          mujoco_geom, pair_cases, timed, wxyz)
from mkcollision_ros.kernels.constants import (EPA_MAX_ITERS, M_AUTO, M_GJK_EPA, M_MPR,  # noqa: E402
                                               OUT_SIZE, ST_FAILED, ST_NOT_RUN,
                                               ST_PENETRATING, ST_TOUCHING)
from mkcollision_ros.kernels.narrowphase import collide_batch  # noqa: E402

METHODS = (("gjk_epa", M_GJK_EPA, np.inf), ("mpr", M_MPR, np.inf), ("auto", M_AUTO, np.inf),
           ("contacts", M_AUTO, 0.0))


def run_ours(table, pairs, pos, quat, method, repeat, cutoff=np.inf):
    out = np.zeros((len(pairs), OUT_SIZE))
    st = np.zeros(len(pairs), np.int64)
    args = (table.codes, table.params, table.vrange, table.verts, pairs, pos, quat, method,
            cutoff, out, st)
    collide_batch(*args)
    t = timed(lambda: collide_batch(*args), repeat) / len(pairs)
    return t, st.copy(), out.copy()


def build_mujoco(shapes, pos, quat, n):
    import mujoco
    assets = {}
    bodies, pairs = [], []
    for i, s in enumerate(shapes):
        g = mujoco_geom(s, f"g{i}", assets, 'contype="0" conaffinity="0"',
                        approx_cone=False)
        if g is None:
            return None
        bodies.append(f'<body mocap="true" pos="{_fmt(pos[i])}" '
                      f'quat="{_fmt(wxyz(quat[i]))}">{g}</body>')
    for k in range(n):
        pairs.append(f'<pair geom1="g{2 * k}" geom2="g{2 * k + 1}"/>')
    xml = (f'<mujoco><size memory="400M"/><asset>{mujoco_assets_xml(assets)}</asset>'
           f'<worldbody>{"".join(bodies)}</worldbody><contact>{"".join(pairs)}</contact>'
           f'</mujoco>')
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    return model, data


def run_mujoco(shapes, pos, quat, n, repeat, tight=False):
    """MuJoCo's collision pass on the cases: (time per pair, hit flags, normals, depths).
    ``tight``: its convex solver held to our accuracy (ccd_tolerance 1e-8 m, about our
    EPA_REL_TOL * scale here, and ccd_iterations = our EPA_MAX_ITERS) instead of its
    defaults (1e-6 m, 35 iterations)."""
    import mujoco
    built = build_mujoco(shapes, pos, quat, n)
    if built is None:
        return None, None, None, None
    model, data = built
    if tight:
        model.opt.ccd_tolerance = 1e-8
        model.opt.ccd_iterations = EPA_MAX_ITERS
    mujoco.mj_collision(model, data)
    t = timed(lambda: mujoco.mj_collision(model, data), repeat) / n
    hit = np.zeros(n, bool)
    g = data.contact.geom[:data.ncon]
    hit[g[:, 0] // 2] = True
    # per pair: the normal of its first contact (MuJoCo's frame row 0) and its deepest
    # contact's distance; NaN where MuJoCo reports none
    normal = np.full((n, 3), np.nan)
    dist = np.full(n, np.nan)
    for c in range(data.ncon - 1, -1, -1):
        k = data.contact.geom[c, 0] // 2
        normal[k] = data.contact.frame[c, :3]
        dist[k] = min(data.contact.dist[c], np.nan_to_num(dist[k], nan=np.inf))
    return t, hit, normal, dist


def mujoco_accuracy(out, hit, nrm_mj, dist_mj, table, pairs):
    """MuJoCo's contact normal and depth against ours (auto, exact distances, world
    frame) on the pairs both call penetrating deeper than 1e-3 of the scale (sum of
    the two bounding radii), where the normal is well defined: the largest and 99th
    percentile angle between the normals' lines (mrad) and the largest depth
    difference (units of 1e-6 * scale).
    Ours is the reference: its normal is within ~5e-4 rad of the exact one and its
    depth within 1e-8 * scale (gjk_epa.py, EPA_REL_TOL).  MuJoCo's defaults stop its
    convex solver at ccd_tolerance 1e-6 m (about 100x looser here) or 35 iterations;
    on the box, cylinder and mesh rows its answers do not change with those settings
    (those pairs take other paths), so there its errors are not a tolerance effect."""
    if nrm_mj is None:
        return "n/a"
    scale = table.params[pairs[:, 0], 7] + table.params[pairs[:, 1], 7]
    use = hit & np.isfinite(dist_mj) & (out[:, 0] < -1e-3 * scale)
    if not np.any(use):
        return "n/a"
    # sign-agnostic (a lower bound of MuJoCo's error): its collision functions differ
    # in which way a contact normal points when it swaps a pair's geoms
    cos = np.clip(np.abs(np.sum(nrm_mj[use] * out[use, 1:4], axis=1)), 0.0, 1.0)
    ang = np.arccos(cos) * 1e3
    dd = np.abs(dist_mj[use] - out[use, 0]) / scale[use] * 1e6
    return f"{ang.max():.2g} / {np.percentile(ang, 99):.2g}, {dd.max():.3g}"


def run_coal(shapes, pos, quat, n, repeat):
    import coal
    geoms = [coal_geometry(s) for s in shapes]
    tfs = [coal_transform(pos[i], quat[i]) for i in range(len(shapes))]
    req = coal.CollisionRequest()
    req.enable_contact = True
    req.num_max_contacts = 1
    res = coal.CollisionResult()
    dreq = coal.DistanceRequest()
    dres = coal.DistanceResult()
    hit = np.zeros(n, bool)
    dist = np.zeros(n)

    def loop_collide():
        for k in range(n):
            res.clear()
            coal.collide(geoms[2 * k], tfs[2 * k], geoms[2 * k + 1], tfs[2 * k + 1], req, res)
            hit[k] = res.isCollision()

    def loop_distance():
        for k in range(n):
            dres.clear()
            dist[k] = coal.distance(geoms[2 * k], tfs[2 * k], geoms[2 * k + 1],
                                    tfs[2 * k + 1], dreq, dres)

    tc = timed(loop_collide, repeat) / n
    try:
        td = timed(loop_distance, repeat) / n
    except Exception:  # noqa: BLE001 - a pair coal cannot measure the distance of
        td = float("nan")
    return tc, td, hit.copy()


def _us(t):
    return "n/a" if t is None or t != t else f"{t * 1e6:.2f}"


def _ratio(a, b):
    return "n/a" if a is None or b is None or a != a or b != b else f"{a / b:.2f}"


def _pct(x):
    return "n/a" if x is None else f"{100 * x:.1f}"


def bench(n, repeat, seed, only=None):
    numba.set_num_threads(1)
    rows = []
    problems = []
    for ia, a in enumerate(KINDS):
        for b in KINDS[ia:]:
            if (a == "plane" and b == "plane") or (only and f"{a}-{b}" not in only):
                continue
            shapes, table, pairs, pos, quat = pair_cases(a, b, n, seed=seed + 101 * ia
                                                         + KINDS.index(b))
            ours = {}
            for name, m, cutoff in METHODS:
                t, st, out = run_ours(table, pairs, pos, quat, m, repeat, cutoff)
                if np.all(st == ST_NOT_RUN):
                    ours[name] = (None, None, None)
                    continue
                ours[name] = (t, st, out)
                bad = np.flatnonzero((st == ST_FAILED) | ~np.isfinite(out[:, 0]))
                if len(bad):
                    problems.append((a, b, name, len(bad), int(bad[0])))
            st_auto = ours["auto"][1]
            hit = (st_auto == ST_TOUCHING) | (st_auto == ST_PENETRATING)
            st_c = ours["contacts"][1]
            if not np.array_equal((st_c == ST_TOUCHING) | (st_c == ST_PENETRATING), hit):
                problems.append((a, b, "contacts differ from auto", 0, 0))
            t_mj, hit_mj, nrm_mj, dist_mj = run_mujoco(shapes, pos, quat, n, repeat)
            acc = mujoco_accuracy(ours["auto"][2], hit, nrm_mj, dist_mj, table, pairs)
            t_mjt, _, nrm_mjt, dist_mjt = run_mujoco(shapes, pos, quat, n, repeat, tight=True)
            acc_t = mujoco_accuracy(ours["auto"][2], hit, nrm_mjt, dist_mjt, table, pairs)
            t_cc, t_cd, hit_cc = run_coal(shapes, pos, quat, n, max(1, repeat // 3))
            same = {}
            for name in ("gjk_epa", "mpr"):
                st = ours[name][1]
                same[name] = (None if st is None else
                              float(np.mean(((st == ST_TOUCHING) | (st == ST_PENETRATING))
                                            == hit)))
            t_auto = ours["auto"][0]
            t_con = ours["contacts"][0]
            rows.append([
                f"{a}-{b}", str(n), _pct(hit.mean()), _us(ours["gjk_epa"][0]),
                _us(ours["mpr"][0]), _us(t_auto), _us(t_con), _us(t_mj), _us(t_cc),
                _us(t_cd), _ratio(t_auto, t_mj), _ratio(t_con, t_mj),
                _ratio(min(x for x in (ours["gjk_epa"][0], ours["mpr"][0], t_auto)
                           if x is not None), t_mj),
                _ratio(t_auto, t_cc),
                _pct(None if hit_mj is None else float(np.mean(hit_mj == hit))),
                _pct(float(np.mean(hit_cc == hit))),
                f"{_pct(same['gjk_epa'])}/{_pct(same['mpr'])}",
                acc, _us(t_mjt), _ratio(t_con, t_mjt), acc_t,
            ])
            print(f"  done {a}-{b}", file=sys.stderr, flush=True)
    head = ["pair", "n", "hit % (auto)", "gjk_epa µs", "mpr µs", "auto µs", "contacts µs",
            "mujoco µs", "coal collide µs", "coal distance µs", "auto/mujoco",
            "contacts/mujoco", "best/mujoco",
            "auto/coal collide", "agree mujoco %", "agree coal %",
            "gjk/mpr agree auto %",
            "mujoco vs ours: normal line mrad max / p99, depth max (1e-6 scale)",
            "mujoco tight µs", "contacts/mujoco tight", "mujoco tight vs ours"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        print("| " + " | ".join(r) + " |")
    if problems:
        print("\nFailed / non-finite results (pair, method, count, first case index):")
        for p in problems:
            print(f"- {p}")
    return rows


STARTUP = r"""
import time
t0 = time.perf_counter()
import numpy as np
from mkcollision_ros.shapes import build_table
from mkcollision_ros.kernels.narrowphase import collide_batch
t1 = time.perf_counter()
tb = build_table([{"type": "sphere", "radius": 0.5}, {"type": "box", "size": [1, 1, 1]}])
out = np.zeros((1, 12)); st = np.zeros(1, np.int64)
collide_batch(tb.codes, tb.params, tb.vrange, tb.verts, np.array([[0, 1]]),
              np.array([[0, 0, 0], [0.9, 0, 0.]]), np.tile([0, 0, 0, 1.], (2, 1)), 0, 0.0, out, st)
t2 = time.perf_counter()
print(f"{t1 - t0:.3f} {t2 - t0:.3f}")
"""


def startup():
    """First-run compile time (empty NUMBA_CACHE_DIR) and cached start-up time."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache,
                   PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))
        for label in ("first run (empty cache, compiles)", "second run (cached)"):
            w0 = time.perf_counter()
            r = subprocess.run([sys.executable, "-c", STARTUP], env=env, cwd=root,
                               capture_output=True, text=True, check=True)
            wall = time.perf_counter() - w0
            imp, first = map(float, r.stdout.split())
            rows.append((label, imp, first, wall))
    print("| start-up | import s | import -> first collide_batch result s | process wall s |")
    print("|---|---|---|---|")
    for label, imp, first, wall in rows:
        print(f"| {label} | {imp:.2f} | {first:.2f} | {wall:.2f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=2000, help="cases per shape pair")
    ap.add_argument("--repeat", type=int, default=9, help="timed repeats (median)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help="n=100, 3 repeats")
    ap.add_argument("--no-startup", action="store_true", help="skip the compile timing")
    ap.add_argument("--pairs", nargs="*", metavar="A-B",
                    help="only these shape pairs, e.g. box-capsule (default: all)")
    args = ap.parse_args()
    if args.quick:
        args.n, args.repeat = 100, 3
    print(f"## Narrow phase: {args.n} cases per pair, median of {args.repeat}, "
          f"numba threads = 1\n")
    bench(args.n, args.repeat, args.seed, args.pairs)
    if not args.no_startup:
        print()
        startup()


if __name__ == "__main__":
    main()
