#!/usr/bin/env python3
"""The clinical-world campaign of docs/journal/2026-12-05.md
("The controller in the clinical world"):
`needle simulate --closed-loop` in today's world, the clinical world (as is, and with the
controller told the push), the floor that bias and registration alone leave, and twice the
clinical world, on the two examples as they are and as a lab sets them up (examples/*-clinical.toml:
a 1 % collision bound for the closed loop, and the tracker's hidden error told to the steering),
and on 20 planted scenarios (seeds 201..220, written by `needle benchmark --generator planted
--write-scenarios`, each planned for steering under a 1 % collision bound; then the same with the
examples' `[steering]` and curvature reserve added, and the unseen family 301..320 so). Each row also counts the runs
within the tissue's reach (`summary.within_reach`: the world's full curvature turned at the target
from the entry comes within the reach tolerance) and the share of those reached. Prints one JSON line per row, then the markdown table; writes OUTDIR/table.json.

usage: scripts/clinical-campaign.py NEEDLE OUTDIR RUNS_PER_EXAMPLE RUNS_PER_GENERATED
(the docs' figures: target/release/needle /tmp/clinical 1000 50; run from the repository root)"""
import json, subprocess, sys, os, statistics

needle, out, n_ex, n_gen = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
LAB = ["--steer", "target_speed_walk=0.02"]
WORLDS = {
    "default": ["--world", "default"],
    "clinical": ["--world", "clinical"],
    "clinical, lab-told": ["--world", "clinical"] + LAB,
    "floor: bias + registration alone": ["--perturb", "tracker_bias_mm=0.3", "--perturb", "registration_error_mm=0.29"],
    "clinical x2, lab-told": ["--world", "clinical", "--perturb", "tracker_bias_mm=0.6", "--perturb", "registration_error_mm=0.58",
        "--perturb", "layer_curvature_spread=0.4", "--perturb", "puncture_mm=2", "--perturb", "target_push_mm=4",
        "--perturb", "tracker_latency_ms=60", "--perturb", "target_imaging_delay_ms=100",
        "--perturb", "curvature_spread=0.06", "--perturb", "segment_curvature_spread=0.02",
        "--perturb", "torsion_lag_deg_per_mm=0.4", "--perturb", "line_drift_mm_per_mm=0.04",
        "--perturb", "insertion_error_mm=0.6", "--perturb", "entry_position_mm=0.4",
        "--perturb", "entry_direction_deg=1.0", "--perturb", "target_shift_mm=1.0",
        "--perturb", "tracker_position_mm=1.0", "--perturb", "tracker_heading_deg=1.0",
        "--fault", "dropout_rate=0.02", "--fault", "dropout_mm=4"] + LAB,
}

def run(path, runs, args):
    cmd = [needle, "simulate", path, "--closed-loop", "--runs", str(runs), "--seed", "1",
           "--json", "--detail", "--threads", "2"] + args
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1] if p.stderr.strip() else "failed"
    d = json.loads(p.stdout)
    return d, None

def row(name, results):
    errs, reached, coll, runs, stops, reached_errs = [], 0, 0, 0, {}, []
    for d in results:
        for r in d["runs_detail"]:
            runs += 1
            if r.get("stop_reason"):
                stops[r["stop_reason"]] = stops.get(r["stop_reason"], 0) + 1
            else:
                reached += 1
                reached_errs.append(r["target_error"])
            coll += 1 if r.get("collided") or (r.get("min_clearance", 1) < 0) else 0
            errs.append(r["target_error"])
        # collisions from the summary are authoritative
    coll = sum(d["summary"]["collisions"] for d in results)
    within = sum(d["summary"]["within_reach"] for d in results)
    reached_within = sum(d["summary"]["reached_within_reach"] for d in results)
    errs.sort()
    reached_errs.sort()
    p95 = errs[int(0.95 * (len(errs) - 1))] if errs else float("nan")
    mean = statistics.fmean(errs) if errs else float("nan")
    return {"world": name, "runs": runs, "reached_pct": 100 * reached / max(runs, 1), "collisions": coll,
            "mean": mean, "p95": p95, "max": errs[-1] if errs else float("nan"), "stops": stops,
            "within_reach": within, "reached_of_within_pct": 100 * reached_within / max(within, 1),
            "reached_mean": statistics.fmean(reached_errs) if reached_errs else float("nan"),
            "reached_p95": reached_errs[int(0.95 * (len(reached_errs) - 1))] if reached_errs else float("nan")}

