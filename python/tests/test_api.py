"""The Python API against the command line it binds: same reports, same sweep records, gradients
against central differences, errors with the CLI's messages, the same numbers for any thread
count. Run from the repository root's `python/` (see `python/test.sh`)."""

import json
import os
import signal
import subprocess
import tempfile
import threading
import time

import numpy as np
import pytest

import proving_ground as pg

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def target_dir():
    """Cargo's target folder (target/, or CARGO_TARGET_DIR's), as cargo says."""
    done = subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps", "--offline"],
                          cwd=REPO, capture_output=True, text=True, check=True)
    return json.loads(done.stdout)["target_directory"]


BINARY = os.path.join(target_dir(), "release", "validate-design")
TASK = "scenarios/cluttered/task-03.json"


def repo(path):
    return os.path.join(REPO, path)


def cli(*args):
    """Runs validate-design in the repository; its exit code must be one of a finished run's."""
    done = subprocess.run([BINARY, *args], cwd=REPO, capture_output=True, text=True)
    assert done.returncode in (0, 1, 3), done.stderr
    return done


@pytest.fixture(autouse=True)
def in_repo(monkeypatch):
    monkeypatch.chdir(REPO)


def test_validate_gives_the_cli_json_report():
    with tempfile.TemporaryDirectory() as out:
        report = os.path.join(out, "r.json")
        cli("designs/free-offset-6dof.json", "--scenario", TASK, "--engines", "mujoco", "--ik-seeds", "6",
            "--tolerance", "z_symmetric", "--mujoco-checks", "10", "--json", report, "--quiet")
        with open(report, encoding="utf-8") as f:
            expected = json.load(f)
    got = pg.validate("designs/free-offset-6dof.json", TASK, engines="mujoco", ik_seeds=6,
                      tolerance="z_symmetric", mujoco_checks=10)
    assert got == expected


def test_a_design_given_as_a_dict_is_the_file_it_would_be():
    with open(repo("designs/economic-elbow.json"), encoding="utf-8") as f:
        data = json.load(f)
    from_file = pg.validate("designs/economic-elbow.json", TASK, reach_only=True, mujoco_checks=0)
    from_dict = pg.validate(pg.Design.from_dict(data), pg.Scenario.load(TASK), reach_only=True, mujoco_checks=0)
    assert from_dict["goals"] == from_file["goals"]
    assert from_dict["verdict"] == from_file["verdict"]


def test_reach_gives_the_records_sweep_writes():
    designs = ["designs/ur5e.json", "designs/economic-elbow.json", "designs/modular-elbow.json"]
    with tempfile.TemporaryDirectory() as out:
        cli("sweep", *designs, "--scenarios", TASK, "--out", os.path.join(out, "s"), "--quiet")
        with open(os.path.join(out, "s", "results.jsonl"), encoding="utf-8") as f:
            expected = [json.loads(line) for line in f]
    got = pg.reach(designs, TASK)
    assert got["records"] == expected
    assert list(got["solved"]) == [r["goals_solved"] for r in expected]
    assert np.allclose(got["task_loss"], [r["task_loss"] for r in expected])


def test_reach_is_the_same_for_any_thread_count_and_takes_dh_arrays():
    rows = np.array([
        [[0.3, 0.0, np.pi / 2], [0.0, 0.4, 0.0], [0.0, 0.35, 0.0], [0.1, 0.0, np.pi / 2], [0.1, 0.0, -np.pi / 2], [0.1, 0.0, 0.0]],
        [[0.2, 0.0, np.pi / 2], [0.0, 0.5, 0.0], [0.0, 0.3, 0.0], [0.1, 0.0, np.pi / 2], [0.1, 0.0, -np.pi / 2], [0.1, 0.0, 0.0]],
    ])
    one = pg.reach(rows, TASK, threads=1)
    two = pg.reach(rows, TASK, threads=2)
    assert one["records"] == two["records"]
    assert one["goals"].tolist() == [8, 8]
    assert np.allclose(one["hardware_cost"], np.abs(rows[:, :, :2]).sum(axis=(1, 2)))


