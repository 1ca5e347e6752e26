//! The figures the README and docs/ quote are the ones `scripts/figures` generated into
//! `docs/figures.toml`: every `<sup>[fig:KEY]</sup>` marker names a figure the file holds, and
//! the number before it is that figure as rounded (the convention: the file's header,
//! docs/README.md... see `needle_e2e::doc_figures`).

use needle_e2e::doc_figures::{figures, pages, problems, quotes, CLOSE, OPEN};

#[test]
fn every_figure_the_docs_quote_is_the_generated_one() {
    let figures = figures();
    let mut found = Vec::new();
    let mut quoted = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).expect("read a page");
        let name = page.file_name().unwrap().to_string_lossy().into_owned();
        quoted += quotes(&text).len();
        found.extend(problems(&name, &text, &figures));
    }
    assert!(found.is_empty(), "quoted figures that differ from docs/figures.toml (regenerate with scripts/figures, or correct the doc):\n{}", found.join("\n"));
    // The README and firmware page quote the device's figures at least: a check of nothing
    // would pass.
    assert!(quoted >= 20, "only {quoted} quoted figures found");
}

#[test]
fn a_planted_wrong_figure_or_key_fails_the_check() {
    let figures = figures();
    let dir = std::env::temp_dir().join(format!("needle-doc-figures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for page in ["README.md", "docs/firmware.md"] {
        let text = std::fs::read_to_string(needle_e2e::workspace().join(page)).unwrap();
        let first = quotes(&text)
            .into_iter()
            .find(|q| q.shown.is_some())
            .unwrap_or_else(|| panic!("{page} quotes a figure"));
        let shown = first.shown.clone().unwrap();
        // The same number with its last digit changed: a figure that drifted.
        let mut wrong: Vec<char> = shown.chars().collect();
        let last = wrong.iter().rposition(char::is_ascii_digit).unwrap();
        wrong[last] = if wrong[last] == '9' {
            '1'
        } else {
            char::from(wrong[last] as u8 + 1)
        };
        let wrong: String = wrong.into_iter().collect();
        let marker = format!("{OPEN}{}{CLOSE}", first.key);
        let planted: Vec<String> = text
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i + 1 == first.line {
                    let at = l.find(&marker).unwrap();
                    let number = l[..at].rfind(&shown).unwrap();
                    format!("{}{wrong}{}", &l[..number], &l[number + shown.len()..])
                } else {
                    l.to_string()
                }
            })
            .collect();
        let copy = dir.join("copy.md");
        std::fs::write(&copy, planted.join("\n")).unwrap();
        let found = problems(
            "copy.md",
            &std::fs::read_to_string(&copy).unwrap(),
            &figures,
        );
        assert_eq!(
            found.len(),
            1,
            "{page}, {shown} planted as {wrong}: {found:?}"
        );
        assert!(
            found[0].contains(&first.key) && found[0].contains(&format!("says {wrong}")),
            "{}",
            found[0]
        );
        // The unchanged page passes, and a key the file does not hold fails.
        assert!(problems(page, &text, &figures).is_empty());
        let unknown = text.replacen(&marker, &format!("{OPEN}device.no_such_figure{CLOSE}"), 1);
        let found = problems(page, &unknown, &figures);
        assert!(
            found.iter().any(|p| p.contains("holds no such figure")),
            "{found:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
