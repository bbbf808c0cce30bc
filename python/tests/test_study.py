"""gradel.study on a local Dask cluster of 2 worker processes on loopback: a 4-run study of a
small dropped sphere (one run deliberately failing), then the same study again, which must skip
the finished runs."""
import csv
import json
import os

import pytest

distributed = pytest.importorskip("distributed", reason="python3-distributed (scripts/packages/python.txt)")

from gradel import study as gs  # noqa: E402

ROOT = os.environ.get("GRADEL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))

BASE = {
    "dim": 3,
    "body": {"shape": "sphere", "size": 6, "voxel_size": 0.01},
    "material": {"youngs_modulus": 1e5, "density": 1000},
    "simulation": {"damping": 1.0, "duration": 0.15, "frame_interval": 0.01},
    "domain": {"min": [-0.2, 0, -0.2], "max": [0.2, 0.5, 0.2], "restitution": 0.3},
}
# Falls from y = 0.06 m (lattice origin) onto the floor at about t = 0.09 s.
BASE["body"]["position"] = [0, 0.06, 0]


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                       dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_overrides_and_run_ids():
    s = gs.apply_overrides(BASE, {"material.youngs_modulus": 2e4, "simulation.gravity": [0, -1, 0], "new.key": 1})
    assert s["material"]["youngs_modulus"] == 2e4 and s["simulation"]["gravity"] == [0, -1, 0] and s["new"] == {"key": 1}
    assert BASE["material"]["youngs_modulus"] == 1e5  # the base is not changed
    assert gs.run_id({"a": 1, "b": 2}) == gs.run_id({"b": 2, "a": 1}) != gs.run_id({"a": 1, "b": 3})
    assert gs.grid_runs({"x": [1, 2], "y": ["a", "b", "c"]})[:2] == [{"x": 1, "y": "a"}, {"x": 1, "y": "b"}]
    with pytest.raises(gs.StudyError, match="s.json: material.youngs_modulus.x: material.youngs_modulus is not"):
        gs.apply_overrides(BASE, {"material.youngs_modulus.x": 1}, "s.json")


def test_bad_study_files_name_the_key(tmp_path):
    def bad(data, match):
        with pytest.raises(gs.StudyError, match=match):
            gs.parse_study(data, "s.json", tmp_path)
    bad({"base": BASE, "grid": {"a": [1]}, "out": "o", "extra": 1}, "s.json: extra: unknown key")
    bad({"base": BASE, "out": "o"}, "exactly one of grid")
    bad({"base": BASE, "grid": {"material.density": []}, "out": "o"}, "grid.material.density: expected a non-empty list")
    bad({"base": "missing.json", "grid": {"a": [1]}, "out": "o"}, "base: .*missing.json: cannot read")
    bad({"base": BASE, "runs": [{"a": 1}, {"a": 1}], "out": "o"}, "given twice")
    bad({"base": BASE, "runs": [{"a": 1}]}, "out: missing")


def test_relative_files_of_a_base_scene_file_are_resolved(tmp_path):
    s = gs.parse_study({"base": os.path.join(ROOT, "scenes", "ct-nrrd.json"), "runs": [{}], "out": "o"}, "s.json", tmp_path)
    path = s.base["body"]["source"]["file"]
    assert os.path.isabs(path) and os.path.isfile(path)


def test_study_on_two_local_workers_reports_failures_and_skips_finished_runs(tmp_path, client):
    data = {
        "base": BASE,
        "runs": [
            {"material.youngs_modulus": 2e4},
            {"material.youngs_modulus": 2e5},
            {"body.size": 8},
            {"material.youngs_modulus": -1},  # fails: the scene reader rejects it
        ],
        "out": "out",
    }
    study = gs.parse_study(data, "tiny.json", tmp_path)
    table = gs.run_study(study, client=client, progress=False)
    assert [r["run_id"] for r in table] == [gs.run_id(r) for r in data["runs"]]
    ok = [r for r in table if not r["error"]]
    failed = [r for r in table if r["error"]]
    assert len(ok) == 3 and len(failed) == 1
    rid = gs.run_id({"material.youngs_modulus": -1})
    assert failed[0]["error"].startswith(f"InputError: runs/{rid}/scene.json: material.youngs_modulus: -1 is out of range")
    assert failed[0]["overrides"] == {"material.youngs_modulus": -1}
    soft, stiff, big = ok
    # Physics: every body fell onto the floor (centre of mass about its radius up, no deeper),
    # and the softer one strains more on impact.
    for r in ok:
        assert r["simulated_seconds"] == pytest.approx(0.15, abs=r["dt"])
        assert 0.0 < r["final_com_y"] < 0.06 + 0.03  # below where the centre started
    assert soft["max_strain"] > 1.5 * stiff["max_strain"] > 0
    assert big["vertices"] > soft["vertices"] == stiff["vertices"]

    # The table: CSV with one row per run, the override keys as columns.
    with open(tmp_path / "out" / "results.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and {"run_id", "error", "material.youngs_modulus", "body.size", "max_stress"} <= set(rows[0])
    assert [bool(r["error"]) for r in rows] == [False, False, False, True]
    for r in table:
        stored = json.loads((tmp_path / "out" / "runs" / r["run_id"] / "result.json").read_text())
        assert stored["error"] == r["error"]

    # Again: the three finished runs are taken from the folder, the failed one runs again.
    stamps = {r["run_id"]: os.stat(tmp_path / "out" / "runs" / r["run_id"] / "result.json").st_mtime_ns for r in ok}
    again = gs.run_study(gs.parse_study(data, "tiny.json", tmp_path), client=client, progress=False)
    assert [r["cached"] for r in again] == [True, True, True, False]
    assert [r.get("state_hash") for r in again[:3]] == [r["state_hash"] for r in ok]
    for rid, stamp in stamps.items():
        assert os.stat(tmp_path / "out" / "runs" / rid / "result.json").st_mtime_ns == stamp
    assert again[3]["error"]


def test_command_line_exit_codes(tmp_path):
    (tmp_path / "bad.json").write_text('{"base": {}, "grid": {"a": []}, "out": "o"}')
    assert gs.main([str(tmp_path / "bad.json"), "--no-progress"]) == gs.EXIT_BAD_STUDY
    assert not (tmp_path / "o").exists()


def test_a_bad_key_or_value_in_the_grid_stops_the_study_before_any_worker(tmp_path):
    data = {"base": BASE, "grid": {"material.youngs_modulu": [1e4, 2e4]}, "out": "o"}
    with pytest.raises(gs.StudyError, match=r"^s\.json: the first run .*: material\.youngs_modulu: "):
        gs.parse_study(data, "s.json", tmp_path)
    data = {"base": BASE, "grid": {"body.size": [0, 8]}, "out": "o"}
    with pytest.raises(gs.StudyError, match=r"^s\.json: the first run \{\"body\.size\": 0\}: body\.size: "):
        gs.parse_study(data, "s.json", tmp_path)
    # The command line: exit 2 naming the key, nothing written, no cluster started.
    (tmp_path / "typo.json").write_text(json.dumps({"base": BASE, "grid": {"simulation.dampng": [1, 2]}, "out": "o"}))
    assert gs.main([str(tmp_path / "typo.json"), "--no-progress"]) == gs.EXIT_BAD_STUDY
    assert not (tmp_path / "o").exists()
    # Only the first run is read ahead: a later run that fails is that run's failure.
    gs.parse_study({"base": BASE, "runs": [{}, {"body.size": 0}], "out": "o"}, "s.json", tmp_path)


def test_the_summary_shows_the_varied_keys_against_one_metric():
    study = gs.parse_study({"base": BASE, "grid": {"material.youngs_modulus": [2e4, 1e5], "body.size": [6]},
                            "out": "o", "metric": "final_com_y"}, "s.json")
    table = [
        {"run_id": "a", "overrides": study.runs[0], "error": "", "cached": False, "final_com_y": 0.0312345},
        {"run_id": "b", "overrides": study.runs[1], "error": "RuntimeError: diverged", "cached": True},
    ]
    lines = gs.summary_lines(study, table)
    assert lines[0] == "study: 2 runs, 1 failed, 1 cached; final_com_y by material.youngs_modulus, body.size"
    assert lines[1].split() == ["material.youngs_modulus", "body.size", "final_com_y"]
    assert lines[2].split() == ["2e+04", "6", "0.03123"]
    assert lines[3].split()[:3] == ["1e+05", "6", "FAILED:"]
    assert gs.summary_lines(study, table, "max_stress")[2].split()[-3:] == ["(no", "column", "max_stress)"]
    assert len(gs.summary_lines(study, table * 30, max_rows=5)) == 2 + 5 + 1


def test_scripts_study_uses_the_active_virtual_environment(tmp_path):
    # A "virtual environment" whose python notes that it ran, then runs this interpreter.
    import subprocess
    import sys
    import gradel

    venv = tmp_path / "venv"
    (venv / "bin").mkdir(parents=True)
    marker = tmp_path / "used"
    site = os.path.dirname(os.path.dirname(os.path.abspath(gradel.__file__)))
    for name in ("python", "python3"):
        script = venv / "bin" / name
        script.write_text(f"#!/bin/sh\necho $0 >> '{marker}'\nPYTHONPATH='{site}' exec '{sys.executable}' \"$@\"\n")
        script.chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k not in ("GRADEL_PYTHON",)}
    env.update(VIRTUAL_ENV=str(venv), PATH=f"{venv / 'bin'}:{env.get('PATH', '')}")
    r = subprocess.run([os.path.join(ROOT, "scripts", "study"), "--help"], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "--metric" in r.stdout
    assert marker.exists() and str(venv / "bin") in marker.read_text()