def test_ctrl_c_stops_a_long_batch():
    # 600 designs take several seconds; a SIGINT 0.3 s in must raise KeyboardInterrupt long before.
    rng = np.random.default_rng(1)
    rows = np.zeros((600, 6, 3))
    rows[:, :, 0] = rng.choice([0.0, 0.1, 0.2, 0.3], size=(600, 6))
    rows[:, :, 1] = rng.choice([0.0, 0.2, 0.3, 0.4], size=(600, 6))
    rows[:, :, 2] = rng.choice([0.0, np.pi / 2, -np.pi / 2], size=(600, 6))
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        pg.reach(rows, TASK)
    stopped = time.perf_counter() - start
    whole = pg.reach(rows[:60], TASK)
    assert len(whole["records"]) == 60
    # The designs already started finish: well under the whole batch, which is ten times this.
    assert stopped < 1.0 + 0.5 * (time.perf_counter() - start - stopped), stopped


def test_ctrl_c_stops_a_long_validation():
    # A mesh robot with detours planned on a cluttered task: seconds of IK and planning. A SIGINT
    # 0.3 s in stops it at the next goal.
    urdf = repo("tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf")
    task = repo("scenarios/cluttered/task-00.json")
    start = time.perf_counter()
    whole = pg.validate(urdf, task, engines="none")
    took = time.perf_counter() - start
    assert whole["trajectory"]["reached"] >= 1
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        pg.validate(urdf, task, engines="none")
    stopped = time.perf_counter() - start
    assert stopped < 0.5 * took, (stopped, took)


def test_gradients_match_central_differences():
    design = pg.Design.load("designs/free-offset-6dof.json")
    rng = np.random.default_rng(3)
    q = rng.uniform(-2.0, 2.0, size=(8, 6))
    out = pg.loss_and_grad(design, TASK, q)
    assert out["loss"].shape == (8,) and out["grad_q"].shape == (8, 6)
    step = 1e-6
    for b in range(8):
        for j in range(6):
            plus, minus = q.copy(), q.copy()
            plus[b, j] += step
            minus[b, j] -= step
            numeric = (pg.loss_and_grad(design, TASK, plus)["loss"][b] - pg.loss_and_grad(design, TASK, minus)["loss"][b]) / (2 * step)
            assert abs(numeric - out["grad_q"][b, j]) <= 1e-5 * max(1.0, abs(numeric)), (b, j, numeric, out["grad_q"][b, j])
    with open(repo("designs/free-offset-6dof.json"), encoding="utf-8") as f:
        data = json.load(f)
    for j in range(6):
        for key, grad in (("d", "grad_d"), ("a", "grad_a")):
            if data["joints"][j][key] == 0:
                continue  # a zero offset decides the capsule structure; it does not move
            plus, minus = json.loads(json.dumps(data)), json.loads(json.dumps(data))
            plus["joints"][j][key] += step
            minus["joints"][j][key] -= step
            numeric = (pg.loss_and_grad(plus, TASK, q)["loss"] - pg.loss_and_grad(minus, TASK, q)["loss"]) / (2 * step)
            assert np.allclose(numeric, out[grad][:, j], rtol=1e-5, atol=1e-5), (key, j)


