//! `cargo xtask device-bench --profile`: where the measured instructions go, by function.
//!
//! The plugin attributes each executed translation block, while a region is open, to the block's
//! start address; blocks are mapped here to the function containing them. Figures at region edges
//! are approximate (a block is counted whole); the totals of `instructions` stay exact.

use crate::elf::{functions, Function};
use anyhow::{Context, Result};
use std::collections::HashMap;
use std::path::Path;

/// The `top` functions by instructions executed, with their share, as text.
pub fn report(image: &Path, profile: &Path, top: usize) -> Result<String> {
    let funcs = functions(image)?;
    let text = std::fs::read_to_string(profile)
        .with_context(|| format!("reading {}", profile.display()))?;
    let mut by_function: HashMap<&str, u64> = HashMap::new();
    let mut total = 0u64;
    for line in text.lines() {
        let mut it = line.split_whitespace();
        let (Some(addr), Some(count)) = (it.next(), it.next()) else {
            continue;
        };
        let (Ok(addr), Ok(count)) = (
            u32::from_str_radix(addr.trim_start_matches("0x"), 16),
            count.parse::<u64>(),
        ) else {
            continue;
        };
        total += count;
        *by_function.entry(containing(&funcs, addr)).or_insert(0) += count;
    }
    let mut rows: Vec<_> = by_function.into_iter().collect();
    rows.sort_by_key(|r| std::cmp::Reverse(r.1));
    let mut out = format!("{total} instructions in measured regions, by function:\n");
    for (name, count) in rows.into_iter().take(top) {
        let share = 100.0 * count as f64 / total.max(1) as f64;
        out.push_str(&format!("  {share:5.1}% {count:>12}  {name}\n"));
    }
    Ok(out)
}

fn containing(funcs: &[Function], addr: u32) -> &str {
    let i = funcs.partition_point(|f| f.addr <= addr);
    match i.checked_sub(1).map(|i| &funcs[i]) {
        // `addr >= f.addr` here, so the difference cannot wrap (a sum near 4 GiB could).
        Some(f) if addr - f.addr < f.size.max(1) => &f.name,
        _ => "?",
    }
}
