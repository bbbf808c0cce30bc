"""Parameter studies of gradel scenes on a Dask distributed cluster (docs/study.md).

A study is a base scene (a scene file or an inline scene, docs/scenes.md) and a set of runs,
each a dict of overrides keyed by dotted paths into the scene, e.g.
``{"material.youngs_modulus": 1e5, "body.size": 12}``. The runs go to a Dask cluster (a
``LocalCluster`` on this machine by default, or the scheduler at ``address``); every run
simulates its scene through the Python API and returns the figures ``gradel run`` prints in its
JSON summary plus the final metrics. Results are stored per run in ``<out>/runs/<run id>/``
(the run id is a hash of the run's overrides) and collected into ``<out>/results.csv`` (and
``results.parquet`` when pandas can write Parquet). A run that fails reports its error in the
``error`` column without stopping the others; running the study again skips the runs that
already finished.

Command line: ``python3 -m gradel.study STUDY.json`` (or ``scripts/study STUDY.json``).
"""
from __future__ import annotations

import argparse
import copy
import csv
import hashlib
import itertools
import json
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence

__all__ = [
    "StudyError",
    "Study",
    "load_study",
    "parse_study",
    "grid_runs",
    "run_id",
    "apply_overrides",
    "run_scene",
    "run_study",
    "check_first_run",
    "summary_lines",
    "main",
]

EXIT_OK = 0
EXIT_BAD_STUDY = 2   # the study file is malformed (nothing run, nothing written)
EXIT_RUNS_FAILED = 5  # the study ran; some runs failed (see the error column)


class StudyError(ValueError):
    """A malformed study file or override; the message names the file and the key."""


@dataclass
class Study:
    """A parsed study: the base scene, one dict of overrides per run, the output folder."""

    base: Dict[str, Any]
    runs: List[Dict[str, Any]]
    out: Path
    source: str = "<study>"
    keys: List[str] = field(default_factory=list)  # every overridden key, in first-seen order
    metric: str = "max_stress"  # the column summarised on screen at the end (DEFAULT_METRIC)


# ---- study files ----------------------------------------------------------------------------

def grid_runs(grid: Mapping[str, Sequence[Any]], source: str = "<study>") -> List[Dict[str, Any]]:
    """Every combination of the grid's values (the first key varies slowest)."""
    keys = list(grid)
    for k in keys:
        values = grid[k]
        if not isinstance(values, list) or not values:
            raise StudyError(f"{source}: grid.{k}: expected a non-empty list of values")
    return [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]


