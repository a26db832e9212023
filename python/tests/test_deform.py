"""curvefem.deform (SCAF with a tet scaffold) from Python: the guarantee comes back in the report
from exact checks independent of the solver, and bad input raises curvefem.InputError."""

import subprocess
import pathlib

import numpy as np
import pytest

import curvefem

BUILD = pathlib.Path(curvefem.__file__).resolve().parents[2]
CLI = BUILD / "tools" / "curvefem" / "curvefem"


def read_obj(path):
    V, F = [], []
    for line in pathlib.Path(path).read_text().splitlines():
        if line.startswith("v "):
            V.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            F.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    return np.array(V), np.array(F, dtype=np.int32)


def split_ring(tmp_path):
    path = tmp_path / "ring.obj"
    subprocess.run([str(CLI), "generate", "split_ring_01", "-q", "-o", str(path)], check=True)
    return read_obj(path)


def test_pulling_the_ends_of_a_split_ring_across_keeps_it_embedded(tmp_path):
    V, F = split_ring(tmp_path)
    last = len(V) - 4  # the generator's last section: the other end cap
    targets = {}
    for k in range(4):
        targets[k] = V[last + k]
        targets[last + k] = V[k]
    W, report = curvefem.deform(V, F, targets, iterations=20)
    assert W.shape == V.shape
    assert report["valid"] is True
    assert report["self_intersecting_pairs"] == 0
    assert report["max_self_intersecting_pairs_over_iterations"] == 0
    assert report["naive_self_intersecting_pairs"] > 0
    assert report["non_positive_tets"] == 0
    assert report["iterations"] >= 1
    # the ends moved toward each other: at least a quarter of the way
    assert np.linalg.norm(W[0] - V[last]) < 0.75 * np.linalg.norm(V[0] - V[last])
    # the scaffold rebuilt every iteration (the thesis) gives a valid result too, with no kept one
    W0, report0 = curvefem.deform(V, F, targets, iterations=20, rebuild_quality=0.0)
    assert report0["valid"] is True
    assert report0["scaffold_kept"] == 0
    assert report["scaffold_kept"] > 0
    assert report["sliver_rests"] is False and report["max_slivers"] == 0
    # sliver rests: the flattened scaffold between the ends pushes back, still embedded
    W1, report1 = curvefem.deform(V, F, targets, iterations=20, sliver_rests=True)
    assert report1["valid"] is True
    assert report1["max_self_intersecting_pairs_over_iterations"] == 0
    assert report1["sliver_rests"] is True and report1["max_slivers"] > 0


def test_untangle_and_bad_input(tmp_path):
    V, F = split_ring(tmp_path)
    last = len(V) - 4
    crossed = V.copy()
    crossed[:4], crossed[last:] = V[last:], V[:4]
    W, report = curvefem.deform(crossed, F, untangle=True, iterations=10)
    assert report["untangle"]["input_self_intersecting_pairs"] > 0
    assert report["untangle"]["genus"] == 0
    assert report["self_intersecting_pairs"] == 0
    assert report["valid"] is True
    with pytest.raises(curvefem.InputError, match="intersects itself"):
        curvefem.deform(crossed, F, {0: V[0]})
    with pytest.raises(curvefem.InputError, match="not a vertex"):
        curvefem.deform(V, F, {len(V) + 5: (0, 0, 0)})
    # the thesis' way back: the ARAP term alone (no positional targets); without it, refused
    W2, report2 = curvefem.deform(crossed, F, untangle=True, iterations=10, arap=1000.0,
                                  way_back_targets=False)
    assert report2["valid"] is True
    assert report2["untangle"]["way_back_targets"] is False
    assert report2["untangle"]["edge_length_error_mean"] < 0.1
    with pytest.raises(curvefem.InputError, match="ARAP"):
        curvefem.deform(crossed, F, untangle=True, way_back_targets=False)
    with pytest.raises(curvefem.InputError, match="untangle option"):
        curvefem.deform(V, F, {0: V[0]}, way_back_targets=False)
