"""The Python module against the C++ API (through the command line, which runs it):
the same contacts and times on a real step; numpy input of every accepted kind; bad
input as ValueError naming the argument; two threads on two contexts."""
import csv
import json
import subprocess
import threading

import numpy as np
import pytest

import cstreams


def test_devices_and_context(context):
    devices = cstreams.devices()
    assert devices and {"address", "name", "platform", "type", "fp64"} <= set(devices[0])
    assert context.device["name"] in [d["name"] for d in devices]
    with pytest.raises(cstreams.DeviceNotFound):
        cstreams.Context("no-such-device-anywhere")


def test_detector_contacts_equal_the_cpp_run(context, funnel, cli, tmp_path):
    V0, V1, F, frames = funnel
    subprocess.run([cli, "run", *frames, "--out", str(tmp_path / "c.csv")], check=True, capture_output=True)
    with open(tmp_path / "c.csv") as f:
        rows = list(csv.DictReader(f))
    detector = cstreams.Detector(context, [dict(name="funnel", faces=F, positions=V0)])
    detector.set_positions(0, V1)
    detector.detect()
    contacts = detector.contacts()
    assert len(contacts) == len(rows) > 0
    for c, r in zip(contacts, rows):
        assert ("vf" if c["kind"] == 0 else "ee") == r["kind"]
        assert list(c["v"]) == [int(r[f"v{k}"]) for k in range(4)]
        assert c["toi"] == float(r["toi"])
    assert detector.earliest_toi()[0] == pytest.approx(contacts["toi"].min(), abs=1e-7)


def test_step_size_equals_the_cpp_stepsize(context, funnel, cli, tmp_path):
    V0, V1, F, frames = funnel
    subprocess.run([cli, "stepsize", *frames, "--repeat", "1", "--json", str(tmp_path / "s.json")], check=True,
                   capture_output=True)
    expected = json.loads((tmp_path / "s.json").read_text())
    ccd = cstreams.MeshCcd(context, V0, F)
    assert ccd.collision_free_stepsize(V0, V1) == expected["stepsize"]
    assert ccd.toi(V0, V1) == expected["toi"]
    assert not ccd.is_step_collision_free(V0, V1)
    assert ccd.is_step_collision_free(V0, V0)
    assert ccd.toi(V0, V1, tmax=0.01) == 1.0


def test_every_accepted_layout_gives_the_same_answer(context, funnel):
    V0, V1, F, _ = funnel
    ccd = cstreams.MeshCcd(context, V0, F.astype(np.int32))
    toi = ccd.toi(V0, V1)
    assert ccd.toi(np.asfortranarray(V0), np.asfortranarray(V1)) == toi
    # Float positions are rounded ones: the time moves by a rounding at most.
    assert abs(ccd.toi(V0.astype(np.float32), V1.astype(np.float32)) - toi) < 1e-6
    assert cstreams.MeshCcd(context, np.asfortranarray(V0), np.asfortranarray(F)).toi(V0, V1) == toi


def test_bad_input_names_the_argument_and_changes_nothing(context, funnel):
    V0, V1, F, _ = funnel
    ccd = cstreams.MeshCcd(context, V0, F)
    toi = ccd.toi(V0, V1)
    cases = [
        (lambda: ccd.toi(V0[:, :2], V1), "V0: wants an (n, 3) array"),
        (lambda: ccd.toi(V0, V1[:-1]), "V1: has"),
        (lambda: ccd.toi(V0.astype(np.int64), V1), "V0: wants an (n, 3) array of float64 or float32"),
        (lambda: ccd.toi(V0, V1[::2]), "V1:"),
        (lambda: ccd.toi(V0, V1, tmax=0), "tmax = 0"),
        (lambda: ccd.toi(V0, V1, max_iterations=-1), "max_iterations"),
        (lambda: cstreams.MeshCcd(context, V0, F.astype(np.float64)), "F: wants an (n, 3) array of int32 or int64"),
        (lambda: cstreams.MeshCcd(context, V0, F + len(V0)), "F: row 0 holds vertex"),
        (lambda: cstreams.MeshCcd(context, V0, F, solver="fast"), "unknown solver"),
        (lambda: cstreams.MeshProximity(context, V0, F).close_pairs(V0, -1.0), "dhat = -1"),
    ]
    nan = V1.copy()
    nan[5, 1] = np.nan
    cases.append((lambda: ccd.toi(V0, nan), "V1: row 5"))
    for call, message in cases:
        with pytest.raises(ValueError, match=None) as error:
            call()
        assert str(error.value).startswith(message), str(error.value)
        assert isinstance(error.value, cstreams.InputError)
    assert ccd.toi(V0, V1) == toi


def test_close_pairs_and_candidates(context, funnel):
    V0, _, F, _ = funnel
    proximity = cstreams.MeshProximity(context, V0, F)
    dhat = 0.01
    pairs = proximity.close_pairs(V0, dhat)
    assert len(pairs) > 0
    assert set(pairs.dtype.names) == {"kind", "object_a", "object_b", "a", "b", "v", "type", "distance"}
    # Below dhat, or above by at most the rounding the documentation states (single
    # precision's, on a device without fp64), and the float the distance is stored in.
    assert (pairs["distance"] < (dhat + 2.0**-19 * np.abs(V0).max()) * (1 + 2.0**-23)).all()
    # A vertex-face pair's distance, recomputed here, within float rounding.
    vf = pairs[pairs["kind"] == 0][0]
    p, tri = V0[vf["v"][0]], V0[vf["v"][1:]]
    n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    assert vf["distance"] >= abs(np.dot(p - tri[0], n)) / np.linalg.norm(n) - 1e-6
    vf_candidates, ee_candidates = proximity.candidates(V0, dhat)
    assert vf_candidates.shape[1] == 2 and ee_candidates.shape[1] == 2
    assert len(vf_candidates) >= (pairs["kind"] == 0).sum()


