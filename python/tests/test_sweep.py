"""sweep() gives `needle sweep --json`'s report for the same weight and range."""

import pytest

import needle_planner as npl
from conftest import ROOT, needle_error, needle_json

PAPER = ROOT / "examples" / "paper.toml"


def test_sweep_equals_the_command():
    scenario = npl.Scenario.from_toml(PAPER)
    got = npl.sweep(scenario, "control", 0, 10, steps=5, threads=2)
    want = needle_json("sweep", str(PAPER), "--weight", "control", "--from", "0", "--to", "10", "--steps", "5")
    assert got == want
    assert got["weight"] == "control" and len(got["points"]) == 5
    # The same on one thread, and by the weight's other name.
    assert npl.sweep(scenario, "a4", 0, 10, steps=5, threads=1) == want


def test_bad_weights_and_ranges_raise():
    scenario = npl.Scenario.from_toml(PAPER)
    with pytest.raises(npl.ScenarioError) as raised:
        npl.sweep(scenario, "speed", 0, 1)
    assert "'speed'" in str(raised.value)
    with pytest.raises(npl.NeedleError) as raised:
        npl.sweep(scenario, "risk", 0, 1, steps=5, log=True)
    assert str(raised.value) == needle_error(
        "sweep", str(PAPER), "--weight", "risk", "--from", "0", "--to", "1", "--steps", "5", "--log"
    )


@pytest.mark.parametrize("steps", [0, -1, 10**6])
def test_a_bad_step_count_is_a_scenario_error_with_the_commands_message(steps):
    scenario = npl.Scenario.from_toml(PAPER)
    with pytest.raises(npl.ScenarioError) as raised:
        npl.sweep(scenario, "control", 0, 10, steps=steps, threads=1)
    flag = str(max(steps, 0))
    assert str(raised.value) == needle_error(
        "sweep", str(PAPER), "--weight", "control", "--from", "0", "--to", "10", "--steps", flag
    )


def test_a_negative_thread_count_is_a_scenario_error():
    scenario = npl.Scenario.from_toml(PAPER)
    with pytest.raises(npl.ScenarioError, match="--threads"):
        npl.sweep(scenario, "control", 0, 10, steps=2, threads=-1)
