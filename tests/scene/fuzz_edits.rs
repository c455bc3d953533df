//! A seeded fuzzer for editing (see fuzz/README.md): random `--set`,
//! `--remove` and `--add` sequences, well-formed and not, on the fuzz
//! corpus scenes. Through the library: no panic; edits that apply save
//! back to text that loads as the edited scene; undoing them all and saving
//! gives the file back byte for byte. Through the binary (`edit` and
//! `--set`): never a crash, and a refusal writes nothing. Time-bounded by
//! RAYOFLIGHT_FUZZ_SECONDS (default 5, CI 60); repeatable with
//! RAYOFLIGHT_FUZZ_SEED.

use crate::common;

use crate::common::{Rng, env_or, files_in};
use rayoflight::scene::edit::{Edit, Edited, Field, Item, NewElement};
use rayoflight::scene::{self, splice};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::{Duration, Instant};

const VALUES: &[&str] = &[
    "0",
    "1",
    "0.5",
    "-1",
    "-0",
    "2",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "1e400",
    "",
    " 1",
    "1,5",
    "0x10",
    "4294967296",
    "10001",
    "whitted",
    "phong",
    "lambert",
    "ambient",
    "Whitted",
    "3.14159",
    "1e-9",
    "65535",
    "1000000000",
];

/// Values most fields take.
const PLAIN: &[&str] = &["0", "1", "0.5", "0.25", "2", "3", "-1.5"];

const FIELDS: &[&str] = &[
    "model.type",
    "model.depth",
    "camera.width",
    "camera.height",
    "camera.eyeDistance",
    "camera.transformation[#].#",
    "object[#].color.#",
    "object[#].material.#",
    "object[#].transformation[#].#",
    "light[#].#",
    "light[#].color.#",
];

const ATTRIBUTES: &[&str] = &[
    "x", "y", "z", "angle", "factor", "red", "green", "blue", "ka", "kd", "ks", "m", "w", "",
];

const ITEMS: &[&str] = &[
    "object[#]",
    "light[#]",
    "object[#].transformation[#]",
    "camera.transformation[#]",
    "camera",
    "object",
];

const KINDS: &[&str] = &["sphere", "plane", "light", "cube", ""];

/// An index: mostly small and valid, sometimes 0 or huge.
fn index(rng: &mut Rng) -> String {
    match rng.below(16) {
        0 => "0".into(),
        1 => "4294967297".into(),
        2 => "-1".into(),
        _ => (1 + rng.below(3)).to_string(),
    }
}