def run_id(overrides: Mapping[str, Any]) -> str:
    """A stable id of a run: the first 12 hex digits of the SHA-256 of its overrides as JSON."""
    text = json.dumps(overrides, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def _absolute_files(node: Any, base_dir: Path) -> Any:
    """Makes every relative ``"file"`` path of a scene (body.source, pin masks) absolute against
    the base scene's folder, as the scene reader would resolve it, so that the scene can be
    written anywhere (a worker's temporary folder)."""
    if isinstance(node, dict):
        out = {}
        for k, v in node.items():
            if k == "file" and isinstance(v, str) and v and not os.path.isabs(v):
                out[k] = str((base_dir / v).resolve())
            else:
                out[k] = _absolute_files(v, base_dir)
        return out
    if isinstance(node, list):
        return [_absolute_files(v, base_dir) for v in node]
    return node


def apply_overrides(scene: Mapping[str, Any], overrides: Mapping[str, Any], source: str = "<study>") -> Dict[str, Any]:
    """A copy of ``scene`` with each dotted key set: ``"a.b.c"`` sets ``scene["a"]["b"]["c"]``
    (creating objects on the way); a number indexes a list (``"manipulators.0.radius"``)."""
    out = copy.deepcopy(dict(scene))
    for key, value in overrides.items():
        parts = key.split(".")
        if not key or any(p == "" for p in parts):
            raise StudyError(f"{source}: {key!r}: expected a dotted key path such as material.youngs_modulus")
        node: Any = out
        for depth, part in enumerate(parts):
            last = depth == len(parts) - 1
            where = ".".join(parts[: depth + 1])
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise StudyError(f"{source}: {key}: {where}: no element {part} in a list of {len(node)}")
                if last:
                    node[int(part)] = copy.deepcopy(value)
                else:
                    node = node[int(part)]
            elif isinstance(node, dict):
                if last:
                    node[part] = copy.deepcopy(value)
                else:
                    node = node.setdefault(part, {})
            else:
                raise StudyError(f"{source}: {key}: {'.'.join(parts[:depth])} is not an object or a list")
    return out


def _read_json(path: Path, context: str = "") -> Any:
    """The JSON in ``path``; StudyError naming ``context`` and the path otherwise."""
    try:
        with open(path) as f:
            return json.load(f)
    except OSError as e:
        raise StudyError(f"{context}{path}: cannot read: {e.strerror}") from None
    except json.JSONDecodeError as e:
        raise StudyError(f"{context}{path}: not JSON ({e})") from None


_STUDY_KEYS = {"base", "grid", "runs", "out", "name", "metric"}

# The column the end-of-study summary shows against the varied keys (the study's "metric",
# or --metric).
DEFAULT_METRIC = "max_stress"


def parse_study(data: Mapping[str, Any], source: str = "<study>", base_dir: Optional[Path] = None,
                check_scene: bool = True) -> Study:
    """Validates a study given as a dict (the JSON of a study file). Relative paths (``base``,
    ``out``) are relative to ``base_dir`` (the study file's folder; default: the current one).
    With ``check_scene``, the first run's scene is read by the scene reader too
    (check_first_run)."""
    base_dir = Path(base_dir or ".")
    if not isinstance(data, Mapping):
        raise StudyError(f"{source}: expected a JSON object with base, grid or runs, and out")
    unknown = sorted(set(data) - _STUDY_KEYS)
    if unknown:
        raise StudyError(f"{source}: {unknown[0]}: unknown key (expected one of {', '.join(sorted(_STUDY_KEYS))})")
    if "base" not in data:
        raise StudyError(f"{source}: base: missing (a scene file path or an inline scene object)")
    base = data["base"]
    scene_dir = base_dir
    if isinstance(base, str):
        path = (base_dir / base) if not os.path.isabs(base) else Path(base)
        base = _read_json(path, f"{source}: base: ")
        scene_dir = path.parent
    if not isinstance(base, dict):
        raise StudyError(f"{source}: base: expected a scene file path or a scene object")
    base = _absolute_files(base, scene_dir)

    if ("grid" in data) == ("runs" in data):
        raise StudyError(f"{source}: give exactly one of grid (key -> list of values) and runs (list of overrides)")
    if "grid" in data:
        if not isinstance(data["grid"], Mapping) or not data["grid"]:
            raise StudyError(f"{source}: grid: expected an object of dotted keys -> lists of values")
        runs = grid_runs(data["grid"], source)
    else:
        runs = data["runs"]
        if not isinstance(runs, list) or not runs or not all(isinstance(r, dict) for r in runs):
            raise StudyError(f"{source}: runs: expected a non-empty list of objects (dotted key -> value)")
        runs = [dict(r) for r in runs]
    ids = [run_id(r) for r in runs]
    if len(set(ids)) != len(ids):
        dup = next(r for r, i in zip(runs, ids) if ids.count(i) > 1)
        raise StudyError(f"{source}: runs: the run {json.dumps(dup)} is given twice")
    for r in runs:
        apply_overrides(base, r, source)  # key paths that cannot be set fail here, before anything runs

    if "out" not in data or not isinstance(data["out"], str) or not data["out"]:
        raise StudyError(f"{source}: out: missing (the folder the results go to)")
    out = Path(data["out"]) if os.path.isabs(data["out"]) else base_dir / data["out"]
    keys: List[str] = []
    for r in runs:
        keys.extend(k for k in r if k not in keys)
    metric = data.get("metric", DEFAULT_METRIC)
    if not isinstance(metric, str) or not metric:
        raise StudyError(f"{source}: metric: expected a column name such as {DEFAULT_METRIC}")
    if check_scene:
        check_first_run(base, runs[0], source)
    return Study(base=base, runs=runs, out=out, source=source, keys=keys, metric=metric)


def check_first_run(base: Mapping[str, Any], overrides: Mapping[str, Any], source: str = "<study>") -> None:
    """Reads the first run's scene with the scene reader (gradel.check_scene, building nothing),
    so that a misspelt key or a bad value in the base or the grid stops the study before any
    worker starts: StudyError naming the key."""
    from . import InputError, check_scene

    try:
        check_scene(apply_overrides(base, overrides, source))
    except InputError as e:
        message = str(e)
        if message.startswith("dict: "):
            message = message[len("dict: "):]
        raise StudyError(f"{source}: the first run {json.dumps(dict(overrides))}: {message}") from None


def load_study(path: os.PathLike | str) -> Study:
    """Reads a study file (JSON: base, grid or runs, out; docs/study.md)."""
    path = Path(path)
    return parse_study(_read_json(path), str(path), path.parent)


# ---- one run ----------------------------------------------------------------------------------

def run_scene(scene: Mapping[str, Any], label: str = "scene") -> Dict[str, Any]:
    """Simulates a scene (a dict, as in a scene file) for its ``simulation.duration`` and returns
    the figures of ``gradel run``'s JSON summary (metrics sampled every ``frame_interval``, as
    its frames are) plus ``final_*`` metrics and the final centre of mass. Raises
    ``gradel.InputError`` for a bad scene (its message names ``label`` and the key) and
    ``RuntimeError`` when the run diverges."""
    import numpy as np

    from . import InputError, Simulation

    sim_cfg = scene.get("simulation", {}) if isinstance(scene.get("simulation", {}), dict) else {}
    with tempfile.TemporaryDirectory(prefix="gradel-study-") as tmp:
        path = os.path.join(tmp, "scene.json")
        with open(path, "w") as f:
            json.dump(scene, f)
        try:
            sim = Simulation.from_scene(path)  # validates the scene (InputError names the key)
        except InputError as e:
            raise InputError(str(e).replace(path, label)) from None
    duration = float(sim_cfg.get("duration", 1.0))
    interval = float(sim_cfg.get("frame_interval", 1.0 / 30.0))
    dt = sim.dt
    frames = max(1, math.ceil(duration / interval - 1e-9))
    max_penetration = 0.0
    max_stress = 0.0
    max_strain = 0.0
    start = time.perf_counter()
    m = sim.metrics()
    for f in range(frames + 1):
        if f > 0:
            t_frame = min(f * interval, duration)
            if sim.time < t_frame - 0.5 * dt:
                sim.advance_to(t_frame)
            if not (np.isfinite(sim.positions).all() and np.isfinite(sim.velocities).all()):
                raise RuntimeError(f"simulation diverged at t={sim.time:.6g} s (dt = {dt:.3g} s), try a smaller dt")
            m = sim.metrics()
        max_penetration = max(max_penetration, m["max_penetration"])
        max_stress = max(max_stress, m["max_stress"])
        max_strain = max(max_strain, m["max_strain"])
    wall = time.perf_counter() - start
    masses = sim.masses
    com = (masses[:, None] * sim.positions).sum(axis=0) / masses.sum()
    result: Dict[str, Any] = {
        "steps": int(round(sim.time / dt)),
        "dt": dt,
        "simulated_seconds": sim.time,
        "frames": frames + 1,
        "wall_seconds": wall,
        "real_time_factor": sim.time / wall if wall > 0 else 0.0,
        "elements": sim.num_elements,
        "vertices": sim.num_vertices,
        "final_kinetic_energy": m["kinetic_energy"],
        "max_penetration": max_penetration,
        "max_stress": max_stress,
        "max_strain": max_strain,
        "state_hash": f"{sim.state_hash:016x}",
    }
    for k, v in m.items():
        if isinstance(v, (list, tuple)):
            for axis, x in zip("xyz", v):
                result[f"final_{k}_{axis}"] = x
        elif k != "kinetic_energy":
            result[f"final_{k}"] = v
    for axis, x in zip("xyz", com):
        result[f"final_com_{axis}"] = float(x)
    return result


def _run_task(rid: str, overrides: Dict[str, Any], scene: Dict[str, Any]) -> Dict[str, Any]:
    """What a worker runs: one scene, its failure caught and returned as the error column."""
    record: Dict[str, Any] = {"run_id": rid, "overrides": overrides}
    try:
        record.update(run_scene(scene, f"runs/{rid}/scene.json"))
        record["error"] = ""
    except Exception as e:  # noqa: BLE001 - every failure of one run is that run's result
        record["error"] = f"{type(e).__name__}: {e}".strip()
    return record


# ---- the study --------------------------------------------------------------------------------

def _write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w") as f:
        json.dump(data, f, indent=2, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)


def _load_finished(run_dir: Path) -> Optional[Dict[str, Any]]:
    try:
        with open(run_dir / "result.json") as f:
            record = json.load(f)
    except (OSError, json.JSONDecodeError):
        return None
    return record if isinstance(record, dict) and not record.get("error") else None


class _Bar:
    """A one-line progress bar on a terminal; one line per finished run otherwise."""

    def __init__(self, total: int, enabled: bool, stream=sys.stderr):
        self.total, self.done, self.failed = total, 0, 0
        self.enabled, self.stream = enabled, stream
        self.tty = enabled and hasattr(stream, "isatty") and stream.isatty()
        self.start = time.perf_counter()

    def update(self, record: Dict[str, Any], cached: bool = False) -> None:
        self.done += 1
        self.failed += bool(record.get("error"))
        if not self.enabled:
            return
        if self.tty:
            width = 30
            filled = int(width * self.done / max(1, self.total))
            self.stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} runs"
                              f", {self.failed} failed, {time.perf_counter() - self.start:.0f} s ")
            if self.done == self.total:
                self.stream.write("\n")
        else:
            state = "cached" if cached else ("FAILED " + record["error"] if record.get("error") else "ok")
            self.stream.write(f"study: {self.done}/{self.total} run {record['run_id']}: {state}\n")
        self.stream.flush()


