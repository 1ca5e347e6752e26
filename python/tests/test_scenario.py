"""Scenario: from a path, from text, from keywords; to_toml reads back to the same plan."""

import pathlib
import threading
import time

import pytest

import needle_planner as npl
from conftest import ROOT, needle_json


def report(scenario, **kwargs):
    made = npl.plan(scenario, **kwargs).to_dict()
    made["stats"].pop("time_us")
    return made


def test_path_text_and_keywords_give_the_same_plan():
    path = ROOT / "examples" / "paper.toml"
    from_path = npl.Scenario.from_toml(path)
    assert from_path.path == path and from_path.name == "paper"
    from_text = npl.Scenario.from_toml(path.read_text())
    assert from_text.path is None
    assert from_text.to_toml() == path.read_text()
    keywords = npl.Scenario(
        name="paper",
        needle={"curvature_radius": 63.7, "max_arc_deg": 180},
        entry={"position": [0, 0, 0], "direction": [0, 0, 1], "max_tilt_deg": 60},
        target={"position": [0, 0, 90], "tolerance": 0.1},
        obstacles=[
            {"center": c, "radius": r}
            for c, r in _paper_obstacles(path)
        ],
        weights={"length": 1, "risk": 1, "penalty": 1000, "control": 2},
        planner=_paper_planner(path),
        execution={"mode": "open_loop"},
    )
    expected = report(from_path)
    assert report(from_text) == expected
    assert report(keywords) == expected
    assert report(npl.Scenario.from_toml(keywords.to_toml())) == expected


def _paper_obstacles(path: pathlib.Path):
    import tomllib  # Python 3.11: the test venv's interpreter

    data = tomllib.loads(path.read_text())
    return [(o["center"], o["radius"]) for o in data["obstacles"]]


def _paper_planner(path: pathlib.Path):
    import tomllib

    return tomllib.loads(path.read_text()).get("planner", {})


def test_replace_changes_the_keys_given(tmp_path):
    paper = npl.Scenario.from_toml(ROOT / "examples" / "paper.toml")
    heavy = paper.replace(weights={"control": 10.0}, name="heavy")
    assert heavy.name == "heavy" and heavy.path is None
    written = tmp_path / "heavy.toml"
    written.write_text(heavy.to_toml())
    cli = needle_json("plan", str(written))
    assert report(heavy) == {**cli, "stats": {k: v for k, v in cli["stats"].items() if k != "time_us"}}
    # The other weights stay; control 10 makes one segment the best (the paper's Figure 8).
    assert npl.plan(heavy).best.control_degree == 1
    assert report(paper.replace(weights={"control": 2.0})) == report(paper)
    # None removes a key: the default (2) again.
    assert report(heavy.replace(weights={"control": None})) == report(paper)
    with pytest.raises(npl.ScenarioError, match="unknown field `colour`"):
        paper.replace(weights={"colour": 1.0})


def test_a_bad_source_is_a_scenario_error():
    try:
        npl.Scenario.from_toml(42)
    except npl.ScenarioError as e:
        assert "not from int" in str(e)
    else:
        raise AssertionError("an int read as a scenario")


def test_the_gil_is_released_while_simulating():
    """A Python thread keeps running while another simulates: the simulation does not hold the
    interpreter."""
    paper = npl.Scenario.from_toml(ROOT / "examples" / "paper.toml")
    done = threading.Event()

    def work():
        npl.simulate(paper, runs=300, seed=1, closed_loop=True, threads=1)
        done.set()

    worker = threading.Thread(target=work)
    start = time.perf_counter()
    worker.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    elapsed = time.perf_counter() - start
    # Held, the loop would tick only before and after the call; released, about once a ms.
    assert elapsed > 0.05, elapsed
    assert ticks > elapsed * 100, (ticks, elapsed)
