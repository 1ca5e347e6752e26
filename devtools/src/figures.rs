//! The figures `cargo xtask device-bench` measures on one board, what they come to against the
//! budgets (`--check`), and their JSON and text forms. Plain data: nothing here runs QEMU.

use crate::replan_bench::ReplanFigures;
use crate::step_bench::StepFigures;
use anyhow::{Context, Result};
use serde_json::{json, Map, Value};

/// Figures of one board.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BoardFigures {
    /// Board name.
    pub board: String,
    /// See [`elf::Footprint`].
    pub flash_bytes: u64,
    /// See [`elf::Footprint`].
    pub static_ram_bytes: u64,
    /// Deepest stack use over all the runs (bytes).
    pub peak_stack_bytes: u64,
    /// Scenario name and instructions executed for its plan.
    pub instructions: Vec<(String, u64)>,
    /// Scenario name and whether the device's plan equals the host's bit for bit.
    pub matches_host: Vec<(String, bool)>,
    /// Scenario name and the instructions per steering reading of one closed-loop insertion.
    pub replan_instructions: Vec<(String, ReplanFigures)>,
    /// The step interrupt's instructions (homing and the paper's schedule), or `None` on a board
    /// that drives no axes.
    pub steps: Option<StepFigures>,
}

impl BoardFigures {
    /// The JSON object of `cargo xtask device-bench --json`.
    pub fn to_json(&self) -> Value {
        let map = |v: &[(String, u64)]| {
            v.iter()
                .map(|(k, n)| (k.clone(), json!(n)))
                .collect::<Map<_, _>>()
        };
        let same = self
            .matches_host
            .iter()
            .map(|(k, b)| (k.clone(), json!(b)))
            .collect::<Map<_, _>>();
        json!({
            "board": self.board,
            "flash_bytes": self.flash_bytes,
            "static_ram_bytes": self.static_ram_bytes,
            "peak_stack_bytes": self.peak_stack_bytes,
            "instructions": map(&self.instructions),
            "matches_host": same,
            "replan_instructions": self
                .replan_instructions
                .iter()
                .map(|(k, r)| {
                    let v = json!({
                        "max": r.max,
                        "median": r.median,
                        "readings": r.readings,
                        "replans": r.replans,
                    });
                    (k.clone(), v)
                })
                .collect::<Map<_, _>>(),
            "step_instructions": self.steps.map(|s| json!({
                "steps": s.steps,
                "max": s.max,
                "sum": s.sum,
                "mean": s.mean(),
                "move_request": s.move_request,
            })),
        })
    }

    /// Reads back one object of `cargo xtask device-bench --json` (what [`Self::to_json`] wrote).
    pub fn from_json(v: &Value) -> Result<BoardFigures> {
        let number = |v: &Value, key: &str| {
            v[key]
                .as_u64()
                .with_context(|| format!("device-bench JSON: {key} is not a count"))
        };
        let object = |key: &str| {
            v[key]
                .as_object()
                .with_context(|| format!("device-bench JSON: {key} is not an object"))
        };
        let counts = object("instructions")?
            .iter()
            .map(|(k, n)| {
                let n = n.as_u64().with_context(|| {
                    format!("device-bench JSON: instructions.{k} is not a count")
                })?;
                Ok((k.clone(), n))
            })
            .collect::<Result<_>>()?;
        let matches_host = object("matches_host")?
            .iter()
            .map(|(k, b)| {
                let same = b.as_bool().context("device-bench JSON: matches_host")?;
                Ok((k.clone(), same))
            })
            .collect::<Result<_>>()?;
        let replan_instructions = object("replan_instructions")?
            .iter()
            .map(|(k, r)| {
                let figures = ReplanFigures {
                    readings: usize::try_from(number(r, "readings")?)?,
                    replans: u32::try_from(number(r, "replans")?)?,
                    max: number(r, "max")?,
                    median: number(r, "median")?,
                };
                Ok((k.clone(), figures))
            })
            .collect::<Result<_>>()?;
        // Absent from the JSON of a firmware without axes (and of older runs).
        let steps = match &v["step_instructions"] {
            Value::Null => None,
            s => Some(StepFigures {
                steps: number(s, "steps")?,
                max: number(s, "max")?,
                sum: number(s, "sum")?,
                move_request: number(s, "move_request")?,
            }),
        };
        Ok(BoardFigures {
            board: v["board"]
                .as_str()
                .context("device-bench JSON: board is not a name")?
                .to_owned(),
            flash_bytes: number(v, "flash_bytes")?,
            static_ram_bytes: number(v, "static_ram_bytes")?,
            peak_stack_bytes: number(v, "peak_stack_bytes")?,
            instructions: counts,
            matches_host,
            replan_instructions,
            steps,
        })
    }
}

