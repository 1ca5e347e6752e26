"""cover() gives `needle cover --json`'s report for the same file and options, and the
command's message for a bad one."""

import pytest

import needle_planner as npl
from conftest import ROOT, needle_error, needle_json

MAP = ROOT / "examples" / "anatomy.seg.nrrd"


def test_cover_equals_the_command():
    got = npl.cover(MAP, segments=["rib"], margin=1.0)
    want = needle_json("cover", str(MAP), "--segments", "rib", "--margin", "1")
    assert got == want
    assert [s["name"] for s in got["segments"]] == ["rib"]
    assert got["spheres"] == len(got["segments"][0]["spheres"])


def test_cover_by_label_with_a_tightness():
    got = npl.cover(str(MAP), labels=[1, 2], tightness=2.5, max_spheres=64)
    want = needle_json("cover", str(MAP), "--labels", "1,2", "--tightness", "2.5", "--max-spheres", "64")
    assert got == want


def test_a_label_not_in_the_map_raises_the_commands_message():
    with pytest.raises(npl.ScenarioError) as raised:
        npl.cover(MAP, labels=[9])
    assert str(raised.value) == needle_error("cover", str(MAP), "--labels", "9")
    with pytest.raises(npl.ScenarioError) as raised:
        npl.cover(ROOT / "examples" / "paper.toml")
    assert "not a label map or mesh this reads" in str(raised.value)


def test_labels_and_segments_together_or_empty_are_refused():
    # Together they silently dropped the segments; an empty list covered everything.
    with pytest.raises(npl.ScenarioError) as raised:
        npl.cover(MAP, labels=[1], segments=["rib"])
    assert "labels and segments are both given" in str(raised.value)
    with pytest.raises(npl.ScenarioError) as raised:
        npl.cover(MAP, labels=[])
    assert "the labels list is empty" in str(raised.value)
    with pytest.raises(npl.ScenarioError) as raised:
        npl.cover(MAP, labels=[1, 1])
    assert "1 is given twice in labels" in str(raised.value)
    with pytest.raises(npl.ScenarioError) as raised:
        npl.cover(MAP, max_spheres=0)
    assert "at least 1, not 0" in str(raised.value)
    # Once an OverflowError from the conversion, not a NeedleError.
    with pytest.raises(npl.ScenarioError) as raised:
        npl.cover(MAP, max_spheres=-1)
    assert "at least 1, not -1" in str(raised.value)


def test_the_defaults_are_the_commands():
    # The wrapper's own defaults (32 spheres, tightness 3) once gave another cover than the
    # command's (512, 1.5).
    got = npl.cover(MAP, margin=1.0)
    want = needle_json("cover", str(MAP), "--margin", "1")
    assert got == want