def test_two_threads_on_two_contexts(funnel):
    V0, V1, F, _ = funnel
    expected = cstreams.MeshCcd(cstreams.Context(), V0, F).toi(V0, V1)
    results, errors = [], []

    def work():
        try:
            ccd = cstreams.MeshCcd(cstreams.Context(), V0, F)
            results.extend(ccd.toi(V0, V1) for _ in range(3))
        except Exception as e:  # reported below, with the thread's error
            errors.append(e)

    threads = [threading.Thread(target=work) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert results == [expected] * 6


def test_examples_run(funnel, tmp_path, capsys):
    import importlib.util
    import pathlib

    _, _, _, frames = funnel
    examples = pathlib.Path(__file__).parents[1] / "examples"
    for name, args in (("first_step", frames), ("plot_tolerance", [*frames, str(tmp_path / "t.png")])):
        spec = importlib.util.spec_from_file_location(name, examples / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        module.main(*args)
    assert "earliest  t = " in capsys.readouterr().out
    assert (tmp_path / "t.png").stat().st_size > 0


# erleben-cube-cliff-edges: float alone reports false contacts there that escalation to
# double removes, so the option must reach the solver.
@pytest.mark.parametrize("dataset,escalate", [("erleben-spike-hole", True), ("erleben-sliding-spike", True),
                                              ("erleben-cube-cliff-edges", True),
                                              ("erleben-cube-cliff-edges", False)])
def test_hand_made_queries_equal_the_cpp_accuracy(context, cli, data, tmp_path, dataset, escalate):
    folder = data / "sample-queries" / dataset
    subprocess.run([cli, "accuracy", "--queries", str(folder), "--solver", "conservative", "--precision", "single",
                    "--repeat", "1", "--json", str(tmp_path / "a.json")] + ([] if escalate else ["--no-escalation"]),
                   check=True, capture_output=True)
    expected = {r["kind"]: r for r in json.loads((tmp_path / "a.json").read_text())["results"]}
    solver = cstreams.QuerySolver(context, escalate=escalate)
    for kind, sub in (("vf", "vertex-face"), ("ee", "edge-edge")):
        answers, truth = [], []
        for path in sorted((folder / sub).glob("*.csv")):
            points, collides = cstreams.read_queries(str(path))
            answers.append(solver.solve(kind, points)[0])
            truth.append(collides)
        answers, truth = np.concatenate(answers), np.concatenate(truth)
        assert len(answers) == expected[kind]["queries"]
        assert int((truth & ~answers).sum()) == expected[kind]["false_negatives"] == 0
        assert int((~truth & answers).sum()) == expected[kind]["false_positives"]
        assert int(truth.sum()) == expected[kind]["positives"]


def test_rods_and_points(context):
    # A plate of two triangles, a rod of two segments above it and a free point.
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                  [0.1, 0.5, 0.1], [0.5, 0.5, 0.1], [0.9, 0.5, 0.1], [0.3, 0.3, 0.2]], dtype=np.float64)
    F = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    E = np.array([[4, 5], [5, 6]], dtype=np.int64)
    ccd = cstreams.MeshCcd(context, V, F, E=E)
    down = V.copy()
    down[4:, 2] -= 0.3
    assert 0.1 / 0.3 - 1e-4 <= ccd.toi(V, down) <= 0.1 / 0.3
    pairs = cstreams.MeshProximity(context, V, F, E=E).close_pairs(V, 0.15)
    assert len(pairs) > 0 and (pairs["b"] >= len(F)).any()  # pairs with the rod's or the point's faces
    with pytest.raises(ValueError, match="^E: "):
        cstreams.MeshCcd(context, V, F, E=np.array([[4, 99]]))


def test_detector_with_segments_and_points(context):
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                  [0.2, 0.5, 0.1], [0.8, 0.5, 0.1], [0.3, 0.3, 0.2]], dtype=np.float64)
    F = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    detector = cstreams.Detector(context, [dict(name="m", faces=F, positions=V, segments=np.array([[4, 5]]),
                                                points=[6])])
    end = V.copy()
    end[4:, 2] -= 0.3
    detector.set_positions(0, end)
    detector.detect()
    contacts = detector.contacts()
    # The rod's ends and the point reach the plate; the earliest, the rod's, at a third.
    assert 0.1 / 0.3 - 1e-4 <= detector.earliest_toi()[0] <= 0.1 / 0.3
    assert {4, 5, 6} <= set(int(c["v"][0]) for c in contacts if c["kind"] == 0)
    with pytest.raises(ValueError, match=r"^objects\[0\]\.points: entry 0 holds vertex 9"):
        cstreams.Detector(context, [dict(name="m", faces=F, positions=V, points=[9])])