def test_bad_inputs_raise_with_the_cli_message():
    with pytest.raises(pg.ProvingGroundError, match=r"bad.json: invalid type: string \"x\", expected f64 at line \d+"):
        pg.validate({"name": "bad", "mode": "free", "joints": [{"d": 0.1, "a": 0.2, "alpha": 0}, {"d": "x", "a": 0, "alpha": 0}]}, TASK)
    with pytest.raises(pg.ProvingGroundError, match=r"bad.json: joints\[1\]\.limits"):
        pg.validate({"name": "bad", "mode": "free", "joints": [{"d": 0.1, "a": 0.2, "alpha": 0}, {"d": 0, "a": 0.1, "alpha": 0, "limits": [1, -1]}]}, TASK)
    with pytest.raises(pg.ProvingGroundError, match="no_such.json"):
        pg.validate("designs/no_such.json", TASK)
    with pytest.raises(pg.ProvingGroundError, match="unknown field `ik_seed`"):
        pg.validate("designs/ur5e.json", TASK, ik_seed=3)
    with pytest.raises(pg.ProvingGroundError, match="ik_seeds"):
        pg.validate("designs/ur5e.json", TASK, ik_seeds=0)
    with pytest.raises(pg.ProvingGroundError, match="unknown engine `bullet`"):
        pg.validate("designs/ur5e.json", TASK, engines="bullet")
    with pytest.raises(pg.ProvingGroundError, match="goals"):
        pg.reach(["designs/ur5e.json"], {"name": "empty", "goals": []})
    with pytest.raises(pg.ProvingGroundError, match="q has shape"):
        pg.loss_and_grad("designs/ur5e.json", TASK, np.zeros((3, 6)))


def test_inputs_without_files():
    scenario = pg.Scenario.generate("cluttered", task=3)
    with open(repo(TASK), encoding="utf-8") as f:
        assert scenario.data == json.load(f)
    ids = pg.catalog("modular6")
    assert len(ids) == 15625 and ids[0].startswith("modular6/")
    design = pg.catalog_design(7)
    assert design.data["name"] == ids[7]
    assert pg.reach([design], scenario)["goals"].tolist() == [8]


def test_the_readme_example_runs(capsys):
    with open(repo("README.md"), encoding="utf-8") as f:
        readme = f.read()
    section = readme[readme.index("## From Python"):]
    start = section.index("```python\n") + len("```python\n")
    example = section[start:section.index("```", start)]
    exec(compile(example, "README.md", "exec"), {})
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] in ("PASS", "FAIL", "UNDECIDED")
    assert printed[1].startswith("[")


def test_the_design_objective_is_the_least_loss_per_goal_plus_the_hardware_cost():
    design = pg.Design.load("designs/free-offset-6dof.json")
    rng = np.random.default_rng(5)
    starts = 3
    q = rng.uniform(-2.0, 2.0, size=(8 * starts, 6))
    samples = [(0, g) for g in range(8) for _ in range(starts)]
    out = pg.loss_and_grad(design, TASK, q, samples)
    with open(repo("designs/free-offset-6dof.json"), encoding="utf-8") as f:
        data = json.load(f)
    hardware = 0.1 * sum(abs(j["d"]) + abs(j["a"]) for j in data["joints"])
    least = out["loss"].reshape(8, starts).min(axis=1).sum()
    assert out["objective"][0] == pytest.approx(least + hardware, rel=1e-12)
    assert out["chosen"].sum() == 8
    step = 1e-6
    for j in range(6):
        if data["joints"][j]["a"] == 0:
            continue
        plus, minus = json.loads(json.dumps(data)), json.loads(json.dumps(data))
        plus["joints"][j]["a"] += step
        minus["joints"][j]["a"] -= step
        numeric = (pg.loss_and_grad(plus, TASK, q, samples)["objective"][0] - pg.loss_and_grad(minus, TASK, q, samples)["objective"][0]) / (2 * step)
        assert numeric == pytest.approx(out["objective_grad_a"][0, j], rel=1e-5, abs=1e-5), j


def test_mujoco_comes_from_the_installed_package_not_the_checkout():
    # The module runs MuJoCo from the `mujoco` package pip installed beside it, so it keeps
    # working when the checkout it was built in moves or is deleted.
    library = os.environ.get("MUJOCO_LIBRARY", "")
    import mujoco

    assert os.path.dirname(library) == os.path.dirname(mujoco.__file__), library
    assert not library.startswith(REPO + os.sep), library
    report = pg.validate(repo("designs/paper-real-world.json"), engines="mujoco")
    assert report["verdict"]["passed"], report["verdict"]
    assert [e["engine"] for e in report["engines"]] == ["mujoco"]
