#!/usr/bin/env python3
"""The safe-default campaign of docs/execution.md ("Safe by default"): plain scenario files, as a
newcomer writes them (no `[execution]`, no bound, no `[steering]`), steered with
`needle simulate --closed-loop` in the default and the clinical world. The families are drawn
by `needle benchmark --generator unseen|planted --write-scenarios` from seeds nobody tuned on
(SEEDS x SCENARIOS: batches starting 7001, 7101, ... of consecutive seeds); the examples are
added with their set-up keys stripped (`planner.max_collision_probability`,
`planner.curvature_reserve`, `[execution]`, `[steering]`). Every run is judged on the true tip
and path (`summary.outcomes`); a scenario refused is counted with its reason.

usage: scripts/default-campaign.py NEEDLE OUTDIR RUNS [BATCHES] [SCENARIOS]
(the docs' figures: target/release/needle /tmp/defaults 8 5 50; run from the repository root)
Prints the markdown table; writes OUTDIR/table.json."""
import json, os, re, subprocess, sys
from concurrent.futures import ThreadPoolExecutor

needle, out, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
batches = int(sys.argv[4]) if len(sys.argv) > 4 else 5
per_batch = int(sys.argv[5]) if len(sys.argv) > 5 else 50
os.makedirs(out, exist_ok=True)
# The controller's default reach tolerance: a run reached when its true tip ends this close to
# where the target truly is.
REACH_MM = 1.0

def write_family(generator):
    files = []
    for b in range(batches):
        seed = 7001 + 100 * b
        d = os.path.join(out, f"{generator}-{seed}")
        if not os.path.isdir(d) or len(os.listdir(d)) < per_batch:
            subprocess.run([needle, "benchmark", "--generator", generator, "--seed", str(seed),
                            "--scenarios", str(per_batch), "--runs", "1", "--open-loop-only",
                            "--write-scenarios", d, "--threads", "1"],
                           check=True, capture_output=True)
        for f in sorted(os.listdir(d)):
            if f.endswith(".toml"):
                path = os.path.join(d, f)
                text = open(path).read()
                open(path, "w").write(strip(text))
                files.append(path)
    return files

def strip(text):
    """The scenario without its set-up keys: what a newcomer would have written."""
    text = re.sub(r"(?m)^(max_collision_probability|curvature_reserve)\s*=.*$", "", text)
    return re.sub(r"(?ms)^\[(execution|steering)\]\n.*?(?=^\[|\Z)", "", text)

def stripped_example(name):
    text = strip(open(os.path.join("examples", name + ".toml")).read())
    # Files the scenario names are relative to its folder: keep them found from OUTDIR.
    text = re.sub(r'(?m)^file = "(.*)"', lambda m: f'file = "{os.path.abspath(os.path.join("examples", m.group(1)))}"', text)
    path = os.path.join(out, f"stripped-{name}.toml")
    open(path, "w").write(text)
    return path

def ending(r):
    """How a run ended, judged here from its record, independently of the command's own
    `outcome` (so the script also judges a binary that has none): the true path, then the
    controller's stop, then the true tip against the reach tolerance."""
    if r["collided"]:
        return "collided"
    if r.get("stop_reason") not in (None, "missed"):
        return "stopped"
    return "reached" if r["target_error"] <= REACH_MM else "missed"

def simulate(path, world):
    cmd = [needle, "simulate", path, "--closed-loop", "--runs", str(runs), "--seed", "1",
           "--world", world, "--json", "--detail", "--threads", "1"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        lines = p.stderr.strip().splitlines()
        return {"file": path, "refused": lines[-1] if lines else "failed"}
    v = json.loads(p.stdout)
    outcomes = {k: 0 for k in ("reached", "missed", "collided", "stopped")}
    misses = []
    for r in v["runs_detail"]:
        outcomes[ending(r)] += 1
        if ending(r) == "missed":
            misses.append(r["target_error"])
        if "outcome" in r:
            assert r["outcome"] == ending(r), (path, r["seed"], r["outcome"])
    return {"file": path, "outcomes": outcomes, "misses": misses, "collisions": v["summary"]["collisions"],
            "error": v["summary"]["target_error"]["mean"]}

def row(name, files, world):
    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda f: simulate(f, world), files))
    done = [r for r in results if "outcomes" in r]
    refused = [r for r in results if "refused" in r]
    total = {k: sum(r["outcomes"][k] for r in done) for k in ("reached", "missed", "collided", "stopped")}
    n = sum(total.values())
    misses = sorted(m for r in done for m in r["misses"])
    reasons = {}
    for r in refused:
        reasons[r["refused"]] = reasons.get(r["refused"], 0) + 1
    return {"family": name, "world": world, "scenarios": len(files), "refused": len(refused),
            "refused_reasons": reasons, "runs": n, **total,
            "reached_percent": 100.0 * total["reached"] / n if n else 0.0,
            "collisions": sum(r["collisions"] for r in done),
            "missed_median_mm": misses[len(misses) // 2] if misses else None,
            "missed_under_1_5_mm": sum(m <= 1.5 for m in misses),
            "missed_max_mm": misses[-1] if misses else None,
            "mean_error": sum(r["error"] for r in done) / len(done) if done else None}

families = {"unseen": write_family("unseen"), "planted": write_family("planted"),
            "examples, stripped": [stripped_example(e) for e in
                                   ("paper", "space", "paper-clinical", "space-clinical", "anatomy")]}
rows = []
for name, files in families.items():
    for world in ("default", "clinical"):
        r = row(name, files, world)
        rows.append(r)
        print(json.dumps(r), flush=True)
json.dump(rows, open(os.path.join(out, "table.json"), "w"), indent=1)
print("\n| family | world | scenarios | refused | runs | reached | missed | collided | stopped | reached % |")
print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for r in rows:
    print(f"| {r['family']} | {r['world']} | {r['scenarios']} | {r['refused']} | {r['runs']} | {r['reached']} "
          f"| {r['missed']} | {r['collided']} | {r['stopped']} | {r['reached_percent']:.1f} |")
