"""Sweep throughput on 1 and 2 workers (process pool and Dask LocalCluster), against serial in the same run.

Each case is one grasp-demo rollout (``bhgrasp.scenarios.grasp_rollout``, ~1.2 s simulated so that the grasp closes
and holds).  Prints cases per second and the speed-up over the serial run measured here (machines are noisy:
compare ratios).  Usage: ``python benchmarks/bench_sweep.py [--cases N] [--duration S]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

from bhgrasp import sweep
from bhgrasp.scenarios import grasp_rollout


def throughput(design, **options) -> float:
    """Cases per second of one sweep."""
    start = time.perf_counter()
    table = sweep.run_sweep(grasp_rollout, design, seed=0, **options)
    elapsed = time.perf_counter() - start
    failed = int((table["status"] != "ok").sum())
    if failed:
        raise SystemExit(f"{failed} benchmark cases failed: {table.loc[table.status != 'ok', 'error'].tolist()}")
    return len(design) / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cases", type=int, default=8)
    parser.add_argument("--duration", type=float, default=1.2, help="simulated time per case [s]")
    args = parser.parse_args()
    design = sweep.grid(mass=[0.2 + 0.8 * i / max(args.cases - 1, 1) for i in range(args.cases)])
    design = [{**case, "estimate": 0.5, "duration": args.duration} for case in design]
    print(f"{platform.machine()}, Python {platform.python_version()}, {os.cpu_count()} CPUs, {len(design)} cases")
    serial = throughput(design, executor="serial")
    rates = {"serial (this process)": serial}
    for workers in (1, 2):
        rates[f"process pool, {workers}"] = throughput(design, workers=workers)
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        print("dask.distributed not installed: Dask rows skipped (pip install distributed)")
    else:
        for workers in (1, 2):
            with LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=None) as cluster:
                with Client(cluster) as client:
                    rates[f"Dask LocalCluster, {workers}"] = throughput(design, executor=client.get_executor())
    print(f"{'executor, workers':<34}{'cases/s':>9}{'x serial':>10}")
    for name, rate in rates.items():
        print(f"{name:<34}{rate:9.3f}{rate / serial:10.2f}")
    for kind in ("process pool", "Dask LocalCluster"):
        if f"{kind}, 2" in rates:
            print(f"scaling 1 -> 2 workers, {kind}: {rates[f'{kind}, 2'] / rates[f'{kind}, 1']:.2f}x")


if __name__ == "__main__":
    main()
