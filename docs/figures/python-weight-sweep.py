"""The paper's robustness analysis of the control weight from Python (docs/python.md): re-plan
examples/paper.toml for a4 from 0 to 10 and draw the best path's length L and number of segments
N against it, each point labelled with its form. Writes docs/figures/python-weight-sweep.svg.

Run from the repository's root, with the package and matplotlib installed in the venv:

    scripts/python-package
    target/python-env/bin/python -m pip install matplotlib
    target/python-env/bin/python docs/figures/python-weight-sweep.py
"""

import matplotlib

matplotlib.use("svg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import needle_planner as npl  # noqa: E402

paper = npl.Scenario.from_toml("examples/paper.toml")
a4 = np.linspace(0.0, 10.0, 21)
best = [npl.plan(paper.replace(weights={"control": float(w)})).best for w in a4]
length = np.array([b.length for b in best])
segments = np.array([b.control_degree for b in best])

# Reproducible SVG bytes: no date, fixed ids.
plt.rcParams["svg.hashsalt"] = "needle-planner"
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.8))
top.plot(a4, length, "o-", color="tab:blue")
for w, b in zip(a4, best):
    top.annotate(b.form, (w, b.length), textcoords="offset points", xytext=(0, 6),
                 ha="center", fontsize=7)
top.set_ylabel("L of the best path (mm)")
top.set_title("paper.toml: the best path as the control weight a4 grows")
bottom.step(a4, segments, where="mid", color="tab:orange")
bottom.set_yticks([1, 2, 3])
bottom.set_ylabel("N (segments)")
bottom.set_xlabel("a4, the weight of N in F = a1 L + a2 D + a3 H + a4 N")
fig.tight_layout()
fig.savefig("docs/figures/python-weight-sweep.svg", metadata={"Date": None})
for w, b in zip(a4, best):
    print(f"a4 = {w:4.1f}: {b.form:4} L = {b.length:6.2f} mm, N = {b.control_degree}")
