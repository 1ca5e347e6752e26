"""A 1000-run closed-loop Monte Carlo study of the paper's plan, in a few lines (docs/python.md).
Run from the repository's root: target/python-env/bin/python python/examples/monte_carlo.py"""

import time

import numpy as np

import needle_planner as npl

paper = npl.Scenario.from_toml("examples/paper.toml")
start = time.perf_counter()
sim = npl.simulate(paper, runs=1000, seed=1, closed_loop=True)
elapsed = time.perf_counter() - start
reached = np.array([reason is None for reason in sim.stop_reasons])
print(f"{sim.runs} closed-loop runs in {elapsed:.1f} s")
print(f"target error: median {np.median(sim.target_errors):.3f} mm, "
      f"95th percentile {np.percentile(sim.target_errors, 95, method='inverted_cdf'):.3f} mm "
      f"(summary: {sim.summary['target_error']['p95']:.3f} mm)")
print(f"collisions: {sim.collided.sum()} ({sim.collided.mean():.1%}), reached: {reached.mean():.1%}")
worst = int(np.argmax(sim.target_errors))
print(f"worst run: seed {sim.seeds[worst]}, {sim.target_errors[worst]:.3f} mm, "
      f"path of {len(sim.paths[worst])} points")
