//! The README's examples, run as a newcomer would type them:
//! every ```` ```console ```` block is a transcript — `$ command` lines,
//! each followed by what it prints (stdout and stderr together) — and is
//! run in a fresh folder (holding a copy of `scenes/` where the block
//! names it), with the built
//! `rayoflight` first on PATH, no display, and HOME and the XDG folders
//! inside the folder. A line `…` alone stands for any lines. The commands
//! of one block run one after another, in the same folder.

use std::fs;
use std::path::Path;
use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// One `$ command` and the lines it prints.
struct Step {
    command: String,
    expected: Vec<String>,
}

/// The console blocks of `text`, each with the line it starts at.
fn blocks(text: &str) -> Vec<(usize, Vec<Step>)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, Vec<Step>)> = None;
    for (i, line) in text.lines().enumerate() {
        match &mut current {
            None if line.trim_end() == "```console" => current = Some((i + 1, Vec::new())),
            None => {}
            Some(_) if line.trim_end() == "```" => blocks.extend(current.take()),
            Some((_, steps)) => match line.strip_prefix("$ ") {
                Some(command) => steps.push(Step {
                    command: command.to_owned(),
                    expected: Vec::new(),
                }),
                None => steps
                    .last_mut()
                    .expect("a console block starts with a $ line")
                    .expected
                    .push(line.trim_end().to_owned()),
            },
        }
    }
    assert!(current.is_none(), "a console block is not closed");
    blocks
}

/// Whether `got` matches `expected`, where a `…` line matches any run of
/// lines.
fn matches(expected: &[String], got: &[&str]) -> bool {
    match expected.split_first() {
        None => got.is_empty(),
        Some((first, rest)) if first == "…" => {
            (0..=got.len()).any(|skip| matches(rest, &got[skip..]))
        }
        Some((first, rest)) => {
            got.first().is_some_and(|g| g.trim_end() == first) && matches(rest, &got[1..])
        }
    }
}

fn copy_xml(from: &Path, to: &Path) {
    fs::create_dir_all(to).unwrap();
    for entry in fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap();
        if path.is_dir() {
            copy_xml(&path, &to.join(name));
        } else if path.extension().is_some_and(|e| e == "xml") {
            fs::copy(&path, to.join(name)).unwrap();
        }
    }
}

#[test]
fn every_console_example_of_the_readme_prints_what_it_says() {
    let readme = fs::read_to_string(Path::new(ROOT).join("README.md")).unwrap();
    let blocks = blocks(&readme);
    assert!(blocks.len() >= 5, "{} console blocks", blocks.len());
    let bin = Path::new(env!("CARGO_BIN_EXE_rayoflight"))
        .parent()
        .unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut failures = Vec::new();
    for (line, steps) in &blocks {
        let dir = tempfile::tempdir().unwrap();
        // A block that uses the repository's scenes has a copy; the others
        // (First steps) run in an empty folder, as a newcomer's is.
        if steps.iter().any(|s| s.command.contains("scenes/")) {
            copy_xml(&Path::new(ROOT).join("scenes"), &dir.path().join("scenes"));
        }
        for step in steps {
            let o = Command::new("sh")
                .arg("-c")
                .arg(format!("exec 2>&1\n{}", step.command))
                .current_dir(dir.path())
                .env("PATH", &path)
                .env("HOME", dir.path())
                .env("XDG_DATA_HOME", dir.path().join(".local/share"))
                .env("XDG_CONFIG_HOME", dir.path().join(".config"))
                .env("XDG_STATE_HOME", dir.path().join(".local/state"))
                .env("COLUMNS", "80")
                .env("LC_ALL", "C")
                .env_remove("DISPLAY")
                .env_remove("WAYLAND_DISPLAY")
                .env_remove("CI")
                .output()
                .expect("sh runs");
            let got = String::from_utf8_lossy(&o.stdout).into_owned();
            let lines: Vec<&str> = got.lines().collect();
            if !matches(&step.expected, &lines) {
                failures.push(format!(
                    "README.md:{line}: $ {}\nexpected:\n{}\ngot:\n{got}",
                    step.command,
                    step.expected.join("\n")
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn the_ellipsis_matches_any_lines() {
    let e = |lines: &[&str]| lines.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert!(matches(&e(&["a", "…", "d"]), &["a", "b", "c", "d"]));
    assert!(matches(&e(&["a", "…", "d"]), &["a", "d"]));
    assert!(!matches(&e(&["a", "…", "d"]), &["a", "b"]));
    assert!(!matches(&e(&["a"]), &["a", "b"]));
    assert!(matches(&e(&[]), &[]));
}
