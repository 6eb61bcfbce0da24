"""What rerun logging adds to a step: ``RerunLog.log_step`` at 100, 1,000 and 10,000
bodies of mixed shapes (``common.scene``, density 0.2 touching pairs per body), file
sink, one process.

For each size: the same seeded moving poses go through a Pipeline at ``--rate`` steps a
second (100; 10,000 bodies at 30), and after each step ``RerunLog.log_step`` is timed:
wall and CPU of the calling thread (what a step waits for: the pickling and the
hand-over to the writer thread), mean and p99 over ``--steps`` steps after ``--warm``
untimed ones.  The recorder runs in the logger's child process; its CPU time per step
is reported beside, and ``close`` (the child finishing the file).  The recorder holds
the per-step data and sends it as columns every ``--batch-steps`` steps.  The
recording's size per step is reported too.

Memory (``--memory-seconds S``): one 1,000-body pipeline logging at 100 Hz for S
seconds to each sink in turn (file, then serve with its 256 MiB buffer and no viewer);
the resident memory of this process and the logger's child together is sampled every
10 s.

    PYTHONPATH=. .venv/bin/python bench/rerun_cost.py [--sizes 100 1000 10000]
    PYTHONPATH=. .venv/bin/python bench/rerun_cost.py --memory-seconds 600 [--sinks save serve]
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.common import move, scene  # noqa: E402
from mkcollision_ros.pipeline import Pipeline  # noqa: E402
from mkcollision_ros.rerun_log import RerunLog  # noqa: E402


def _rss_mb(pid="self"):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def _cpu_s(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def cost(n, steps, warm, seed, batch_steps, rate):
    bodies, pos, quat, _ = scene(n, 0.2, seed)
    p = Pipeline(bodies)
    rng = np.random.default_rng(seed)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "cost.rrd")
        log = RerunLog(f"save:{path}", batch_steps=batch_steps, batch_seconds=1e9)
        wall, cpu, step_ms, contacts = [], [], [], []
        period = 1.0 / rate
        nxt = time.perf_counter()
        for k in range(warm + steps):
            if k == warm:
                child0 = _cpu_s(log.process.pid)
            pos, quat = move(rng, pos, quat)
            t = time.perf_counter()
            res = p.step(pos, quat, 0.01 * k)
            t1, c1 = time.perf_counter(), time.thread_time()
            log.log_step(p.scene, res, k)
            t2, c2 = time.perf_counter(), time.thread_time()
            if k >= warm:
                step_ms.append(1e3 * (t1 - t))
                wall.append(1e3 * (t2 - t1))
                cpu.append(1e3 * (c2 - c1))
                contacts.append(len(res.depth))
            nxt += period
            time.sleep(max(0.0, nxt - time.perf_counter()))
        t1 = time.perf_counter()
        child = _cpu_s(log.process.pid) - child0
        log.close()
        close_s = time.perf_counter() - t1
        size = os.path.getsize(path) / (warm + steps) / 1024.0
    return dict(bodies=n, rate=rate, contacts=int(np.median(contacts)),
                step=np.median(step_ms), mean=np.mean(wall), p99=np.percentile(wall, 99),
                cpu=np.mean(cpu), child=1e3 * child / steps, close=close_s, kib=size)


def memory(seconds, seed, kinds=("save", "serve")):
    bodies, pos, quat, _ = scene(1000, 0.2, seed)
    rng = np.random.default_rng(seed)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        specs = {"save": f"save:{os.path.join(tmp, 'long.rrd')}",
                 "serve": "serve:127.0.0.1:19877"}
        for sink in (specs[k] for k in kinds):
            p = Pipeline(bodies, rerun=RerunLog(sink, web_port=0, memory_limit="256MiB"))
            start = time.monotonic()
            samples, k, nxt = [], 0, 0.0
            while True:
                now = time.monotonic() - start
                if now >= nxt:
                    samples.append((round(now), _rss_mb() + _rss_mb(p.rerun.process.pid)))
                    nxt += 10.0
                if now >= seconds:
                    break
                pos, quat = move(rng, pos, quat)
                p.step(pos, quat, 0.01 * k)
                k += 1
                time.sleep(max(0.0, start + 0.01 * k - time.monotonic()))
            p.close()
            rows.append((sink.split(":")[0], k, samples))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 10000])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--warm", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--batch-steps", type=int, default=10)
    ap.add_argument("--rate", type=float, default=100.0,
                    help="steps a second (10,000 bodies: at most 30)")
    ap.add_argument("--memory-seconds", type=float, default=0.0)
    ap.add_argument("--sinks", nargs="+", default=["save", "serve"],
                    choices=["save", "serve"], help="sinks of the memory run")
    a = ap.parse_args()
    if a.memory_seconds > 0:
        print("| sink | steps | resident MB at t = 0, 10, 20 ... s |\n|---|---|---|")
        for sink, k, samples in memory(a.memory_seconds, a.seed, a.sinks):
            first = samples[0][1]
            peak = max(m for _, m in samples)
            print(f"| {sink} | {k} | {', '.join(f'{m:.0f}' for _, m in samples)} "
                  f"(first {first:.0f}, peak {peak:.0f}, last {samples[-1][1]:.0f}) |",
                  flush=True)
        return
    print("| bodies | rate Hz | contacts | step ms | log_step ms (mean, p99) | its CPU ms "
          "| logger process CPU ms a step | close s | KiB a step |\n"
          "|---|---|---|---|---|---|---|---|---|")
    for n in a.sizes:
        rate = a.rate if n < 10000 else min(a.rate, 30.0)
        r = cost(n, a.steps if n < 10000 else max(20, a.steps // 5), a.warm, a.seed,
                 a.batch_steps, rate)
        print(f"| {r['bodies']} | {r['rate']:g} | {r['contacts']} | {r['step']:.3f} | "
              f"{r['mean']:.3f}, {r['p99']:.3f} | {r['cpu']:.3f} | {r['child']:.2f} | "
              f"{r['close']:.2f} | {r['kib']:.1f} |", flush=True)

if __name__ == "__main__":
    main()
