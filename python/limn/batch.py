"""Run limn's jobs over many assets on dask.distributed: ``python3 -m limn.batch MANIFEST.jsonl``.

The manifest holds one asset per line (JSON)::

    {"input": "scans/rock.obj", "output": "cages/rock.obj",
     "steps": [{"repair": {}}, {"simplify": {"proxies": 200}}, {"subdivide": {"uniform": 2}}]}

Steps run in order on the asset's mesh, each with the keyword arguments of the function of the
same name (:func:`limn.repair`, :func:`limn.simplify`, :func:`limn.subdivide`, :func:`limn.paint`
with ``strokes`` a script file, and ``bake``: with ``uv`` true and a ``.glb`` output every
material channel goes into the GLB's material, ``normal_map`` adding a normal map of the height).
A step may save its own result with ``"output"`` (a mesh, the ``.lot`` of a paint step, the
``.png``, ``.glb`` or vertex-coloured mesh of a bake step); the asset's final mesh goes to the
line's ``"output"``. Relative paths are relative to the manifest.

Each asset is one task: a failing asset reports its error and the others go on. Results go to a
JSON-lines file (one line per asset as it finishes: name, status ``done``/``skipped``/``failed``,
outputs, the jobs' reports, the error) and are flushed at once, so an interrupted run keeps every
finished result. Every output is written atomically (a temporary file renamed into place); an
asset whose outputs all exist and are newer than its inputs is skipped, so re-running a manifest
only does what is missing. By default a LocalCluster on this machine runs the tasks (one worker
process per core); ``--scheduler tcp://HOST:PORT`` sends them to any dask scheduler (a studio's
cluster), whose workers must be able to ``import limn`` and to read and write the paths.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time
import uuid
from typing import Any, Iterable, Optional

STEPS = ("repair", "simplify", "subdivide", "unwrap", "paint", "bake")


class ManifestError(ValueError):
    """A manifest line that cannot be run (names the line and the problem)."""


def read_manifest(path: str | os.PathLike) -> list[dict[str, Any]]:
    """The assets of a JSON-lines manifest, paths made absolute (relative ones are relative to the
    manifest's folder). Raises ManifestError naming the line for a malformed one."""
    path = pathlib.Path(path)
    base = path.resolve().parent
    assets = []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            where = f"{path}:{number}"
            try:
                entry = json.loads(line)
            except json.JSONDecodeError as e:
                raise ManifestError(f"{where}: not JSON ({e.msg})") from None
            assets.append(_check_entry(entry, where, base))
    names = [a["name"] for a in assets]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise ManifestError(f"{path}: two assets named {dup!r} (give each a \"name\")")
    return assets


def _check_entry(entry: Any, where: str, base: pathlib.Path) -> dict[str, Any]:
    if not isinstance(entry, dict) or "input" not in entry:
        raise ManifestError(f"{where}: expected an object with \"input\"")
    unknown = set(entry) - {"input", "output", "steps", "name"}
    if unknown:
        raise ManifestError(f"{where}: unknown key {sorted(unknown)[0]!r}")
    steps = entry.get("steps", [])
    if not isinstance(steps, list):
        raise ManifestError(f"{where}: \"steps\" must be a list")
    checked = []
    for i, step in enumerate(steps):
        if not isinstance(step, dict) or len(step) != 1:
            raise ManifestError(f"{where}: step {i} must be one {{\"job\": {{options}}}}")
        (job, options), = step.items()
        if job not in STEPS:
            raise ManifestError(f"{where}: step {i}: unknown job {job!r} (known: "
                                f"{', '.join(STEPS)})")
        if not isinstance(options, dict):
            raise ManifestError(f"{where}: step {i}: the options of {job} must be an object")
        options = dict(options)
        for key in ("output", "strokes", "texture"):
            if isinstance(options.get(key), str):
                options[key] = str(base / options[key])
        checked.append((job, options))
    absolute = {"input": str(base / entry["input"]), "steps": checked}
    if entry.get("output") is not None:
        absolute["output"] = str(base / entry["output"])
    absolute["name"] = str(entry.get("name", entry["input"]))
    return absolute


def _outputs(asset: dict[str, Any]) -> list[str]:
    outs = [options["output"] for _, options in asset["steps"] if "output" in options]
    if "output" in asset:
        outs.append(asset["output"])
    return outs


def _inputs(asset: dict[str, Any]) -> list[str]:
    ins = [asset["input"]]
    ins += [o[k] for _, o in asset["steps"] for k in ("strokes", "texture") if isinstance(o.get(k),
                                                                                            str)]
    return ins


def up_to_date(asset: dict[str, Any]) -> bool:
    """True when the asset has outputs and each exists and is newer than every input."""
    outs = _outputs(asset)
    if not outs:
        return False
    try:
        newest_in = max(os.path.getmtime(p) for p in _inputs(asset))
        return all(os.path.getmtime(p) > newest_in for p in outs)
    except OSError:
        return False


def _remove_stale_temporaries(outputs: list[str]) -> None:
    """Removes what a killed run of this asset left while writing: limn writes OUT through a
    temporary ``.OUT.limn-XXXXXX`` beside it and renames it, and a worker killed in between
    cannot remove it."""
    for out in outputs:
        path = pathlib.Path(out)
        for stale in path.parent.glob(f".{path.name}.limn-*"):
            try:
                stale.unlink()
            except OSError:
                pass


def run_asset(asset: dict[str, Any], force: bool = False) -> dict[str, Any]:
    """Runs one asset's steps; never raises: a failure is the result's ``error``."""
    import limn  # on the worker

    _remove_stale_temporaries(_outputs(asset))
    start = time.perf_counter()
    result: dict[str, Any] = {"name": asset["name"], "input": asset["input"], "outputs": [],
                              "stats": [], "error": None}
    if not force and up_to_date(asset):
        result.update(status="skipped", outputs=_outputs(asset))
        return result
    try:
        mesh = limn.read_mesh(asset["input"])
        texture = None
        for job, options in asset["steps"]:
            options = dict(options)
            output = options.pop("output", None)
            if job == "paint":
                if "texture" in options:
                    options["texture"] = limn.load_texture(options["texture"])
                done = limn.paint(mesh, options.pop("strokes"), **options)
                texture = done.texture
                if output:
                    texture.save(output)
            elif job == "bake":
                if texture is None:
                    raise limn.InputError("bake: no texture (a paint step must come first)")
                glb = bool(output) and str(output).lower().endswith(".glb")
                if options.get("uv") and glb:
                    # Every material channel the texture has goes into the GLB's material.
                    options.pop("uv")
                    m = limn.bake_material(texture, mesh, **options)
                    limn.write_glb(mesh, output, base_color=m.base_color,
                                   metallic_roughness=m.metallic_roughness, normal=m.normal,
                                   metallic=m.metallic, roughness=m.roughness)
                    result["stats"].append({"job": job})
                    result["outputs"].append(output)
                    continue
                if options.pop("normal_map", False):
                    raise limn.InputError("bake: normal_map goes with uv=True and a .glb output")
                baked = limn.bake(texture, mesh, **options)
                if output:
                    if options.get("uv"):
                        limn.write_png(output, baked)
                    else:
                        colored = mesh.copy()
                        colored.colors = baked
                        limn.write_mesh(colored, output)
                result["stats"].append({"job": job})
                if output:
                    result["outputs"].append(output)
                continue
            else:
                done = getattr(limn, job)(mesh, **options)
                mesh = done.mesh
                if output:
                    limn.write_mesh(mesh, output)
            result["stats"].append({"job": job, **done.stats})
            if output:
                result["outputs"].append(output)
        if "output" in asset:
            limn.write_mesh(mesh, asset["output"])
            result["outputs"].append(asset["output"])
        result["status"] = "done"
    except Exception as e:  # one asset's failure is its result, not the run's
        result["status"] = "failed"
        message = str(e).splitlines()[0] if str(e) else type(e).__name__
        result["error"] = f"{type(e).__name__}: {message}"
    result["seconds"] = time.perf_counter() - start
    return result


def run(manifest: str | os.PathLike, results: str | os.PathLike, *,
        scheduler: Optional[str] = None, workers: Optional[int] = None, force: bool = False,
        progress: bool = True, client=None) -> list[dict[str, Any]]:
    """Runs every asset of ``manifest`` on dask.distributed and appends one JSON line per asset
    to ``results`` as each finishes; returns the results.

    scheduler: a dask scheduler's address (default: a LocalCluster here, ``workers`` processes of
    one thread each, one per core by default). client: an existing ``distributed.Client`` to use
    instead. force: run assets even when their outputs are up to date.
    """
    from distributed import Client, LocalCluster, as_completed

    assets = read_manifest(manifest)
    own_cluster = None
    if client is None:
        if scheduler:
            client = Client(scheduler)
        else:
            own_cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1,
                                       threads_per_worker=1, processes=True,
                                       dashboard_address=":0")  # any free port
            client = Client(own_cluster)
    done: list[dict[str, Any]] = []
    try:
        # One task per asset, its key naming the asset and this run (a key the scheduler still
        # knows from an earlier run would give that run's result back). A task lost with its
        # worker is run again by the scheduler.
        run_id = uuid.uuid4().hex[:8]
        futures = [client.submit(run_asset, asset, force, key=f"limn-{run_id}-{i}-{asset['name']}",
                                 pure=False) for i, asset in enumerate(assets)]
        finished: Iterable = as_completed(futures)
        if progress:
            finished = _progress(finished, len(futures))
        with open(results, "a", encoding="utf-8") as out:
            for future in finished:
                result = future.result()
                out.write(json.dumps(result) + "\n")
                out.flush()
                os.fsync(out.fileno())
                done.append(result)
    finally:
        if own_cluster is not None:
            client.close()
            own_cluster.close()
    return done