/// The human-readable report.
pub fn table(figures: &[BoardFigures]) -> String {
    let mut s = String::new();
    for f in figures {
        s.push_str(&format!(
            "{}: flash {} B ({:.1} KiB), static RAM {} B, peak stack {} B, RAM total {:.1} KiB\n",
            f.board,
            f.flash_bytes,
            f.flash_bytes as f64 / 1024.0,
            f.static_ram_bytes,
            f.peak_stack_bytes,
            (f.static_ram_bytes + f.peak_stack_bytes) as f64 / 1024.0
        ));
        for ((name, n), (_, same)) in f.instructions.iter().zip(&f.matches_host) {
            s.push_str(&format!(
                "  {name}: {n} instructions per plan ({:.2} M), plan {} the host's\n",
                *n as f64 / 1e6,
                if *same { "equals" } else { "DIFFERS from" }
            ));
        }
        if f.replan_instructions.is_empty() {
            s.push_str("  steering not measured (--plan-only)\n");
        }
        match f.steps {
            None => s.push_str("  drives no axes: no step interrupt to measure\n"),
            Some(st) => s.push_str(&format!(
                "  step interrupt: {} steps (homing, the paper's schedule), max {} instructions \
                 (≈ {:.1} µs at 168 MHz), mean {:.0}\n",
                st.steps,
                st.max,
                st.max as f64 / 168.0,
                st.mean()
            )),
        }
        for (name, r) in &f.replan_instructions {
            s.push_str(&format!(
                "  {name} steered: {} readings, {} replans; per reading max {} (≈ {:.1} ms at \
                 168 MHz), median {} instructions (≈ {:.0} readings/s at 168 MHz, one \
                 instruction per cycle)\n",
                r.readings,
                r.replans,
                r.max,
                r.max as f64 / 168e3,
                r.median,
                168e6 / r.median.max(1) as f64
            ));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::budgets::tests::within;

    #[test]
    fn the_json_reads_back_as_the_figures_it_was_written_from() {
        let mut figures = within();
        figures.matches_host[1].1 = false;
        let back = BoardFigures::from_json(&figures.to_json()).unwrap();
        assert_eq!(back, figures);
        let mut broken = figures.to_json();
        broken["flash_bytes"] = json!("many");
        let error = BoardFigures::from_json(&broken).unwrap_err().to_string();
        assert!(error.contains("flash_bytes"), "{error}");
    }

    #[test]
    fn the_table_says_when_steering_was_not_measured() {
        let figures = BoardFigures {
            board: "mps2-an386".into(),
            flash_bytes: 1,
            static_ram_bytes: 2,
            peak_stack_bytes: 3,
            instructions: vec![("paper".into(), 14_000_000)],
            matches_host: vec![("paper".into(), true)],
            replan_instructions: Vec::new(),
            steps: None,
        };
        let text = table(&[figures]);
        assert!(
            text.contains("paper: 14000000 instructions per plan"),
            "{text}"
        );
        assert!(text.contains("steering not measured"), "{text}");
        assert!(text.contains("drives no axes"), "{text}");
    }
}
