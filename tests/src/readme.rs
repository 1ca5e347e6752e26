//! The README read as data: its fenced blocks and the examples of its command table, so tests can
//! run what it shows exactly as written.

use crate::workspace;

/// The README's text.
pub fn text() -> String {
    std::fs::read_to_string(workspace().join("README.md")).expect("read README.md")
}

/// The fenced blocks of `text`: (language, lines).
pub fn fenced_blocks(text: &str) -> Vec<(String, Vec<String>)> {
    let mut blocks = Vec::new();
    let mut open: Option<(String, Vec<String>)> = None;
    for line in text.lines() {
        match (open.take(), line.strip_prefix("```")) {
            (None, Some(lang)) => open = Some((lang.trim().to_string(), Vec::new())),
            (Some(block), Some(_)) => blocks.push(block),
            (Some((lang, mut lines)), None) => {
                lines.push(line.to_string());
                open = Some((lang, lines));
            }
            (None, None) => {}
        }
    }
    blocks
}

/// The example of each row of the "Commands" table: (subcommand, example line).
pub fn table_examples(text: &str) -> Vec<(String, String)> {
    let section = text
        .split("\n## Commands")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("README has a Commands section");
    section
        .lines()
        .filter(|l| l.starts_with("| `"))
        .filter_map(|l| {
            let cells: Vec<&str> = l.split(" | ").collect();
            let command = cells.first()?.trim_start_matches("| ").trim_matches('`');
            let example = cells.last()?.trim_end_matches(" |").trim_matches('`');
            example
                .starts_with("needle ")
                .then(|| (command.to_string(), example.to_string()))
        })
        .collect()
}

/// The arguments (after `cargo xtask`) of the README's example of the developer task `task`:
/// the first `` `cargo xtask TASK ...` `` it shows.
pub fn xtask_example_args(task: &str) -> Vec<String> {
    let text = text();
    let start = format!("`cargo xtask {task}");
    let at = text
        .find(&start)
        .unwrap_or_else(|| panic!("README: no example of `cargo xtask {task}`"));
    let example = text[at + 1..].split('`').next().unwrap_or_default();
    example
        .split_whitespace()
        .skip(2)
        .map(str::to_string)
        .collect()
}

/// The arguments (after `needle`) of the command table's example of `command`.
pub fn example_args(command: &str) -> Vec<String> {
    let (_, line) = table_examples(&text())
        .into_iter()
        .find(|(c, _)| c == command)
        .unwrap_or_else(|| panic!("README: no example of `needle {command}`"));
    line.split_whitespace()
        .skip(1)
        .map(str::to_string)
        .collect()
}
