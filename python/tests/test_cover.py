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
