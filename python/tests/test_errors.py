"""Bad input raises a typed exception carrying the command's message, and nothing reaches the
interpreter as a panic (a pyo3 PanicException is a BaseException: these tests would error)."""

import math

import numpy as np
import pytest

import needle_planner as npl
from conftest import ROOT, needle_error

HEAD = """name = "probe"
[needle]
curvature_radius = 63.7
[entry]
position = [0.0, 0.0, 0.0]
direction = [0.0, 0.0, 1.0]
[target]
position = [0.0, 30.0, 90.0]
"""

# (what is wrong, the file's text, the same scenario as keywords)
BAD_SCENARIOS = [
    (
        "wrong key",
        HEAD + "[weight]\nlength = 1.0\n",
        {"weight": {"length": 1.0}},
    ),
    (
        "wrong type",
        HEAD.replace("63.7", '"wide"'),
        {"needle": {"curvature_radius": "wide"}},
    ),
    (
        "NaN",
        HEAD.replace("63.7", "nan"),
        {"needle": {"curvature_radius": math.nan}},
    ),
    (
        "array of the wrong shape",
        HEAD.replace("position = [0.0, 30.0, 90.0]", "position = [30.0, 90.0]"),
        {"target": {"position": np.array([30.0, 90.0])}},
    ),
    (
        "nested array",
        HEAD.replace("position = [0.0, 30.0, 90.0]", "position = [[0.0, 30.0, 90.0]]"),
        {"target": {"position": np.array([[0.0, 30.0, 90.0]])}},
    ),
    (
        "negative radius",
        HEAD + "[[obstacles]]\ncenter = [0.0, 15.0, 45.0]\nradius = -6.0\n",
        {"obstacles": [{"center": [0.0, 15.0, 45.0], "radius": -6.0}]},
    ),
]

PAPER_KEYWORDS = {
    "needle": {"curvature_radius": 63.7},
    "entry": {"position": [0.0, 0.0, 0.0], "direction": [0.0, 0.0, 1.0]},
    "target": {"position": [0.0, 30.0, 90.0]},
}


def keywords(changes):
    tables = {k: dict(v) for k, v in PAPER_KEYWORDS.items()}
    for table, value in changes.items():
        if isinstance(value, dict) and table in tables:
            tables[table].update(value)
        else:
            tables[table] = value
    return tables


@pytest.mark.parametrize("what,text,changes", BAD_SCENARIOS, ids=[b[0] for b in BAD_SCENARIOS])
def test_a_bad_scenario_is_a_scenario_error_with_the_commands_message(
    tmp_path, what, text, changes
):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    expected = needle_error("plan", str(path))
    with pytest.raises(npl.ScenarioError) as from_file:
        npl.Scenario.from_toml(str(path))
    assert str(from_file.value) == expected
    with pytest.raises(npl.ScenarioError) as from_text:
        npl.Scenario.from_toml(text)
    assert expected.endswith(str(from_text.value).splitlines()[-1])
    # Keywords are written as a file would be: the same reason (its last line; the position in
    # the text differs).
    with pytest.raises(npl.ScenarioError) as from_keywords:
        npl.Scenario(**keywords(changes))
    assert expected.endswith(str(from_keywords.value).splitlines()[-1])
    assert isinstance(from_keywords.value, npl.NeedleError)


def test_a_missing_file_is_the_commands_message():
    expected = needle_error("plan", "no/such.toml")
    with pytest.raises(npl.ScenarioError, match="cannot read scenario") as e:
        npl.Scenario.from_toml("no/such.toml")
    assert str(e.value) == expected


@pytest.fixture(scope="module")
def paper():
    return npl.Scenario.from_toml(ROOT / "examples" / "paper.toml")


