"""limn.batch on a LocalCluster of 2 workers: 20 assets, 3 of them broken; failures stay with
their asset, re-runs skip what is up to date, and a worker killed mid-run loses no result."""

import json
import os
import re
import subprocess
import sys
import threading
import time

import distributed  # a dependency scripts/setup installs: missing, these tests fail
import pytest

import limn
from limn import batch

STEPS = [{"repair": {}}, {"simplify": {"proxies": 12}}, {"subdivide": {"uniform": 3}}]


@pytest.fixture(scope="module")
def assets(tmp_path_factory):
    root = tmp_path_factory.mktemp("batch")
    (root / "in").mkdir()
    (root / "out").mkdir()
    lines = []
    names = ["torus", "cage", "cube", "terrain-small"]
    for i in range(17):
        src = root / "in" / f"a{i:02}.obj"
        limn.write_mesh(limn.shape(names[i % len(names)], seed=i + 1), src)
        lines.append({"input": f"in/{src.name}", "output": f"out/a{i:02}.obj", "steps": STEPS})
    (root / "in" / "bad_index.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    (root / "in" / "bad_text.obj").write_text("this is not a mesh\n")
    lines.append({"input": "in/bad_index.obj", "output": "out/bad_index.obj", "steps": STEPS})
    lines.append({"input": "in/bad_text.obj", "output": "out/bad_text.obj", "steps": STEPS})
    lines.append({"input": "in/missing.obj", "output": "out/missing.obj", "steps": STEPS})
    manifest = root / "assets.jsonl"
    manifest.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return root, manifest


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def results_of(path):
    return {r["name"]: r for r in map(json.loads, path.read_text().splitlines())}


def test_broken_assets_fail_alone_and_reruns_skip(assets, client):
    root, manifest = assets
    out = root / "results.jsonl"
    batch.run(manifest, out, client=client, progress=False)
    results = results_of(out)
    assert len(results) == 20
    failed = {n for n, r in results.items() if r["status"] == "failed"}
    assert failed == {"in/bad_index.obj", "in/bad_text.obj", "in/missing.obj"}
    assert "vertex index 9 out of range" in results["in/bad_index.obj"]["error"]
    assert "cannot open" in results["in/missing.obj"]["error"]
    for name, r in results.items():
        if name in failed:
            continue
        assert r["status"] == "done"
        assert [s["job"] for s in r["stats"]] == ["repair", "simplify", "subdivide"]
        mesh = limn.read_mesh(r["outputs"][-1])
        # The same pipeline in this process gives the same mesh.
        here = limn.subdivide(limn.simplify(limn.repair(limn.read_mesh(r["input"])).mesh,
                                            proxies=12).mesh, uniform=3).mesh
        assert (mesh.positions == here.positions).all()
    # Run again: everything that landed is up to date, the broken ones fail again.
    again = root / "again.jsonl"
    batch.run(manifest, again, client=client, progress=False)
    statuses = {n: r["status"] for n, r in results_of(again).items()}
    assert sum(s == "skipped" for s in statuses.values()) == 17
    assert {n for n, s in statuses.items() if s == "failed"} == failed
    # Touch an input (a second past its output, whatever the file system's clock resolution):
    # only that asset runs again.
    later = os.path.getmtime(root / "out" / "a03.obj") + 1
    os.utime(root / "in" / "a03.obj", (later, later))
    third = root / "third.jsonl"
    batch.run(manifest, third, client=client, progress=False)
    assert results_of(third)["in/a03.obj"]["status"] == "done"
    assert sum(r["status"] == "skipped" for r in results_of(third).values()) == 16


def test_a_killed_worker_loses_no_result(assets, client):
    root, manifest = assets
    # Heavier steps with small outputs, so the kill lands while assets are running.
    heavy = root / "heavy.jsonl"
    lines = []
    for line in map(json.loads, manifest.read_text().splitlines()):
        line["output"] = line["output"].replace("out/", "out/heavy-")
        line["steps"] = [{"subdivide": {"uniform": 3}}, {"simplify": {"proxies": 12}}]
        lines.append(line)
    heavy.write_text("".join(json.dumps(line) + "\n" for line in lines))
    out = root / "killed.jsonl"
    seen_at_kill = []

    def kill_one_worker():
        while not out.exists() or len(out.read_text().splitlines()) < 3:
            time.sleep(0.005)
        pids = client.run(os.getpid)
        victim = sorted(pids)[0]
        seen_at_kill.append(len(out.read_text().splitlines()))
        os.kill(pids[victim], 9)

    thread = threading.Thread(target=kill_one_worker, daemon=True)
    thread.start()
    batch.run(heavy, out, client=client, progress=False)
    thread.join(timeout=60)
    assert seen_at_kill and seen_at_kill[0] < 17, "the worker died after the run"
    results = results_of(out)
    assert len(results) == 20
    # An asset whose worker died after its output landed is "skipped" when run again.
    landed = [r for r in results.values() if r["status"] in ("done", "skipped")]
    assert len(landed) == 17
    for r in landed:
        assert limn.info(limn.read_mesh(r["outputs"][-1]))["manifold"]
    leftovers = [p.name for p in (root / "out").iterdir() if ".limn-" in p.name]
    assert not leftovers  # no temporary file of an interrupted write stays behind


def test_command_line(assets, tmp_path):
    root, manifest = assets
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"input": "x.obj", "steps": [{"smooth": {}}]}\n')
    done = subprocess.run([sys.executable, "-m", "limn.batch", str(bad), "--workers", "1",
                           "--quiet"], capture_output=True, text=True)
    assert done.returncode == 2
    assert "bad.jsonl:1: step 0: unknown job 'smooth'" in done.stderr
    results = tmp_path / "r.jsonl"
    done = subprocess.run([sys.executable, "-m", "limn.batch", str(manifest), "-o", str(results),
                           "--workers", "2", "--quiet"], capture_output=True, text=True)
    assert done.returncode == 1, done.stderr  # three assets failed
    summary = re.search(r"limn.batch: (\d+) done, (\d+) skipped, 3 failed", done.stderr)
    assert summary and int(summary[1]) + int(summary[2]) == 17, done.stderr
    assert len(results.read_text().splitlines()) == 20


def test_an_asset_unwrapped_painted_and_baked_to_a_glb(tmp_path):
    limn.write_mesh(limn.shape("torus"), tmp_path / "torus.obj")
    (tmp_path / "fill.json").write_text(json.dumps(
        {"strokes": [{"type": "fill", "color": [0.9, 0.3, 0.2, 1]}]}))
    line = {"input": "torus.obj", "steps": [
        {"unwrap": {"size": 128, "output": "torus-uv.obj"}},
        {"paint": {"strokes": "fill.json"}},
        {"bake": {"uv": True, "size": 128, "output": "torus.glb"}}]}
    (tmp_path / "assets.jsonl").write_text(json.dumps(line) + "\n")
    [asset] = batch.read_manifest(tmp_path / "assets.jsonl")
    result = batch.run_asset(asset)
    assert result["status"] == "done", result["error"]
    assert result["stats"][0]["job"] == "unwrap" and result["stats"][0]["charts"] > 1
    baked = limn.read_mesh(tmp_path / "torus.glb")
    assert baked.uvs.shape[0] > 0
    expected = limn.unwrap(limn.shape("torus"), size=128).mesh
    assert baked.face_count == 2 * expected.face_count  # quads fanned to triangles
