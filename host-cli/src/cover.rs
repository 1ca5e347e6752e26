//! `needle cover`: the label map's covers (`needle-anatomy`) printed, and with `--out` written as
//! `[[obstacles]]`, joined to `--scenario`'s text only when the two still make a scenario.

use anyhow::{anyhow, Context, Result};
use needle_anatomy::command::{covers, obstacles_toml, report_json, table, CoverArgs};
use needle_anatomy::cover::SegmentCover;
use needle_scenario::ScenarioFile;
use std::path::Path;

/// Runs `needle cover`.
pub fn run_cover(a: &CoverArgs) -> Result<()> {
    let covers = covers(a)?;
    let total: usize = covers.iter().map(|c| c.spheres.len()).sum();
    if let Some(out) = &a.out {
        write_obstacles(out, a, &covers, total)?;
    }
    let text = if a.json {
        report_json(a, &covers)?.to_string() + "\n"
    } else {
        table(a, &covers, total)
    };
    print!("{text}");
    Ok(())
}

fn write_obstacles(out: &Path, a: &CoverArgs, covers: &[SegmentCover], total: usize) -> Result<()> {
    let spheres = obstacles_toml(a, covers);
    let text = match &a.scenario {
        Some(base) => {
            let text = std::fs::read_to_string(base)
                .with_context(|| format!("cannot read {}", base.display()))?;
            let joined = text + &spheres;
            ScenarioFile::parse(&joined)
                .and_then(|f| f.to_scenario())
                .map_err(|e| {
                    anyhow!(
                        "{} with the cover's {total} spheres is not a scenario: {e:#}",
                        base.display()
                    )
                })?;
            joined
        }
        None => spheres,
    };
    std::fs::write(out, text).with_context(|| format!("cannot write {}", out.display()))
}