# The summary figures in `gradel run`'s order; the final metrics follow in name order.
_SUMMARY = ["steps", "dt", "simulated_seconds", "frames", "wall_seconds", "real_time_factor", "elements", "vertices",
            "final_kinetic_energy", "max_penetration", "max_stress", "max_strain",
            "state_hash"]


def _columns(study: Study, rows: List[Dict[str, Any]]) -> List[str]:
    first = ["run_id", "error", "cached"] + study.keys + _SUMMARY
    rest = sorted({k for r in rows for k in r if k not in first and k != "overrides"})
    return first + rest


def _write_table(study: Study, rows: List[Dict[str, Any]]) -> List[Path]:
    columns = _columns(study, rows)
    flat = []
    for r in rows:
        row = {k: v for k, v in r.items() if k != "overrides"}
        for k, v in r["overrides"].items():
            row[k] = json.dumps(v) if isinstance(v, (list, dict)) else v
        flat.append(row)
    written = []
    tmp = study.out / "results.csv.tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, restval="")
        w.writeheader()
        w.writerows(flat)
    os.replace(tmp, study.out / "results.csv")
    written.append(study.out / "results.csv")
    try:  # Parquet when pandas has an engine (pyarrow or fastparquet); CSV is always written
        import pandas as pd

        pd.DataFrame(flat, columns=columns).to_parquet(study.out / "results.parquet", index=False)
        written.append(study.out / "results.parquet")
    except (ImportError, ValueError):
        pass
    return written


