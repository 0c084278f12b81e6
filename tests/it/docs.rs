//! The documentation a newcomer finds their way in: a README short enough
//! to read, whose contents list reaches every page of `docs/`, and links
//! between them that lead somewhere (the file exists, and so does the
//! heading an anchor names).

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn pages() -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> = fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    pages
}

/// The lines outside fenced code blocks.
fn prose(text: &str) -> Vec<&str> {
    let mut fenced = false;
    text.lines()
        .filter(|l| {
            if l.starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced
        })
        .collect()
}

/// GitHub's anchor for a heading: lower case, punctuation other than `-`
/// and `_` dropped, spaces turned into `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(text: &str) -> BTreeSet<String> {
    prose(text)
        .into_iter()
        .filter_map(|l| l.strip_prefix('#'))
        .map(|l| slug(l.trim_start_matches('#')))
        .collect()
}

/// Every `](target)` of the text's prose that is not a web address.
fn local_links(text: &str) -> Vec<String> {
    let mut links = Vec::new();
    for line in prose(text) {
        let mut rest = line;
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let end = rest.find(')').expect("a closing parenthesis");
            let target = &rest[..end];
            if !target.starts_with("http") {
                links.push(target.to_string());
            }
            rest = &rest[end..];
        }
    }
    links
}

fn check_links(file: &Path) -> Vec<String> {
    let text = fs::read_to_string(file).unwrap();
    let mut broken = Vec::new();
    for link in local_links(&text) {
        let (path, anchor) = link.split_once('#').unwrap_or((&link, ""));
        let target = if path.is_empty() {
            file.to_path_buf()
        } else {
            file.parent().unwrap().join(path)
        };
        if !target.exists() {
            broken.push(format!("{}: {link}: no such file", file.display()));
            continue;
        }
        if !anchor.is_empty() {
            let headings = anchors(&fs::read_to_string(&target).unwrap());
            if !headings.contains(anchor) {
                broken.push(format!("{}: {link}: no such heading", file.display()));
            }
        }
    }
    broken
}

#[test]
fn the_readme_is_short_and_lists_every_page() {
    let readme = fs::read_to_string(root().join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(
        lines <= 300,
        "README.md has {lines} lines; move detail to docs/"
    );
    // What a newcomer needs first, in this order.
    let headings: Vec<&str> = prose(&readme)
        .into_iter()
        .filter(|l| l.starts_with("## "))
        .collect();
    let expected = [
        "## Contents",
        "## Try it (two commands on a fresh machine)",
        "## Install",
        "## Everyday use",
        "## Habits from ping, fping and irtt",
        "## For scripts and CI",
        "## For a safety case",
        "## Watching and monitoring",
        "## Figures measured here",
        "## Completions and man pages",
        "## License",
    ];
    assert_eq!(headings, expected);
    assert!(readme.contains("cargo run --release -- sim:"));
    assert!(readme.contains("bash scripts/test.sh"));
    // The listening form leads the everyday commands (it works against a
    // SITL, which sends to 14550).
    let everyday = readme.split("## Everyday use").nth(1).unwrap();
    let first_command = everyday
        .lines()
        .find(|l| l.starts_with("mavping "))
        .unwrap();
    assert!(first_command.starts_with("mavping udp:"), "{first_command}");
    // The contents list links every page of docs/.
    let contents = readme
        .split("## Contents")
        .nth(1)
        .unwrap()
        .split("\n## ")
        .next()
        .unwrap();
    for page in pages() {
        let name = page.file_name().unwrap().to_str().unwrap();
        assert!(
            contents.contains(&format!("(docs/{name})")),
            "docs/{name} is not in the README's contents"
        );
    }
}

#[test]
fn every_link_between_the_pages_leads_somewhere() {
    let mut files = vec![root().join("README.md"), root().join("CHANGELOG.md")];
    files.extend(pages());
    let broken: Vec<String> = files.iter().flat_map(|f| check_links(f)).collect();
    assert!(broken.is_empty(), "{}", broken.join("\n"));
    // Each page leads back to the README.
    for page in pages() {
        let text = fs::read_to_string(&page).unwrap();
        assert!(
            local_links(&text)
                .iter()
                .any(|l| l.starts_with("../README.md")),
            "{} has no way back to the README",
            page.display()
        );
    }
}

#[test]
fn slugs_are_githubs() {
    assert_eq!(
        slug("JSON events (`--json`, or `--format json`)"),
        "json-events---json-or---format-json"
    );
    assert_eq!(slug("Routes: `--bind` and `-I`"), "routes---bind-and--i");
    assert_eq!(
        slug("Try it (two commands on a fresh machine)"),
        "try-it-two-commands-on-a-fresh-machine"
    );
}
