//! `needle bench`: planning timed (`needle_analysis::bench`), on scenario files or on generated
//! spheres near and far from the path.

use anyhow::Result;
use needle_scenario::load_scenario;
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenario files (default: examples/paper.toml).
    files: Vec<PathBuf>,
    /// Measured runs per scenario.
    #[arg(long, default_value_t = 200)]
    runs: usize,
    /// Print JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Instead of files: TOTAL generated spheres of which NEAR lie within 20 mm of the
    /// entry-target segment (D summed over the spheres within 20 mm), planned side by side with
    /// the NEAR alone; the two plans must be the same (docs/anatomy.md, "Hundreds of spheres").
    #[arg(long, value_name = "TOTAL,NEAR", conflicts_with = "files")]
    near_and_far: Option<String>,
    /// The seed of `--near-and-far`'s scenario.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs `needle bench`.
pub fn bench(args: &BenchArgs) -> Result<()> {
    if let Some(spec) = &args.near_and_far {
        return bench_near_and_far(args, spec);
    }
    let files = if args.files.is_empty() {
        vec![PathBuf::from("examples/paper.toml")]
    } else {
        args.files.clone()
    };
    let mut out = Vec::new();
    for f in &files {
        let scenario = load_scenario(f)?;
        let name = f
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let r = needle_analysis::bench::run(&scenario, 3, args.runs)?;
        if args.json {
            out.push(needle_analysis::bench::to_json(&name, &r));
        } else {
            write!(
                std::io::stdout(),
                "{}",
                needle_analysis::bench::table(&name, &r)
            )?;
        }
    }
    if args.json {
        writeln!(std::io::stdout(), "{}", serde_json::Value::Array(out))?;
    }
    Ok(())
}

/// `needle bench --near-and-far TOTAL,NEAR`.
fn bench_near_and_far(args: &BenchArgs, spec: &str) -> Result<()> {
    let parsed = spec
        .split_once(',')
        .and_then(|(t, n)| Some((t.trim().parse().ok()?, n.trim().parse().ok()?)));
    let Some((total, near)) = parsed else {
        anyhow::bail!("--near-and-far {spec}: expected TOTAL,NEAR (two whole numbers)");
    };
    let r = needle_analysis::bench::near_and_far(args.seed, total, near, args.runs)?;
    let m = needle_analysis::bench::measures(args.seed, total, near, args.runs)?;
    let ratio = r.all_ms / r.near_ms;
    let rows = [("check", m.check), ("risk", m.risk), ("predict", m.predict)];
    let text = if args.json {
        let mut v = serde_json::json!({
            "seed": args.seed, "spheres": total, "near": near, "runs": args.runs.max(1),
            "best": r.best, "all_ms": r.all_ms, "near_ms": r.near_ms, "ratio": ratio,
            "measured_forms": m.forms,
        });
        for (name, x) in rows {
            v[format!("{name}_us")] = serde_json::json!({
                "culled": x.culled_us, "every": x.every_us, "near": x.near_us,
            });
        }
        format!("{v}\n")
    } else {
        let mut t = format!(
            "seed {}: {total} spheres, {near} within 20 mm; the same plan (best {})\n\
             {total} spheres: median {:.2} ms over {} runs\n\
             {near} alone: median {:.2} ms\nratio {ratio:.3}\n\
             every feasible form ({}) measured, median us: {total} culled, {total} every sphere, \
             {near} alone\n",
            args.seed,
            r.best,
            r.all_ms,
            args.runs.max(1),
            r.near_ms,
            m.forms
        );
        for (name, x) in rows {
            t.push_str(&format!(
                "{name:<8} {:>9.1} {:>9.1} {:>9.1}\n",
                x.culled_us, x.every_us, x.near_us
            ));
        }
        t
    };
    write!(std::io::stdout(), "{text}")?;
    Ok(())
}