/// Fills each `#` of `pattern`: indices inside brackets, attributes after
/// a dot (mostly one that belongs there).
fn fill(rng: &mut Rng, pattern: &str) -> String {
    let mut out = String::new();
    for (i, c) in pattern.char_indices() {
        if c == '#' {
            let before = &pattern[..i];
            let fitting: &[&str] = if before.ends_with("color.") {
                &["red", "green", "blue"]
            } else if before.ends_with("material.") {
                &["ka", "kd", "ks", "m"]
            } else if before.ends_with("].") && before.contains("transformation") {
                &["x", "y", "z", "angle", "factor"]
            } else {
                &["x", "y", "z"]
            };
            if before.ends_with('[') {
                out += &index(rng);
            } else if rng.below(5) > 0 {
                out += fitting[rng.below(fitting.len())];
            } else {
                out += ATTRIBUTES[rng.below(ATTRIBUTES.len())];
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// One random edit, as the command line would give it.
enum Arg {
    Set(String, String),
    Remove(String),
    Add(String),
}

fn random_args(rng: &mut Rng) -> Vec<Arg> {
    (0..1 + rng.below(3))
        .map(|_| match rng.below(6) {
            0 => {
                let item = ITEMS[rng.below(ITEMS.len())];
                Arg::Remove(fill(rng, item))
            }
            1 => Arg::Add(KINDS[rng.below(KINDS.len())].into()),
            _ => {
                let field = FIELDS[rng.below(FIELDS.len())];
                let value = if rng.below(3) > 0 {
                    PLAIN[rng.below(PLAIN.len())]
                } else {
                    VALUES[rng.below(VALUES.len())]
                };
                Arg::Set(fill(rng, field), value.into())
            }
        })
        .collect()
}

/// Applies `args` as `rayoflight edit` does; `None` on the first refusal.
fn apply(edited: &mut Edited, args: &[Arg]) -> Option<Vec<rayoflight::scene::edit::Undo>> {
    let mut undos = Vec::new();
    for arg in args {
        let edit = match arg {
            Arg::Set(path, value) => {
                let field = Field::parse(path).ok()?;
                Edit::Set(field, field.parse_value(value).ok()?)
            }
            Arg::Remove(path) => Edit::Remove(Item::parse(path).ok()?),
            Arg::Add(kind) => Edit::add(edited.scene(), NewElement::parse(kind).ok()?),
        };
        undos.push(edited.apply(&edit).ok()?);
    }
    Some(undos)
}

/// The library's promises for one scene text and one edit sequence;
/// whether the edits applied (or one was refused).
fn exercise(text: &str, args: &[Arg]) -> bool {
    let path = Path::new("fuzz.xml");
    let Ok(loaded) = scene::parse(text, path) else {
        return false;
    };
    let mut edited = Edited::new(loaded);
    let Some(undos) = apply(&mut edited, args) else {
        return false;
    };
    let saved = splice::save(text, path, &edited).expect("applied edits save");
    let back = scene::parse(&saved, path).expect("the saved text loads");
    assert!(
        &back == edited.scene(),
        "the saved text is the edited scene"
    );
    for undo in undos.into_iter().rev() {
        edited.undo(undo).expect("an undo applies");
    }
    let restored = splice::save(text, path, &edited).expect("the undone scene saves");
    assert!(restored == text, "undoing everything gives the file back");
    true
}

/// The corpus scenes that load, as text.
fn corpus() -> Vec<String> {
    let texts: Vec<String> = common::fuzz_corpus()
        .into_iter()
        .filter_map(|bytes| String::from_utf8(bytes).ok())
        .filter(|t| scene::parse(t, Path::new("c.xml")).is_ok())
        .collect();
    assert!(texts.len() >= 20, "the corpus has scenes that load");
    texts
}

fn describe(args: &[Arg]) -> String {
    args.iter()
        .map(|a| match a {
            Arg::Set(p, v) => format!("--set '{p}={v}'"),
            Arg::Remove(p) => format!("--remove '{p}'"),
            Arg::Add(k) => format!("--add '{k}'"),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn fuzz_edits_through_the_library() {
    let seconds = env_or("RAYOFLIGHT_FUZZ_SECONDS", 5);
    let mut rng = Rng(env_or("RAYOFLIGHT_FUZZ_SEED", 1).max(1));
    let corpus = corpus();
    let start = Instant::now();
    let (mut runs, mut applied) = (0u64, 0u64);
    std::panic::set_hook(Box::new(|_| {}));
    while start.elapsed() < Duration::from_secs(seconds) {
        let k = rng.below(corpus.len());
        let args = random_args(&mut rng);
        runs += 1;
        let outcome = catch_unwind(AssertUnwindSafe(|| exercise(&corpus[k], &args)));
        applied += u64::from(matches!(outcome, Ok(true)));
        if outcome.is_err() {
            let _ = std::panic::take_hook();
            // Run it again to show the message.
            eprintln!("corpus scene {k}: {}", describe(&args));
            exercise(&corpus[k], &args);
            unreachable!("the input panicked the first time");
        }
    }
    let _ = std::panic::take_hook();
    eprintln!("fuzz edits: {runs} sequences in {seconds} s, {applied} applied and saved");
    // Enough of them are valid to test saving, not only refusals.
    assert!(applied * 10 >= runs, "{applied} of {runs} applied");
}

#[test]
fn fuzz_edits_through_the_command_line() {
    let mut rng = Rng(env_or("RAYOFLIGHT_FUZZ_SEED", 1).max(1) ^ 0x5eed);
    let corpus = corpus();
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("scene.xml");
    // A process per run: a bounded number, not a time.
    for run in 0..60 {
        let text = &corpus[rng.below(corpus.len())];
        std::fs::write(&scene_path, text).unwrap();
        let before = files_in(dir.path());
        let args = random_args(&mut rng);
        let render = rng.below(3) == 0;
        let mut argv: Vec<String> = if render {
            // --set on a render: only values, and a tiny image.
            vec![
                "--no-gui".into(),
                "scene.xml".into(),
                "-out".into(),
                "out.png".into(),
            ]
        } else {
            vec!["edit".into(), "scene.xml".into()]
        };
        for a in &args {
            match a {
                Arg::Set(p, v) => argv.extend(["--set".into(), format!("{p}={v}")]),
                Arg::Remove(p) if !render => argv.extend(["--remove".into(), p.clone()]),
                Arg::Add(k) if !render => argv.extend(["--add".into(), k.clone()]),
                _ => {}
            }
        }
        if render {
            // Keep the render small whatever the file says.
            argv.extend(["--set".into(), "camera.width=8".into()]);
            argv.extend(["--set".into(), "camera.height=6".into()]);
            argv.extend(["--set".into(), "model.depth=3".into()]);
        }
        let refs: Vec<&str> = argv.iter().map(String::as_str).collect();
        let o = common::rayoflight(dir.path(), &refs);
        let code = o.status.code();
        let err = common::stderr(&o);
        assert!(
            matches!(code, Some(0..=2)),
            "run {run}: {argv:?} ended with {code:?}: {err}"
        );
        if code != Some(0) {
            assert_eq!(
                err.trim_end().lines().count(),
                1,
                "run {run}: {argv:?}: {err}"
            );
            assert_eq!(
                std::fs::read_to_string(&scene_path).unwrap(),
                *text,
                "run {run}: a refusal changed the scene: {argv:?}"
            );
            assert_eq!(
                files_in(dir.path()),
                before,
                "run {run}: {argv:?} wrote a file"
            );
        }
        let _ = std::fs::remove_file(dir.path().join("out.png"));
    }
}