@pytest.mark.parametrize(
    "kwargs,flags",
    [
        ({"perturb": {"curvature_spread": math.nan}}, ["--perturb", "curvature_spread=nan"]),
        ({"perturb": {"curvature_spread": -1}}, ["--perturb", "curvature_spread=-1"]),
        ({"perturb": {"no_such_key": 1}}, ["--perturb", "no_such_key=1"]),
        ({"perturb": {"curvature_spread": [1, 2]}}, ["--perturb", "curvature_spread=[1, 2]"]),
        ({"runs": 0}, ["--runs", "0"]),
        ({"runs": 10**12}, ["--runs", str(10**12)]),
        ({"form": "LL"}, ["--form", "LL"]),
        ({"world": "mars"}, ["--world", "mars"]),
        ({"world": " "}, ["--world", " "]),
        (
            {"world": "clinical", "perturb": {"layers": 9}},
            ["--world", "clinical", "--perturb", "layers=9"],
        ),
        (
            {"closed_loop": True, "faults": {"dropout_rate": 2}},
            ["--closed-loop", "--fault", "dropout_rate=2"],
        ),
        (
            {"closed_loop": True, "steer": {"tracker_position_mm": "x"}},
            ["--closed-loop", "--steer", "tracker_position_mm=x"],
        ),
    ],
)
def test_bad_simulation_options_carry_the_commands_message(paper, kwargs, flags):
    runs = [] if "--runs" in flags else ["--runs", "2"]
    expected = needle_error("simulate", "examples/paper.toml", *runs, *flags)
    with pytest.raises(npl.ScenarioError) as e:
        npl.simulate(paper, **{"runs": 2, **kwargs})
    assert str(e.value) == expected


def test_no_feasible_form_is_a_plan_error_holding_the_report(paper):
    expected = needle_error("plan", "examples/paper.toml", "--forms", "L")
    with pytest.raises(npl.PlanError) as e:
        npl.plan(paper, forms=["L"])
    assert str(e.value) == expected
    assert e.value.plan.best is None and e.value.plan.forms[0].form == "L"


def test_bad_plan_options_are_scenario_errors(paper):
    expected = needle_error("plan", "examples/paper.toml", "--forms", "LL")
    with pytest.raises(npl.ScenarioError) as e:
        npl.plan(paper, forms=["LL"])
    assert str(e.value) == expected
    with pytest.raises(npl.ScenarioError, match="--max-degree"):
        npl.plan(paper, max_degree=300)
    with pytest.raises(npl.ScenarioError):
        npl.plan(paper, forms=[1, 2])


NASTY = [math.nan, math.inf, -math.inf, 0.0, -0.0, 1e38, -1e38, 1e-45, 2**70, -1]


@pytest.mark.parametrize("value", NASTY, ids=repr)
def test_no_value_anywhere_panics(value):
    """Every number of a scenario and of a simulation's options set to an extreme: each call
    returns or raises a NeedleError, never anything else."""
    slots = [
        ("needle", "curvature_radius"), ("needle", "max_arc_deg"), ("needle", "length"),
        ("needle", "max_line_length"), ("entry", "max_tilt_deg"), ("target", "tolerance"),
        ("weights", "length"), ("weights", "control"), ("planner", "min_clearance"),
        ("planner", "curvature_reserve"), ("planner", "max_collision_probability"),
        ("planner", "max_control_degree"), ("driver", "insert_speed"),
        ("driver", "max_twist_deg"), ("execution", "curvature_spread"),
        ("steering", "tracker_position_mm"),
    ]
    for table, key in slots:
        tables = keywords({table: {key: value}})
        tables["planner"] = {**tables.get("planner", {}), "max_control_degree": 2,
                             **({key: value} if table == "planner" else {})}
        try:
            s = npl.Scenario(**tables)
            npl.plan(s)
            npl.simulate(s, runs=2, closed_loop=True, threads=1)
        except npl.NeedleError:
            pass
    for vector in [[value, 0, 1], [0, 0, value]]:
        for table in ("entry", "target"):
            key = "direction" if table == "entry" else "position"
            try:
                npl.plan(npl.Scenario(**keywords({table: {key: vector}})))
            except npl.NeedleError:
                pass
    paper = npl.Scenario(**keywords({}))
    for key in ("curvature_spread", "insertion_error_mm", "measure_every_mm", "target_shift_mm"):
        try:
            npl.simulate(paper, runs=2, closed_loop=True, perturb={key: value}, threads=1)
        except npl.NeedleError:
            pass
