"""What Python costs on top of the C++ jobs, and limn.batch's throughput on 1 and 2 workers.

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [--models ../shared/models]

Overhead: the wall time of a `limn.simplify` / `limn.subdivide` / `limn.info` call from Python
against the C++ job's own time inside that call (the phases its report times, measured in C++),
best of N each; the difference is argument conversion, the GIL, results handed to numpy and the
report turned into a dict. Goal (issue 29): < 5% on a 100k-face job. Batch: the same manifest
(repair -> simplify -> subdivide per asset) on a LocalCluster of 1 and of 2 worker processes.
"""

import argparse
import json
import os
import pathlib
import shutil
import tempfile
import time

import limn
from limn import batch


def best(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append((time.perf_counter() - t0) * 1000)
    return min(times), out


def inner_ms(stats, keys):
    return sum(stats["timings_ms"][k] or 0.0 for k in keys)


def overhead(models, repeat):
    print("Python call vs the C++ job inside it (best of %d)" % repeat)
    print(f"{'job':<22} {'mesh':<18} {'faces':>8} {'python ms':>10} {'C++ ms':>9} {'overhead':>9}")
    rows = []
    meshes = [("cube", limn.shape("cube")), ("spot", limn.read_mesh(models / "tri/spot.obj")),
              ("armadillo-100k", limn.read_mesh(models / "tri/armadillo-100k.obj"))]
    simplify_keys = ("prepare", "seeding", "optimisation", "meshing", "validate")
    for name, mesh in meshes:
        if mesh.face_count >= 12:
            wall, r = best(lambda: limn.simplify(mesh, proxies=min(100, mesh.face_count // 4)),
                           repeat)
            # The C++ side of the same call, timed the same way: its phases, best of the runs.
            inner = min(inner_ms(limn.simplify(mesh, proxies=min(100, mesh.face_count // 4))
                                 .stats, simplify_keys) for _ in range(repeat))
            rows.append(("simplify", name, mesh.face_count, wall, inner))
    for name, mesh in [("torus", limn.shape("torus")), ("torus-dense-small",
                                                         limn.shape("torus-dense-small"))]:
        level = 3
        wall, r = best(lambda: limn.subdivide(mesh, uniform=level), repeat)
        keys = ("topology", "stencils_and_apply", "output")
        inner = min(inner_ms(limn.subdivide(mesh, uniform=level).stats, keys)
                    for _ in range(repeat))
        rows.append((f"subdivide --uniform {level}", name, r.mesh.face_count, wall, inner))
    for job, name, faces, wall, inner in rows:
        print(f"{job:<22} {name:<18} {faces:>8} {wall:>10.2f} {inner:>9.2f} "
              f"{100 * (wall - inner) / inner:>8.1f}%")


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
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--assets", type=int, default=16)
    args = parser.parse_args()
    models = pathlib.Path(args.models)
    overhead(models, args.repeat)
    throughput(models, args.assets, 3)


if __name__ == "__main__":
    main()