def run_study(study: Study, address: Optional[str] = None, n_workers: Optional[int] = None,
              threads_per_worker: int = 1, progress: bool = True, client: Any = None,
              cluster_options: Optional[Mapping[str, Any]] = None) -> List[Dict[str, Any]]:
    """Runs every run of ``study`` not yet finished in ``study.out`` and returns the table (one
    dict per run, in the study's order; ``error`` is empty for a run that succeeded, ``cached``
    is true for one finished by an earlier invocation).

    The cluster: ``client`` (a ``distributed.Client``) if given; else the scheduler at
    ``address`` (``tcp://host:8786``); else a ``LocalCluster`` of ``n_workers`` processes (default:
    the number of CPUs) with ``threads_per_worker`` threads each, plus ``cluster_options``."""
    runs_dir = study.out / "runs"
    runs_dir.mkdir(parents=True, exist_ok=True)
    ids = [run_id(r) for r in study.runs]
    rows: Dict[str, Dict[str, Any]] = {}
    todo = []
    bar = _Bar(len(ids), progress)
    for rid, overrides in zip(ids, study.runs):
        run_dir = runs_dir / rid
        run_dir.mkdir(exist_ok=True)
        finished = _load_finished(run_dir)
        if finished is not None:
            finished["cached"] = True
            rows[rid] = finished
            bar.update(finished, cached=True)
            continue
        scene = apply_overrides(study.base, overrides, study.source)
        _write_json_atomic(run_dir / "scene.json", scene)
        todo.append((rid, overrides, scene))

    if todo:
        from distributed import Client, LocalCluster, as_completed

        own_client = None
        cluster = None
        if client is None:
            if address:
                own_client = client = Client(address)
            else:
                options = dict(n_workers=n_workers or os.cpu_count() or 1, threads_per_worker=threads_per_worker,
                               processes=True, dashboard_address=None)
                options.update(cluster_options or {})
                cluster = LocalCluster(**options)
                own_client = client = Client(cluster)
        try:
            futures = {client.submit(_run_task, rid, ov, sc, key=f"gradel-run-{rid}-{time.time_ns()}", pure=False): rid
                       for rid, ov, sc in todo}
            overrides_of = {rid: ov for rid, ov, _ in todo}
            for fut in as_completed(futures):
                rid = futures[fut]
                try:
                    record = fut.result()
                except Exception as e:  # noqa: BLE001 - a worker lost (crash) is that run's failure
                    record = {"run_id": rid, "overrides": overrides_of[rid], "error": f"{type(e).__name__}: {e}"}
                record["cached"] = False
                _write_json_atomic(runs_dir / rid / "result.json", record)
                rows[rid] = record
                bar.update(record)
        finally:
            if own_client is not None:
                own_client.close()
            if cluster is not None:
                cluster.close()

    table = [rows[rid] for rid in ids]
    _write_table(study, table)
    return table


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return json.dumps(v) if isinstance(v, (list, dict)) else str(v)


