"""What Python costs on top of the C++ jobs, and limn.batch's throughput on 1 and 2 workers.

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [--models ../shared/models]

Overhead: the wall time of a `limn.simplify` call from Python against the C++ job's own time
inside that same call (the phases its report times, measured in C++, which run one after the
other); the difference is argument conversion, the GIL, results handed to numpy and the report
turned into a dict. Goal (issue 29): < 5% on a 100k-face job. Batch: the same manifest
(repair -> simplify -> subdivide per asset) on a LocalCluster of 1 and of 2 worker processes.
"""

import argparse
import json
import os
import pathlib
import shutil
import statistics
import tempfile
import time

import limn
from limn import batch


def overhead(models, repeat):
    """Per call: the wall time from Python, and the C++ job's time inside that same call (its
    phases, which run one after the other); medians over `repeat` calls."""
    print(f"Python call vs the C++ job inside it (medians of {repeat} calls)")
    print(f"{'job':<10} {'mesh':<16} {'faces':>7} {'python ms':>10} {'C++ ms':>9} "
          f"{'overhead ms':>12} {'overhead':>9}")
    keys = ("prepare", "seeding", "optimisation", "meshing", "validate")
    for name, path in [("spot", "tri/spot.obj"), ("fandisk", "tri/fandisk.obj"),
                       ("armadillo-100k", "tri/armadillo-100k.obj")]:
        mesh = limn.read_mesh(models / path)
        walls, inners = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            r = limn.simplify(mesh, proxies=100)
            walls.append((time.perf_counter() - t0) * 1000)
            inners.append(sum(r.stats["timings_ms"][k] or 0.0 for k in keys))
        extra = statistics.median(w - i for w, i in zip(walls, inners))
        inner = statistics.median(inners)
        print(f"{'simplify':<10} {name:<16} {mesh.face_count:>7} {statistics.median(walls):>10.2f} "
              f"{inner:>9.2f} {extra:>12.3f} {100 * extra / inner:>8.2f}%")


def throughput(models, assets, repeat):
    from distributed import Client, LocalCluster

    root = pathlib.Path(tempfile.mkdtemp(prefix="limn-batch-bench-"))
    try:
        (root / "in").mkdir()
        src = root / "in" / "bunny.obj"
        shutil.copy(models / "tri/stanford-bunny.obj", src)
        lines = [{"input": "in/bunny.obj", "name": f"bunny-{i}", "output": f"out/{i}.obj",
                  "steps": [{"repair": {}}, {"simplify": {"proxies": 200}},
                            {"subdivide": {"uniform": 2}}]} for i in range(assets)]
        (root / "out").mkdir()
        manifest = root / "assets.jsonl"
        manifest.write_text("".join(json.dumps(line) + "\n" for line in lines))
        print(f"\nlimn.batch: {assets} assets (stanford-bunny: repair, simplify K=200, subdivide "
              f"--uniform 2), best of {repeat}")
        base = None
        for workers in (1, 2):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=":0")
            client = Client(cluster)
            client.run(lambda: __import__("limn"))  # imports done before the clock starts
            times = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                done = batch.run(manifest, root / "results.jsonl", client=client, force=True,
                                 progress=False)
                times.append(time.perf_counter() - t0)
                assert all(r["status"] == "done" for r in done), done
            client.close()
            cluster.close()
            rate = assets / min(times)
            base = base or rate
            print(f"{workers} worker(s): {min(times):.2f} s, {rate:.2f} assets/s "
                  f"({rate / base:.2f}x)")
    finally:
        shutil.rmtree(root)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--models", default=str(pathlib.Path(__file__).resolve().parents[2] /
                                                "shared" / "models"))
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--assets", type=int, default=16)
    args = parser.parse_args()
    models = pathlib.Path(args.models)
    overhead(models, args.repeat)
    throughput(models, args.assets, 3)


if __name__ == "__main__":
    main()
