//! A seeded mutation fuzzer for the scene parser and for parse-then-render
//! of tiny images (see fuzz/README.md): no input may panic, and every
//! scene that parses must render the same through the plain path, the
//! exact fast path and `auto`. Time-bounded: RAYOFLIGHT_FUZZ_SECONDS
//! (default 5, CI 60); repeatable: RAYOFLIGHT_FUZZ_SEED (default 1).

use rayoflight::render::{self, RenderOptions};
use rayoflight::scene;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::{Duration, Instant};

use crate::common;
use crate::common::{Rng, env_or};

const NUMBERS: &[&str] = &[
    "1e308",
    "-1e308",
    "1e-320",
    "-0",
    "0",
    "nan",
    "inf",
    "1e400",
    "4294967296",
    "18446744073709551616",
    "10001",
    "+1",
    ".5",
    "1,5",
    "0x10",
    "",
    " ",
    "-1",
    "2.5e-300",
];

const SNIPPETS: &[&str] = &[
    "<sphere/>",
    "<plane/>",
    "<camera width=\"3\" height=\"2\" eyeDistance=\"1\"/>",
    "<model type=\"whitted\" depth=\"10000\"/>",
    "<light x=\"0\" y=\"0\" z=\"0\"/>",
    "<scale factor=\"0\"/>",
    "<scale x=\"1e-300\"/>",
    "<translate x=\"1e308\"/>",
    "<!-- -->",
    "<![CDATA[x]]>",
    "&amp;",
    "&#0;",
    "&#x110000;",
    "<?pi?>",
    "<!DOCTYPE x>",
    "</scene>",
    "<scene>",
    "\u{feff}",
    "\t",
    "é",
    "\u{1F600}",
    ">",
    "<",
    "\"",
    "'",
    "=",
    // Well-formedness that quick-xml does not check.
    "\u{0}",
    "\u{1}",
    "\u{c}",
    "\u{fffe}",
    "\u{ffff}",
    "&#1;",
    "&#xFFFE;",
    "&#x41;",
    "\r",
    "\r\n",
    "--",
    "-->",
    "<!--",
    "]]>",
    "<?XML x?>",
    "<?a:b?>",
    "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>",
    "<?xml version=\"1.0\" encoding=\"UTF-16\"?>",
    " encoding=\"latin1\"",
    "\"x=\"1\"",
];

fn corpus() -> Vec<Vec<u8>> {
    let inputs = common::fuzz_corpus();
    assert!(inputs.len() >= 50, "the corpus is there");
    inputs
}

fn mutate(rng: &mut Rng, input: &[u8], corpus: &[Vec<u8>]) -> Vec<u8> {
    let mut data = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(data.len() + 1);
        match rng.below(8) {
            0 if !data.is_empty() => {
                let i = rng.below(data.len());
                data[i] ^= 1 << rng.below(8);
            }
            1 if !data.is_empty() => {
                let end = (at + 1 + rng.below(16)).min(data.len());
                data.drain(at.min(end)..end);
            }
            2 => {
                let byte = rng.next() as u8;
                data.insert(at, byte);
            }
            3 => {
                let s = SNIPPETS[rng.below(SNIPPETS.len())].as_bytes();
                data.splice(at..at, s.iter().copied());
            }
            4 => {
                // Replace the next quoted value by an extreme number.
                if let Some(q) = data[at..].iter().position(|&b| b == b'"') {
                    let start = at + q + 1;
                    if let Some(len) = data[start..].iter().position(|&b| b == b'"') {
                        let n = NUMBERS[rng.below(NUMBERS.len())].as_bytes();
                        data.splice(start..start + len, n.iter().copied());
                    }
                }
            }
            5 => {
                // Splice with another corpus entry.
                let other = &corpus[rng.below(corpus.len())];
                let from = rng.below(other.len() + 1);
                let to = (from + rng.below(200)).min(other.len());
                data.splice(at..at, other[from..to].iter().copied());
            }
            6 if !data.is_empty() => {
                // Duplicate a chunk (repeated elements and attributes).
                let end = (at + rng.below(80)).min(data.len());
                let chunk = data[at.min(end)..end].to_vec();
                data.splice(end..end, chunk);
            }
            _ => data.truncate(at),
        }
    }
    data
}