def summary_lines(study: Study, table: List[Dict[str, Any]], metric: Optional[str] = None,
                  max_rows: int = 40) -> List[str]:
    """A short summary for the screen: runs, failures, then one line per run with the varied
    keys against one metric (``metric``, default the study's), failed runs marked; at most
    ``max_rows`` runs (the first ones) and a count of the rest."""
    metric = metric or study.metric
    failed = sum(bool(r.get("error")) for r in table)
    cached = sum(bool(r.get("cached")) for r in table)
    lines = [f"study: {len(table)} runs, {failed} failed, {cached} cached; {metric} by "
             + (", ".join(study.keys) if study.keys else "run")]
    header = study.keys + [metric]
    rows = []
    for r in table[:max_rows]:
        cells = [_cell(r.get("overrides", {}).get(k, "")) for k in study.keys]
        if r.get("error"):
            cells.append("FAILED: " + r["error"].splitlines()[0][:60])
        elif metric in r:
            cells.append(_cell(r[metric]))
        else:
            cells.append(f"(no column {metric})")
        rows.append(cells)
    widths = [max(len(h), *(len(c[i]) for c in rows)) if rows else len(h) for i, h in enumerate(header)]
    lines.append("  ".join(h.ljust(w) for h, w in zip(header, widths)).rstrip())
    for cells in rows:
        lines.append("  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip())
    if len(table) > max_rows:
        lines.append(f"... and {len(table) - max_rows} more runs (results.csv)")
    return lines


# ---- command line -----------------------------------------------------------------------------

def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python3 -m gradel.study",
        description="Run a parameter study of gradel scenes on a Dask cluster (docs/study.md).")
    parser.add_argument("study", help="study file (JSON: base, grid or runs, out)")
    parser.add_argument("--address", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786 (default: a local cluster)")
    parser.add_argument("--workers", type=int, help="local cluster: worker processes (default: CPU count)")
    parser.add_argument("--threads-per-worker", type=int, default=1, help="local cluster: threads per worker (default 1)")
    parser.add_argument("--out", help="result folder (overrides the study's out)")
    parser.add_argument("--no-progress", action="store_true", help="print no progress")
    parser.add_argument("--metric", help=f"the column the summary at the end shows against the varied keys "
                                         f"(default: the study's metric, else {DEFAULT_METRIC})")
    args = parser.parse_args(argv)
    try:
        study = load_study(args.study)
    except StudyError as e:
        print(f"gradel.study: {e}", file=sys.stderr)
        return EXIT_BAD_STUDY
    if args.out:
        study.out = Path(args.out)
    table = run_study(study, address=args.address, n_workers=args.workers,
                      threads_per_worker=args.threads_per_worker, progress=not args.no_progress)
    failed = [r for r in table if r.get("error")]
    summary = {"study": args.study, "runs": len(table), "failed": len(failed),
               "cached": sum(bool(r.get("cached")) for r in table), "results": str(study.out / "results.csv")}
    print(json.dumps(summary, indent=2))
    for r in failed:
        print(f"gradel.study: run {r['run_id']} {json.dumps(r['overrides'])} failed: {r['error']}", file=sys.stderr)
    for line in summary_lines(study, table, args.metric):  # on the screen (stderr): stdout stays JSON
        print(line, file=sys.stderr)
    return EXIT_RUNS_FAILED if failed else EXIT_OK


if __name__ == "__main__":
    # Through the package's module, so that the workers get gradel.study._run_task by name.
    from gradel.study import main as _main

    sys.exit(_main())
