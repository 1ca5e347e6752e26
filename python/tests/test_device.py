"""Device: `needle info` and `needle send` from Python, against the simulated device hil-sim
(scripts/python-package builds it and names it in HIL_SIM_BIN)."""

import os
import pathlib
import socket
import subprocess

import pytest

import needle_planner as npl
from conftest import ROOT, needle_error, needle_json


@pytest.fixture(scope="module")
def device_address():
    binary = os.environ.get("HIL_SIM_BIN") or str(ROOT / "target" / "ci" / "hil-sim")
    assert pathlib.Path(binary).exists(), f"no hil-sim at {binary}: set HIL_SIM_BIN"
    server = subprocess.Popen(
        [binary, "--tcp", "127.0.0.1:0"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
        text=True,
    )
    try:
        address = server.stdout.readline().strip()
        assert address, "hil-sim printed no address"
        yield address
    finally:
        server.kill()
        server.wait()


def without_time(report: dict) -> dict:
    report = dict(report, stats=dict(report["stats"]))
    report["stats"].pop("time_us")
    return report


def test_info_is_the_commands(device_address):
    assert npl.Device(tcp=device_address).info() == needle_json("info", "--tcp", device_address)


# paper-bounded: planned on the device under its 1 % collision bound, figures checked here.
@pytest.mark.parametrize("name", ["paper", "space", "paper-bounded"])
def test_a_plan_on_the_device_is_the_commands_and_the_local_one(device_address, name):
    path = f"examples/{name}.toml"
    scenario = npl.Scenario.from_toml(ROOT / path)
    on_device = npl.Device(tcp=device_address).plan(scenario)
    sent = needle_json("send", path, "--tcp", device_address)
    assert without_time(on_device.to_dict()) == without_time(sent)
    assert without_time(on_device.to_dict()) == without_time(npl.plan(scenario).to_dict())


def test_no_device_is_a_device_error_with_the_commands_message():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        closed = f"127.0.0.1:{s.getsockname()[1]}"
    expected = needle_error("info", "--tcp", closed, "--deadline", "2")
    with pytest.raises(npl.DeviceError) as e:
        npl.Device(tcp=closed, deadline=2).info()
    assert str(e.value) == expected
    with pytest.raises(npl.DeviceError):
        npl.Device()
    with pytest.raises(npl.DeviceError, match="--deadline"):
        npl.Device(tcp=closed, deadline=-1)
