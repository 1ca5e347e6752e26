//! The figures the docs quote, checked against `docs/figures.toml` (written by `scripts/figures`).
//!
//! A doc quotes a figure as its number, its unit if any, then a marker naming the key:
//! `0.40 M<sup>[fig:device.stm32f4.reading_max_m.paper-bounded-lab]</sup>`. The marker stands for
//! the last number before it on its line; the doc may round, and matches when it is within half a
//! unit of its own last digit of the file's value.

use crate::workspace;
use std::path::PathBuf;

/// What opens a marker, before its key.
pub const OPEN: &str = "<sup>[fig:";
/// What closes a marker, after its key.
pub const CLOSE: &str = "]</sup>";

/// One quoted figure: the line it is on (from 1), its key, and the number shown before it.
#[derive(Debug, Clone, PartialEq)]
pub struct Quote {
    /// Line number, from 1.
    pub line: usize,
    /// The key, dotted (`device.stm32f4.flash_kib`).
    pub key: String,
    /// The number as the doc shows it (thousands' spaces kept), if there is one.
    pub shown: Option<String>,
}

/// The figures file.
pub fn figures() -> toml::Table {
    let path = workspace().join("docs/figures.toml");
    let text = std::fs::read_to_string(&path).expect("read docs/figures.toml");
    text.parse().expect("docs/figures.toml is TOML")
}

/// The pages whose figures are checked: README.md and every page of docs/ (the journal is
/// history and quotes none).
pub fn pages() -> Vec<PathBuf> {
    let mut pages = vec![workspace().join("README.md")];
    let docs = std::fs::read_dir(workspace().join("docs")).expect("read docs/");
    let mut found: Vec<PathBuf> = docs
        .map(|e| e.expect("a docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    found.sort();
    pages.extend(found);
    pages
}

/// Every marker of `text`, with the number before it.
pub fn quotes(text: &str) -> Vec<Quote> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut before = String::new();
        let mut rest = line;
        while let Some(at) = rest.find(OPEN) {
            before.push_str(&rest[..at]);
            let after = &rest[at + OPEN.len()..];
            let Some(end) = after.find(CLOSE) else {
                out.push(Quote {
                    line: i + 1,
                    key: after.to_string(),
                    shown: None,
                });
                break;
            };
            out.push(Quote {
                line: i + 1,
                key: after[..end].to_string(),
                shown: last_number(&before),
            });
            // A marker's own key (digits in `spheres256`) is no number of the text.
            before.push(' ');
            rest = &after[end + CLOSE.len()..];
        }
    }
    out
}

/// The last number in `text`: digits not inside a word, thousands grouped by single spaces,
/// an optional fraction.
pub fn last_number(text: &str) -> Option<String> {
    let chars: Vec<char> = text.chars().collect();
    let mut last = None;
    let mut i = 0;
    while i < chars.len() {
        let starts = chars[i].is_ascii_digit()
            && (i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '_'));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < chars.len() && chars[j].is_ascii_digit() {
            j += 1;
        }
        // Groups of three after a space, when the first group has at most three digits.
        while j - i <= 3 || chars[i..j].contains(&' ') {
            let group = chars.get(j + 1..j + 4);
            let is_group = chars.get(j) == Some(&' ')
                && group.is_some_and(|g| g.iter().all(char::is_ascii_digit))
                && !chars.get(j + 4).is_some_and(char::is_ascii_digit);
            if !is_group {
                break;
            }
            j += 4;
        }
        if chars.get(j) == Some(&'.') && chars.get(j + 1).is_some_and(char::is_ascii_digit) {
            j += 1;
            while j < chars.len() && chars[j].is_ascii_digit() {
                j += 1;
            }
        }
        last = Some(chars[i..j].iter().collect::<String>());
        i = j;
    }
    last
}

/// The value of a dotted key in the figures file.
pub fn lookup<'a>(figures: &'a toml::Table, key: &str) -> Option<&'a toml::Value> {
    let mut parts = key.split('.');
    let mut value = figures.get(parts.next()?)?;
    for part in parts {
        value = value.as_table()?.get(part)?;
    }
    Some(value)
}

/// Whether `shown` (as a doc writes it) is `value` rounded to the digits shown.
pub fn agrees(shown: &str, value: f64) -> bool {
    let digits: String = shown.chars().filter(|c| *c != ' ').collect();
    let Ok(number) = digits.parse::<f64>() else {
        return false;
    };
    let decimals = digits.split_once('.').map_or(0, |(_, f)| f.len());
    let half_unit = 0.5 * 10f64.powi(-i32::try_from(decimals).unwrap_or(i32::MAX));
    (number - value).abs() <= half_unit * (1.0 + 1e-9)
}

/// What is wrong with the figures `text` quotes, one line each (`name:line: ...`).
pub fn problems(name: &str, text: &str, figures: &toml::Table) -> Vec<String> {
    let mut out = Vec::new();
    for q in quotes(text) {
        let at = format!("{name}:{}: fig:{}", q.line, q.key);
        let value = lookup(figures, &q.key)
            .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|n| n as f64)));
        match (value, &q.shown) {
            (None, _) => out.push(format!("{at}: docs/figures.toml holds no such figure")),
            (Some(_), None) => out.push(format!("{at}: no number before the marker")),
            (Some(v), Some(shown)) if !agrees(shown, v) => {
                out.push(format!("{at}: the doc says {shown}, docs/figures.toml {v}"));
            }
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_number_before_a_marker_is_read_as_shown() {
        let q = quotes("flash 178 720 B<sup>[fig:a.b]</sup>, RAM 56.9 KiB<sup>[fig:c]</sup>");
        assert_eq!(q[0].shown.as_deref(), Some("178 720"));
        assert_eq!(q[1].shown.as_deref(), Some("56.9"));
        // Digits inside words and in an earlier marker's key are not the figure.
        let q = quotes("mps2-an386 spheres256<sup>[fig:x.spheres256]</sup> and<sup>[fig:y]</sup>");
        assert_eq!(q[0].shown, None);
        assert_eq!(q[1].shown, None);
        assert_eq!(last_number("RL 2 yes 0.40 M"), Some("0.40".into()));
    }

    #[test]
    fn a_figure_agrees_when_it_is_the_value_rounded_as_shown() {
        assert!(agrees("178.9", 178.914));
        assert!(agrees("179", 178.914));
        assert!(!agrees("178.8", 178.914));
        assert!(agrees("183 208", 183_208.0));
        assert!(!agrees("183 209", 183_208.0));
        assert!(agrees("0.40", 0.403_5));
        assert!(!agrees("0.54", 0.403_5));
    }
}
