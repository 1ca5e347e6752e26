"""How much the Python package adds to planning: `plan(paper)` from Python against `needle
bench`'s median for the same scenario, measured side by side in one run (docs/python.md).

Build both in release first (from the repository's root):

    cargo build --release -p needle-cli
    target/python-env/bin/maturin build --release -m python/Cargo.toml -o target/wheels-release \
        -i target/python-env/bin/python
    target/python-env/bin/python -m pip install --force-reinstall --no-deps \
        target/wheels-release/needle_planner-*.whl
    target/python-env/bin/python python/examples/overhead.py [RUNS]
"""

import json
import statistics
import subprocess
import sys
import time

import needle_planner as npl

runs = int(sys.argv[1]) if len(sys.argv) > 1 else 200
paper = npl.Scenario.from_toml("examples/paper.toml")


def python_median(read_the_report: bool) -> float:
    def once():
        made = npl.plan(paper)
        if read_the_report:
            made.best.length  # parses the report

    for _ in range(3):
        once()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        once()
        times.append((time.perf_counter() - start) * 1e6)
    return statistics.median(times)


def bench_median() -> float:
    done = subprocess.run(
        ["target/release/needle", "bench", "examples/paper.toml", "--runs", str(runs), "--json"],
        capture_output=True, text=True, check=True,
    )
    return json.loads(done.stdout)[0]["median_us"]


# Interleaved, twice each, so that both see the same machine load.
python, read, bench = [], [], []
for _ in range(2):
    bench.append(bench_median())
    python.append(python_median(False))
    read.append(python_median(True))
b, p, r = min(bench), min(python), min(read)
print(f"needle bench examples/paper.toml (planner only): median {b:8.1f} us")
print(f"needle_planner.plan(paper):                      median {p:8.1f} us  ratio {p / b:.3f}")
print(f"needle_planner.plan(paper).best.length:          median {r:8.1f} us  ratio {r / b:.3f}")
