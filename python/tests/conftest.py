"""Shared fixtures: the repository's example scenarios and the `needle` binary the package's
numbers are checked against (scripts/python-package builds it and names it in NEEDLE_BIN)."""

import json
import os
import pathlib
import subprocess

import pytest

import needle_planner

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _needle_bin() -> pathlib.Path:
    named = os.environ.get("NEEDLE_BIN")
    if named:
        return pathlib.Path(named)
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    for profile in ("ci", "release", "debug"):
        candidate = target / profile / "needle"
        if candidate.exists():
            return candidate
    raise RuntimeError(
        "no needle binary: set NEEDLE_BIN or build it (cargo build --profile ci -p needle-cli)"
    )


def run_needle(*args: str, ok: bool = True) -> subprocess.CompletedProcess:
    """Runs `needle ARGS` from the repository's root; with `ok`, asserts that it succeeds."""
    done = subprocess.run(
        [str(_needle_bin()), *args], cwd=ROOT, capture_output=True, text=True, check=False
    )
    if ok:
        assert done.returncode == 0, done.stderr
    return done


def needle_json(*args: str) -> dict:
    """What `needle ARGS --json` prints, parsed."""
    return json.loads(run_needle(*args, "--json").stdout)


def needle_error(*args: str) -> str:
    """The message `needle ARGS` fails with (its stderr without `error: `)."""
    done = run_needle(*args, ok=False)
    assert done.returncode == 1, (done.returncode, done.stderr)
    text = done.stderr.strip()
    assert text.startswith("error: "), text
    return text[len("error: "):]


@pytest.fixture(scope="session")
def examples() -> pathlib.Path:
    return ROOT / "examples"


@pytest.fixture(scope="session", autouse=True)
def installed_package():
    """The tests check the installed wheel, not the source tree (which has no native module)."""
    assert "site-packages" in needle_planner.__file__, needle_planner.__file__
