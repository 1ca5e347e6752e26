"""simulate() gives `needle simulate --json`'s output bit for bit, and every run as arrays."""

import numpy as np
import pytest

import needle_planner as npl
from conftest import ROOT, needle_json


@pytest.fixture(scope="module")
def paper():
    return npl.Scenario.from_toml(ROOT / "examples" / "paper.toml")


@pytest.mark.parametrize("closed_loop", [False, True])
def test_seeded_simulation_equals_the_command(paper, closed_loop):
    flags = ["--closed-loop"] if closed_loop else []
    sim = npl.simulate(paper, runs=20, seed=7, closed_loop=closed_loop)
    cli = needle_json("simulate", "examples/paper.toml", "--runs", "20", "--seed", "7", *flags)
    assert sim.to_dict() == cli
    assert sim.summary == cli["summary"]
    assert sim.plan["form"] == "RL" and sim.plan == cli["plan"]
    # Every run as the command's --detail prints it (its f32 figures, widened exactly).
    detail = needle_json(
        "simulate", "examples/paper.toml", "--runs", "20", "--seed", "7", "--detail", *flags
    )["runs_detail"]
    f32 = lambda key: np.array([r[key] for r in detail], dtype=np.float32)  # noqa: E731
    assert np.array_equal(sim.seeds, [r["seed"] for r in detail])
    assert np.array_equal(sim.target_errors.astype(np.float32), f32("target_error"))
    assert np.array_equal(sim.path_deviations.astype(np.float32), f32("path_rms"))
    assert np.array_equal(sim.path_max_deviations.astype(np.float32), f32("path_max"))
    assert np.array_equal(sim.collided, [r["collided"] for r in detail])
    assert sim.collided.dtype == np.bool_
    for path, run in zip(sim.paths, detail):
        assert np.array_equal(path.astype(np.float32), np.array(run["points"], dtype=np.float32))
    if closed_loop:
        assert sim.stop_reasons == [r["stop_reason"] for r in detail]


def test_perturbation_faults_and_steering_are_the_flags(paper):
    sim = npl.simulate(
        paper,
        runs=8,
        seed=3,
        closed_loop=True,
        perturb={"curvature_spread": 0.1},
        faults={"dropout_rate": 0.01},
        steer={"tracker_position_mm": 0.2},
        threads=1,
    )
    cli = needle_json(
        "simulate", "examples/paper.toml", "--runs", "8", "--seed", "3", "--closed-loop",
        "--perturb", "curvature_spread=0.1", "--fault", "dropout_rate=0.01",
        "--steer", "tracker_position_mm=0.2",
    )
    assert sim.to_dict() == cli


def test_runs_do_not_depend_on_the_thread_count(paper):
    one = npl.simulate(paper, runs=12, seed=5, threads=1)
    two = npl.simulate(paper, runs=12, seed=5, threads=2)
    assert one.json == two.json
    assert np.array_equal(one.target_errors, two.target_errors)


def test_a_thousand_runs_come_back_as_arrays(paper):
    sim = npl.simulate(paper, runs=1000, seed=1)
    assert sim.target_errors.shape == (1000,)
    assert sim.collided.shape == (1000,)
    assert len(sim.paths) == 1000 and sim.paths[0].shape[1] == 3
    assert int(sim.collided.sum()) == sim.summary["collisions"]
    assert sim.target_errors.max() == pytest.approx(sim.summary["target_error"]["max"], abs=0)


@pytest.mark.parametrize("world", ["clinical", "default"])
def test_a_named_world_equals_the_command(paper, world):
    sim = npl.simulate(paper, runs=6, seed=2, closed_loop=True, world=world, threads=1)
    cli = needle_json(
        "simulate", "examples/paper.toml", "--runs", "6", "--seed", "2", "--closed-loop",
        "--world", world,
    )
    assert sim.to_dict() == cli
    assert sim.to_dict()["world"]["tracker_dof"] == (5 if world == "clinical" else 6)


def test_the_clinical_world_changed_by_perturb_and_faults_equals_the_command(paper):
    sim = npl.simulate(
        paper,
        runs=4,
        seed=9,
        closed_loop=True,
        world="clinical",
        perturb={"layers": 0},
        faults={"dropout_rate": 0},
        compare_open_loop=True,
    )
    cli = needle_json(
        "simulate", "examples/paper.toml", "--runs", "4", "--seed", "9", "--closed-loop",
        "--world", "clinical", "--perturb", "layers=0", "--fault", "dropout_rate=0",
        "--compare-open-loop",
    )
    assert sim.to_dict() == cli


def test_none_is_the_scenarios_world(tmp_path):
    text = (ROOT / "examples" / "paper.toml").read_text()
    path = tmp_path / "clinical.toml"
    # Into the example's own [execution] table: TOML refuses a second.
    path.write_text(text.replace("[execution]\n", '[execution]\nworld = "clinical"\n', 1))
    scenario = npl.Scenario.from_toml(str(path))
    sim = npl.simulate(scenario, runs=3, seed=1)
    cli = needle_json("simulate", str(path), "--runs", "3", "--seed", "1")
    assert sim.to_dict() == cli
    assert sim.to_dict()["world"]["layers"] == 3
    replaced = npl.simulate(scenario, runs=3, seed=1, world="default")
    assert replaced.to_dict() == needle_json(
        "simulate", str(path), "--runs", "3", "--seed", "1", "--world", "default"
    )