def _progress(futures: Iterable, total: int) -> Iterable:
    try:
        from tqdm import tqdm
    except ImportError:  # a plain count instead
        for i, f in enumerate(futures, 1):
            print(f"limn.batch: {i}/{total}", file=sys.stderr)
            yield f
        return
    yield from tqdm(futures, total=total, unit="asset", file=sys.stderr)


def main(argv: Optional[list[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m limn.batch", description=__doc__.split(
        "\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("manifest", help="JSON lines, one asset per line")
    parser.add_argument("-o", "--results", help="JSON-lines results (default: MANIFEST with "
                        ".results.jsonl)")
    parser.add_argument("--scheduler", help="a dask scheduler address (default: a local cluster)")
    parser.add_argument("--workers", type=int, help="local worker processes (default: cores)")
    parser.add_argument("--force", action="store_true", help="run assets that are up to date")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    results = args.results or str(pathlib.Path(args.manifest).with_suffix(".results.jsonl"))
    try:
        done = run(args.manifest, results, scheduler=args.scheduler, workers=args.workers,
                   force=args.force, progress=not args.quiet)
    except (ManifestError, OSError) as e:
        print(f"limn.batch: error: {e}", file=sys.stderr)
        return 2
    failed = sum(r["status"] == "failed" for r in done)
    skipped = sum(r["status"] == "skipped" for r in done)
    print(f"limn.batch: {len(done) - failed - skipped} done, {skipped} skipped, {failed} failed; "
          f"results in {results}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