/// Parses and, where it parses, renders a tiny version: must not panic.
fn exercise(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return; // load() refuses non-UTF-8 before parsing
    };
    if let Ok(mut s) = scene::parse(text, Path::new("fuzz.xml")) {
        s.camera.width = s.camera.width.min(24);
        s.camera.height = s.camera.height.min(24);
        s.model.depth = s.model.depth.min(50);
        s.objects.truncate(200);
        s.lights.truncate(50);
        let with = |options: RenderOptions| {
            render::render(
                &s,
                &RenderOptions {
                    threads: Some(1),
                    ..options
                },
            )
            .expect("valid options")
        };
        // The exact shortcuts (BVH, culling, early stop) and auto's plan
        // must give the plain path's image on whatever parses.
        let plain = with(RenderOptions::reference());
        assert!(
            with(RenderOptions::default()) == plain,
            "the fast path differs from the plain one"
        );
        assert!(
            with(render::auto(&s).options) == plain,
            "auto differs from the plain path"
        );
        let _ = scene::fresh::to_xml(&s);
    }
}

#[test]
fn fuzz_parse_and_render() {
    let seconds = env_or("RAYOFLIGHT_FUZZ_SECONDS", 5);
    let mut rng = Rng(env_or("RAYOFLIGHT_FUZZ_SEED", 1).max(1));
    let corpus = corpus();
    let start = Instant::now();
    let mut runs = 0u64;
    let crashes = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-crashes");
    // Quiet the default panic message: a crash is reported below.
    std::panic::set_hook(Box::new(|_| {}));
    while start.elapsed() < Duration::from_secs(seconds) {
        let seed = &corpus[rng.below(corpus.len())];
        let input = mutate(&mut rng, seed, &corpus);
        runs += 1;
        if catch_unwind(AssertUnwindSafe(|| exercise(&input))).is_err() {
            let _ = std::panic::take_hook();
            std::fs::create_dir_all(&crashes).unwrap();
            let file = crashes.join(format!("crash-{runs}.xml"));
            std::fs::write(&file, &input).unwrap();
            panic!("input {runs} panicked; saved to {}", file.display());
        }
    }
    let _ = std::panic::take_hook();
    eprintln!("fuzz: {runs} inputs in {seconds} s, no panic");
    assert!(runs > 0);
}

/// The differential oracle of well-formed XML: every
/// mutated input that libxml2 (`xmllint --noout`) finds not well-formed
/// must be refused with a line and column. (The converse need not hold: a
/// well-formed file can break the scene format.) Inputs go to xmllint in
/// batches, one process for many files. Time-bounded like the fuzzer
/// above; in CI a missing xmllint is a failure.
#[test]
fn fuzz_against_xmllint() {
    let seconds = env_or("RAYOFLIGHT_FUZZ_SECONDS", 5);
    let mut rng = Rng(env_or("RAYOFLIGHT_FUZZ_SEED", 1).max(1));
    let corpus = corpus();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-xmllint");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let start = Instant::now();
    let (mut runs, mut refused_by_xmllint, mut same_line) = (0u64, 0u64, 0u64);
    while start.elapsed() < Duration::from_secs(seconds) {
        let batch: Vec<(std::path::PathBuf, Vec<u8>)> = (0..200)
            .map(|i| {
                let seed = &corpus[rng.below(corpus.len())];
                let input = mutate(&mut rng, seed, &corpus);
                (dir.join(format!("{i}.xml")), input)
            })
            .collect();
        for (path, input) in &batch {
            std::fs::write(path, input).unwrap();
        }
        let paths: Vec<_> = batch.iter().map(|(p, _)| p.clone()).collect();
        let Some(lines) = common::xmllint(&paths) else {
            return;
        };
        for ((path, input), xmllint) in batch.iter().zip(lines) {
            runs += 1;
            let Some(xmllint) = xmllint else { continue };
            refused_by_xmllint += 1;
            let ours = scene::load(path).err().and_then(|e| e.position());
            match ours {
                Some(p) => same_line += u64::from(p.line == xmllint),
                None => {
                    let kept = dir.join(format!("accepted-{runs}.xml"));
                    std::fs::write(&kept, input).unwrap();
                    let ours = scene::load(path).map(|_| "loads".to_owned());
                    panic!(
                        "xmllint finds {} not well-formed (line {xmllint}) but RayOfLight gives {:?}",
                        kept.display(),
                        ours.map_err(|e| e.to_string())
                    );
                }
            }
        }
    }
    eprintln!(
        "fuzz against xmllint: {runs} inputs in {seconds} s, {refused_by_xmllint} not well-formed, \
         all refused with a position, {same_line} of them at xmllint's line"
    );
    assert!(refused_by_xmllint > 0);
}

#[test]
fn fuzz_regressions_stay_fixed() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        exercise(&std::fs::read(&path).unwrap());
    }
}
