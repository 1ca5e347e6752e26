//! The firmware's cost, measured by `cargo xtask device-bench` in QEMU on both boards, within every
//! device budget of `needle_devtools::budgets::BUDGETS` (flash, RAM, the paper and space plans'
//! instructions, a steering reading's), and every device plan equal to the host's.

mod firmware_support;

use firmware_support::emulator_ready;
use needle_devtools::budgets::BUDGETS;
use needle_devtools::device_bench::BoardFigures;
use needle_e2e::xtask;
use serde_json::Value;

#[test]
fn firmware_stays_within_its_budgets_on_both_boards() {
    if !emulator_ready("firmware_stays_within_its_budgets_on_both_boards") {
        return;
    }
    // The README's example, as written: it must check the budgets and print the figures.
    let args = needle_e2e::readme::xtask_example_args("device-bench");
    assert_eq!(args.first().map(String::as_str), Some("device-bench"));
    assert!(args.iter().any(|a| a == "--check") && args.iter().any(|a| a == "--json"));
    let out = xtask()
        .args(&args)
        .output()
        .expect("run cargo xtask device-bench");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "cargo xtask device-bench failed: {stderr}"
    );
    let boards: Value = serde_json::from_slice(&out.stdout).expect("device-bench prints JSON");
    let boards: Vec<BoardFigures> = boards
        .as_array()
        .expect("one object per board")
        .iter()
        .map(|b| BoardFigures::from_json(b).expect("the figures of one board"))
        .collect();
    let names: Vec<&str> = boards.iter().map(|b| b.board.as_str()).collect();
    assert_eq!(names, ["mps2-an386", "stm32f4"]);

    let mut problems = Vec::new();
    for b in &boards {
        let name = &b.board;
        // Sanity: a measurement that saw no planning or steering would pass any budget.
        assert!(
            b.flash_bytes > 10_000 && b.static_ram_bytes > 1_000 && b.peak_stack_bytes > 256,
            "{name}: implausible sizes"
        );
        assert!(
            b.instructions.iter().all(|(_, n)| *n > 100_000),
            "{name}: implausible counts"
        );
        for (scenario, r) in &b.replan_instructions {
            println!(
                "{name}: {scenario} steered, {} readings, max {}, median {}",
                r.readings, r.max, r.median
            );
            assert!(
                r.readings > 50 && r.median > 1_000,
                "{name}: implausible steering counts"
            );
        }
        for budget in BUDGETS {
            let figure = budget.figure(b).map_or("not measured".into(), |n| {
                let margin = budget.limit.saturating_sub(n);
                format!(
                    "{} ({} to spare)",
                    budget.unit.show(n),
                    budget.unit.show(margin)
                )
            });
            println!(
                "{name}: {} {figure}, budget {}",
                budget.name,
                budget.unit.show(budget.limit)
            );
        }
        problems.extend(needle_devtools::budgets::problems(b));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The bench's lab row (`paper-bounded-lab`) plans and steers as the clinical examples say (their
/// curvature reserve, what they tell their steering), so the budget holds for what a lab runs.
#[test]
fn the_lab_row_steers_as_the_clinical_examples_say() {
    use needle_devtools::replan_bench::{LAB_RESERVE, LAB_STEERING};
    use needle_scenario::build::load_scenario;
    use needle_scenario::execution::load_execution;
    for name in ["paper-clinical", "space-clinical"] {
        let file = needle_e2e::example(name);
        let told = load_execution(&file).unwrap().steering;
        assert_eq!(told, LAB_STEERING, "{name}");
        let reserve = load_scenario(&file).unwrap().options.curvature_reserve;
        assert_eq!(reserve, LAB_RESERVE, "{name}");
    }
    assert_ne!(LAB_STEERING, planner_core::steer::SteerConfig::DEFAULT);
}
