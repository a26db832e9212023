"""curvefem.study: the convergence studies of `curvefem study` from Python (pipeline/study.hpp)."""

import csv
import json
import os
import pathlib
import subprocess

import pytest

import curvefem

BUILD = pathlib.Path(curvefem.__file__).resolve().parents[2]
CLI = BUILD / "tools" / "curvefem" / "curvefem"

EXACT = "sin(x)*cos(y)*exp(z)"
LAP = "sin(x)*cos(y)*exp(z)"  # -Δu = (1 + 1 - 1) u


def cube_study(out):
    """P1 and P2 on the built-in cube of 2, 4, 8 divisions: an h-refinement per degree."""
    return {
        "description": "P1/P2 h-refinement",
        "base": {
            "geometry": {"builtin": {"shape": "cube", "divisions": 2, "order": 1}},
            "physics": {"type": "poisson"},
            "rhs": LAP,
            "boundary_conditions": [{"type": "dirichlet", "select": {"all": True},
                                     "value": EXACT}],
            "exact": EXACT,
        },
        "sweep": {"/discretization/degree": [1, 2], "/geometry/builtin/divisions": [2, 4, 8]},
        "output": {"dir": str(out)},
    }


def test_a_study_from_a_dict_fits_the_optimal_rates_and_writes_its_outputs(tmp_path):
    stages = []
    report = curvefem.study(cube_study(tmp_path / "s"), progress=lambda s, f: stages.append(s))
    assert report["exit_code"] == 0 and report["failed_runs"] == 0
    assert len(report["runs"]) == 6
    assert any(s.startswith("[1/6] degree=1_divisions=2: ") for s in stages)
    rates = {tuple(s["parameters"].items()): s["rates"] for s in report["series"]}
    # L2 error O(h^(p+1)) and H1 O(h^p), least squares over n = 2, 4, 8 by tets (exactly ~ h^-3).
    l2_p1 = rates[(("degree", 1),)]["l2_error"]["rate_h_tets"]
    l2_p2 = rates[(("degree", 2),)]["l2_error"]["rate_h_tets"]
    h1_p2 = rates[(("degree", 2),)]["h1_error"]["rate_h_tets"]
    assert 1.8 < l2_p1 < 2.2, l2_p1
    assert 2.8 < l2_p2 < 3.3, l2_p2
    assert 1.8 < h1_p2 < 2.3, h1_p2
    out = tmp_path / "s"
    on_disk = json.loads((out / "study.json").read_text())
    assert on_disk["runs"] == report["runs"]
    with open(out / "study.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["name"] for r in rows] == [r["name"] for r in report["runs"]]
    assert all(r["status"] == "ok" for r in rows)
    assert (out / "runs" / "degree=2_divisions=8" / "report.json").is_file()


def test_the_module_and_the_cli_give_the_same_study(tmp_path):
    study = cube_study(tmp_path / "py")
    study["sweep"] = {"/discretization/degree": [2], "/geometry/builtin/divisions": [2, 4]}
    from_python = curvefem.study(study)
    study["output"]["dir"] = str(tmp_path / "cli")
    path = tmp_path / "study.json"
    path.write_text(json.dumps(study))
    subprocess.run([str(CLI), "study", str(path), "--quiet"], check=True)
    from_cli = json.loads((tmp_path / "cli" / "study.json").read_text())
    for a, b in zip(from_python["runs"], from_cli["runs"]):
        assert a["name"] == b["name"] and a["dofs"] == b["dofs"]
        assert a["l2_error"] == pytest.approx(b["l2_error"], rel=1e-12)


def test_a_bad_study_raises_input_error_naming_the_path_and_writes_nothing(tmp_path):
    study = cube_study(tmp_path / "bad")
    study["sweeps"] = study.pop("sweep")
    with pytest.raises(curvefem.InputError) as info:
        curvefem.study(study)
    assert "/sweeps: unknown key" in str(info.value)
    assert "allowed here: base, description, output, refine, sweep, x" in str(info.value)
    study = cube_study(tmp_path / "bad")
    study["sweep"]["/discretization/degree"] = [1, 7]
    with pytest.raises(curvefem.InputError) as info:
        curvefem.study(study)
    assert "/sweep/~1discretization~1degree/1" in str(info.value)
    study = cube_study(tmp_path / "bad")
    study["x"] = "cells"
    with pytest.raises(curvefem.InputError) as info:
        curvefem.study(study)
    assert "/x: 'cells': expected dofs or tets" in str(info.value)
    assert not (tmp_path / "bad").exists()
    with pytest.raises(curvefem.Error):
        curvefem.study(tmp_path / "missing.json")


def test_the_study_schema_is_data():
    keys = {k["path"]: k for k in json.loads(
        subprocess.run([str(CLI), "schema", "--study", "--json"], check=True,
                       capture_output=True, text=True).stdout)}
    assert set(keys) == {"base", "sweep", "refine", "x", "description", "output", "output.dir"}
    assert keys["x"]["allowed"] == ["dofs", "tets"] and keys["x"]["default"] == "dofs"