LAB_STEERING = "\n[steering]\nregistration_mm = 0.42\ntarget_speed_walk = 0.02\ncurvature_walk = 0.02\n"
# The curvature reserve the clinical examples ask for (layered tissue: more curvature in hand).
LAB_RESERVE = "curvature_reserve = 0.4\n"

def write_generated(gen, steering="", seed=201, reserve=""):
    """The planted family of `seed`, each scenario planned for steering under a 1 % collision bound (and
    `steering` appended: what the lab tells the closed loop; `reserve` added to `[planner]`)."""
    os.makedirs(gen, exist_ok=True)
    subprocess.run([needle, "benchmark", "--generator", "planted", "--scenarios", "20", "--seed", str(seed),
                    "--runs", "1", "--open-loop-only", "--write-scenarios", gen],
                   check=True, capture_output=True)
    for f in os.listdir(gen):
        path = os.path.join(gen, f)
        s = open(path).read()
        if "max_collision_probability" not in s:
            s = s.replace("[planner]\n", "[planner]\nmax_collision_probability = 0.01\n" + reserve, 1)
            s += '\n[execution]\nmode = "closed_loop"\n' + steering
            open(path, "w").write(s)

os.makedirs(out, exist_ok=True)
write_generated(f"{out}/gen")
write_generated(f"{out}/gen-lab", LAB_STEERING, reserve=LAB_RESERVE)
write_generated(f"{out}/gen-lab-301", LAB_STEERING, 301, LAB_RESERVE)
table = []
for ex in ["examples/paper.toml", "examples/space.toml", "examples/paper-clinical.toml",
           "examples/space-clinical.toml"]:
    for name, args in WORLDS.items():
        d, err = run(ex, n_ex, args)
        r = row(name, [d] if d else [])
        r["scenario"] = os.path.basename(ex)
        table.append(r)
        print(json.dumps(r), flush=True)
def family_rows(family, label):
    gen = sorted(f for f in os.listdir(f"{out}/{family}") if f.endswith(".toml"))
    for name, args in WORLDS.items():
        results, refused = [], []
        for f in gen:
            d, err = run(f"{out}/{family}/{f}", n_gen, args)
            if d:
                results.append(d)
            else:
                refused.append((f, err))
        r = row(name, results)
        r["scenario"] = f"{label} ({len(results)} steered, {len(refused)} refused)"
        r["refused"] = refused
        table.append(r)
        print(json.dumps(r), flush=True)

family_rows("gen", "planted 201-220")
family_rows("gen-lab", "planted 201-220, lab-set")
family_rows("gen-lab-301", "planted 301-320 (unseen), lab-set")
json.dump(table, open(f"{out}/table.json", "w"), indent=1)
print()
print("| scenario | world | runs | reached | within the tissue's reach | reached of those | collisions "
      "| mean | p95 | max | reached runs: mean / p95 | stops |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for r in table:
    stops = ", ".join(f"{k} {v}" for k, v in sorted(r["stops"].items())) or "none"
    print(f"| {r['scenario']} | {r['world']} | {r['runs']} | {r['reached_pct']:.1f} % | {r['within_reach']} "
          f"| {r['reached_of_within_pct']:.1f} % | {r['collisions']} "
          f"| {r['mean']:.2f} | {r['p95']:.2f} | {r['max']:.2f} | {r['reached_mean']:.2f} / {r['reached_p95']:.2f} "
          f"| {stops} |")
