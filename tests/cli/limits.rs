//! docs/limits.md, checked against the binary: the test reads the table
//! of limits and, for each row, runs the binary just over the limit (the
//! documented error, its exit status) and at or under it (no error). A row
//! without a check here fails, and so does a check without its row: the
//! table and the program cannot drift apart.
//!
//! Where the row is a limit, "at" means at it exactly when that costs
//! seconds, not minutes; the rows whose limit costs gigabytes to reach
//! (10 million objects) are checked just over it, where the loader stops.
#![cfg(unix)]

use crate::common;

use crate::common::{TINY, mirrors_text, stderr, stdout};
use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// One row of the table: what is limited, the limit, the error text
/// (backquoted in the table; `…` stands for any text).
struct Row {
    what: String,
    error: String,
}

fn table() -> Vec<Row> {
    let doc = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/limits.md");
    let text = fs::read_to_string(doc).unwrap();
    let (_, table) = text
        .split_once("## The limits")
        .expect("docs/limits.md has its table");
    table
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2) // the header and its rule
        .map(|line| {
            // `\|` in a cell is a bar, not a new cell.
            let cells: Vec<String> = line
                .replace("\\|", "\u{1}")
                .split('|')
                .map(|c| c.trim().replace('\u{1}', "|"))
                .collect();
            assert_eq!(cells.len(), 5, "three cells: {line}");
            // No backquotes: no error (the row says what runs instead).
            let error = cells[3].split('`').nth(1).unwrap_or_default().to_owned();
            Row {
                what: cells[1].clone(),
                error,
            }
        })
        .collect()
}

/// A check: `dir` holds `tiny.xml` (16×12); `error` is the documented
/// text.
type Check = fn(&Path, &str) -> Result<(), String>;

const CHECKS: &[(&str, Check)] = &[
    ("scene: file size", file_size),
    ("scene: objects", objects),
    ("scene: lights", lights),
    ("scene: image pixels", image_pixels),
    ("scene: width and height", width_and_height),
    ("scene: model depth", model_depth),
    ("scene: XML", xml),
    ("scene: transformation", transformation),
    ("render: anti-aliasing", anti_aliasing),
    ("render: threads", threads),
    ("render: region", region),
    ("render: memory of a pass or an EXR", pass_memory),
    ("split: tasks", split_tasks),
    ("bench, study: runs", runs),
    ("bench: split size", split_size),
    ("bench: big scene", big_spheres),
    ("output: the scene itself", the_scene_itself),
    ("output: folder", folder),
    ("output: read-only file", read_only),
    ("output: a file the caller may not write", not_writable),
    ("output: JPEG, GIF and TGA size", jpeg_gif_tga_size),
    ("output: WebP size", webp_size),
    ("output: image to a device or FIFO", image_to_special),
    ("output: text to a device or FIFO", text_to_special),
    ("output: a full disk", full_disk),
    ("output: stdout", closed_stdout),
    ("output: links in sticky folders", sticky_links),
    ("output: a loop of links", link_loop),
    ("sheet: columns", sheet_columns),
    ("sheet: an image", sheet_image),
    ("sheet: pixels", sheet_pixels),
    ("assemble: open parts", assemble_open_parts),
    ("explain: pixel", explain_pixel),
    ("explain: the ray tree", explain_tree),
    ("lsp: a message", lsp_message),
];

#[test]
fn every_documented_limit_is_the_programs() {
    let rows = table();
    let mut failures = Vec::new();
    for row in &rows {
        if !CHECKS.iter().any(|(what, _)| *what == row.what) {
            failures.push(format!("{}: no check in tests/cli/limits.rs", row.what));
        }
    }
    for (what, _) in CHECKS {
        if !rows.iter().any(|r| r.what == *what) {
            failures.push(format!("{what}: checked, but not in docs/limits.md"));
        }
    }
    for row in &rows {
        let Some((_, check)) = CHECKS.iter().find(|(what, _)| *what == row.what) else {
            continue;
        };
        let dir = common::folder_with(&[("tiny.xml", TINY)]);
        let result = check(dir.path(), &row.error);
        if let Err(why) = result {
            failures.push(format!("{}: {why}", row.what));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

// ----- running the binary -----

/// A folder anyone may enter (some checks run as `nobody`) holding
/// `tiny.xml`.
fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_rayoflight")
}

/// `prefix` (a wrapper such as `prlimit …`, or none) then the binary with
/// `args`, in `dir`, headless.
fn run_with(dir: &Path, prefix: &[&str], args: &[&str]) -> Output {
    let mut all: Vec<&str> = prefix.to_vec();
    all.push(bin());
    all.extend_from_slice(args);
    Command::new(all[0])
        .args(&all[1..])
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs")
}

fn run(dir: &Path, args: &[&str]) -> Output {
    run_with(dir, &[], args)
}

/// Whether `text` holds the pieces of `pattern` between its `…`, in order.
fn matches(text: &str, pattern: &str) -> bool {
    let mut rest = text;
    for piece in pattern.split('…') {
        match rest.find(piece) {
            Some(at) => rest = &rest[at + piece.len()..],
            None => return false,
        }
    }
    true
}

/// The command failed with `code` and an error that matches `pattern`.
fn refused(o: &Output, code: i32, pattern: &str, what: &str) -> Result<(), String> {
    let err = stderr(o);
    if o.status.code() != Some(code) {
        return Err(format!(
            "{what}: exit {:?}, not {code}: {err}",
            o.status.code()
        ));
    }
    if !matches(&err, pattern) {
        return Err(format!("{what}: {err:?} does not say {pattern:?}"));
    }
    Ok(())
}

/// The command succeeded.
fn accepted(o: &Output, what: &str) -> Result<(), String> {
    if o.status.success() {
        Ok(())
    } else {
        Err(format!("{what}: exit {:?}: {}", o.status.code(), stderr(o)))
    }
}

/// The command failed, but not for the limit `pattern` says.
fn not_for(o: &Output, pattern: &str, what: &str) -> Result<(), String> {
    let err = stderr(o);
    if matches(&err, pattern) {
        return Err(format!("{what}: refused for the limit: {err}"));
    }
    Ok(())
}

/// A scene of one sphere and one light, a `width × height` camera, and
/// `extra` elements.
fn scene(width: &str, height: &str, extra: &str) -> String {
    format!(
        r#"<scene>
  <sphere><transformation><translate z="3"/></transformation></sphere>
  <light x="0" y="-3" z="-3"/>
  <camera width="{width}" height="{height}" eyeDistance="2"/>
{extra}</scene>
"#
    )
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    path
}

// ----- scene loading -----

fn file_size(dir: &Path, error: &str) -> Result<(), String> {
    const LIMIT: u64 = 1 << 30;
    // Sparse: no disk is used, and the size is refused from the metadata.
    let big = fs::File::create(dir.join("big.xml")).unwrap();
    big.set_len(LIMIT + 1).unwrap();
    refused(&run(dir, &["plan", "big.xml"]), 1, error, "1 GiB + 1")?;
    // At the limit the file is read, and refused for what it holds.
    big.set_len(LIMIT).unwrap();
    let o = run(dir, &["plan", "big.xml"]);
    refused(&o, 1, "big.xml", "1 GiB of zeros")?;
    not_for(&o, error, "1 GiB")?;
    accepted(&run(dir, &["plan", "tiny.xml"]), "tiny")
}

/// A scene with `n` copies of `element` after the camera.
fn many(dir: &Path, name: &str, element: &str, n: usize) -> PathBuf {
    let mut text = scene("16", "12", "");
    text.truncate(text.len() - "</scene>\n".len());
    text.reserve((element.len() + 1) * n + 10);
    for _ in 0..n {
        text.push_str(element);
        text.push('\n');
    }
    text.push_str("</scene>\n");
    write(dir, name, &text)
}

fn objects(dir: &Path, error: &str) -> Result<(), String> {
    // The scene already has one sphere: 10 000 000 more is one over.
    many(dir, "over.xml", "<sphere/>", 10_000_000);
    let o = run(dir, &["plan", "over.xml"]);
    refused(&o, 1, error, "10 000 001 objects")?;
    // At the first object over: new sphere k is on line 4 + k.
    refused(
        &o,
        1,
        "over.xml:10000004:",
        "the line of the first one over",
    )?;
    many(dir, "under.xml", "<sphere/>", 99_999);
    accepted(&run(dir, &["plan", "under.xml"]), "100 000 objects")
}

fn lights(dir: &Path, error: &str) -> Result<(), String> {
    let light = r#"<light x="0" y="-3" z="-3"/>"#;
    many(dir, "over.xml", light, 1_000_000);
    refused(
        &run(dir, &["plan", "over.xml"]),
        1,
        error,
        "1 000 001 lights",
    )?;
    many(dir, "at.xml", light, 999_999);
    accepted(&run(dir, &["plan", "at.xml"]), "1 000 000 lights")
}

fn image_pixels(dir: &Path, error: &str) -> Result<(), String> {
    write(dir, "over.xml", &scene("16384", "16385", ""));
    refused(&run(dir, &["plan", "over.xml"]), 1, error, "16384 x 16385")?;
    write(dir, "wide.xml", &scene("268435457", "1", ""));
    refused(&run(dir, &["plan", "wide.xml"]), 1, error, "268435457 x 1")?;
    write(dir, "at.xml", &scene("16384", "16384", ""));
    accepted(&run(dir, &["plan", "at.xml"]), "16384 x 16384")?;
    write(dir, "line.xml", &scene("268435456", "1", ""));
    accepted(&run(dir, &["plan", "line.xml"]), "268435456 x 1")
}

fn width_and_height(dir: &Path, error: &str) -> Result<(), String> {
    for (w, h) in [("0", "12"), ("16", "0"), ("4294967296", "1"), ("-1", "1")] {
        write(dir, "bad.xml", &scene(w, h, ""));
        refused(
            &run(dir, &["plan", "bad.xml"]),
            1,
            error,
            &format!("{w} x {h}"),
        )?;
    }
    write(dir, "one.xml", &scene("1", "1", ""));
    accepted(&run(dir, &["plan", "one.xml"]), "1 x 1")?;
    // The largest width is read (then refused for its pixels).
    write(dir, "max.xml", &scene("4294967295", "1", ""));
    not_for(&run(dir, &["plan", "max.xml"]), error, "4294967295 x 1")
}

fn model_depth(dir: &Path, error: &str) -> Result<(), String> {
    let model = |d: &str| format!(r#"  <model type="whitted" depth="{d}"/>"#) + "\n";
    write(dir, "over.xml", &scene("16", "12", &model("10001")));
    refused(&run(dir, &["plan", "over.xml"]), 1, error, "depth 10001")?;
    write(dir, "at.xml", &scene("16", "12", &model("10000")));
    accepted(
        &run(dir, &["--no-gui", "at.xml", "-out", "at.png"]),
        "depth 10000",
    )
}

fn xml(dir: &Path, error: &str) -> Result<(), String> {
    let good = scene("16", "12", "");
    write(dir, "tag.xml", &good.replace("</sphere>", "</sphre>"));
    refused(
        &run(dir, &["plan", "tag.xml"]),
        1,
        error,
        "a mismatched tag",
    )?;
    write(dir, "after.xml", &(good.clone() + "<scene/>\n"));
    refused(
        &run(dir, &["plan", "after.xml"]),
        1,
        "after the end of the <scene> element",
        "a second root",
    )?;
    write(dir, "good.xml", &good);
    accepted(&run(dir, &["plan", "good.xml"]), "well-formed")
}

// ----- rendering -----

fn anti_aliasing(dir: &Path, error: &str) -> Result<(), String> {
    for n in ["17", "0", "-1"] {
        let o = run(dir, &["--no-gui", "tiny.xml", "--aa", n]);
        refused(&o, 2, error, &format!("--aa {n}"))?;
        refused(&o, 2, &format!("not \"{n}\""), &format!("--aa {n}"))?;
    }
    accepted(
        &run(
            dir,
            &["--no-gui", "tiny.xml", "--aa", "16", "-out", "a.png"],
        ),
        "--aa 16",
    )
}

fn threads(dir: &Path, error: &str) -> Result<(), String> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let max = (4 * cores).min(1024);
    let over = (max + 1).to_string();
    for n in [over.as_str(), "0", "-1"] {
        let o = run(dir, &["--no-gui", "tiny.xml", "--threads", n]);
        refused(&o, 2, error, &format!("--threads {n}"))?;
        refused(&o, 2, &format!("from 1 to {max} "), "four per core")?;
    }
    accepted(
        &run(
            dir,
            &[
                "--no-gui",
                "tiny.xml",
                "--threads",
                &max.to_string(),
                "-out",
                "t.png",
            ],
        ),
        "--threads at four per core",
    )
}

fn region(dir: &Path, error: &str) -> Result<(), String> {
    for r in ["0,0,17,12", "0,0,16,13", "3,0,3,12"] {
        let o = run(dir, &["tiny.xml", "--region", r, "-out", "p.png"]);
        let pattern = if r == "3,0,3,12" { "is empty" } else { error };
        refused(&o, 2, pattern, &format!("--region {r}"))?;
    }
    accepted(
        &run(dir, &["tiny.xml", "--region", "0,0,16,12", "-out", "p.png"]),
        "the whole image",
    )
}

fn pass_memory(dir: &Path, error: &str) -> Result<(), String> {
    // 2^28 pixels of f64 values, in 2 GiB of address space: refused
    // before rendering (else an allocation fails, or hours of work).
    write(dir, "big.xml", &scene("16384", "16384", ""));
    let limit = format!("--as={}", 2u64 << 30);
    let guard = ["timeout", "120", "prlimit", limit.as_str(), "--"];
    for args in [
        &["big.xml", "--pass", "depth", "-out", "d.png"][..],
        &["big.xml", "-out", "x.exr"],
    ] {
        refused(&run_with(dir, &guard, args), 1, error, &format!("{args:?}"))?;
    }
    accepted(
        &run_with(
            dir,
            &guard,
            &["tiny.xml", "--pass", "depth", "-out", "d.exr"],
        ),
        "a small pass",
    )
}

fn split_tasks(dir: &Path, error: &str) -> Result<(), String> {
    refused(
        &run(dir, &["split", "tiny.xml", "--tasks", "193"]),
        2,
        error,
        "193 tasks for 192 pixels",
    )?;
    refused(
        &run(dir, &["split", "tiny.xml", "--tasks", "0"]),
        2,
        "--tasks expects",
        "0 tasks",
    )?;
    let o = run(dir, &["split", "tiny.xml", "--tasks", "192"]);
    accepted(&o, "192 tasks")?;
    match stdout(&o).lines().count() {
        192 => Ok(()),
        n => Err(format!("192 tasks printed {n} regions")),
    }
}

fn runs(dir: &Path, error: &str) -> Result<(), String> {
    for command in ["bench", "study"] {
        for k in ["1001", "0", "-1"] {
            let o = run(dir, &[command, "--runs", k]);
            refused(&o, 2, error, &format!("{command} --runs {k}"))?;
        }
    }
    // 1000 is read: the bench then stops at its CSV's missing folder,
    // checked before the work.
    let o = run(
        dir,
        &["bench", "--runs", "1000", "--csv", "gone/b.csv", "-q"],
    );
    refused(&o, 1, "the folder gone does not exist", "bench --runs 1000")
}

fn split_size(dir: &Path, error: &str) -> Result<(), String> {
    for size in ["16385", "7", "-1"] {
        let o = run(dir, &["bench", "--split-size", size]);
        refused(&o, 2, error, &format!("--split-size {size}"))?;
    }
    for size in ["0", "8", "16384"] {
        let o = run(
            dir,
            &["bench", "--split-size", size, "--csv", "gone/b.csv", "-q"],
        );
        refused(
            &o,
            1,
            "the folder gone does not exist",
            &format!("--split-size {size}"),
        )?;
    }
    Ok(())
}

fn big_spheres(dir: &Path, error: &str) -> Result<(), String> {
    for n in ["4000001", "-1", "a million"] {
        let o = run(dir, &["bench", "--big-spheres", n]);
        refused(&o, 2, error, &format!("--big-spheres {n}"))?;
    }
    for n in ["0", "4000000"] {
        let o = run(
            dir,
            &["bench", "--big-spheres", n, "--csv", "gone/b.csv", "-q"],
        );
        refused(
            &o,
            1,
            "the folder gone does not exist",
            &format!("--big-spheres {n}"),
        )?;
    }
    Ok(())
}

// ----- output -----

fn the_scene_itself(dir: &Path, error: &str) -> Result<(), String> {
    fs::hard_link(dir.join("tiny.xml"), dir.join("hard.png")).unwrap();
    std::os::unix::fs::symlink("tiny.xml", dir.join("soft.png")).unwrap();
    for out in ["./tiny.xml", "hard.png", "soft.png"] {
        refused(&run(dir, &["tiny.xml", "-out", out]), 1, error, out)?;
        refused(
            &run(dir, &["export-pov", "tiny.xml", "-out", out]),
            1,
            error,
            out,
        )?;
    }
    if fs::read_to_string(dir.join("tiny.xml")).unwrap() != TINY {
        return Err("the scene was written".into());
    }
    accepted(
        &run(dir, &["tiny.xml", "-out", "other.png"]),
        "another file",
    )
}

fn folder(dir: &Path, error: &str) -> Result<(), String> {
    accepted(
        &run(
            dir,
            &["tiny.xml", "--region", "0,0,16,12", "-out", "part.png"],
        ),
        "a part",
    )?;
    for (args, path) in [
        (&["tiny.xml", "-out", "gone/x.png"][..], "gone/x.png"),
        (&["bench", "--csv", "gone/b.csv", "-q"], "gone/b.csv"),
        (&["sheet", "-out", "gone/s.png", "part.png"], "gone/s.png"),
        (
            &[
                "edit",
                "tiny.xml",
                "--set",
                "model.depth=1",
                "-out",
                "gone/e.xml",
            ],
            "gone/e.xml",
        ),
        (
            &["export-pov", "tiny.xml", "-out", "gone/x.pov"],
            "gone/x.pov",
        ),
        (
            &["assemble", "-out", "gone/a.png", "part.png"],
            "gone/a.png",
        ),
    ] {
        let o = run(dir, args);
        refused(&o, 1, error, path)?;
        refused(&o, 1, &format!("{path}: the folder gone "), path)?;
        if stderr(&o).contains(".tmp") {
            return Err(format!("{path}: names a temporary file: {}", stderr(&o)));
        }
    }
    accepted(
        &run(dir, &["tiny.xml", "-out", "x.png"]),
        "a folder that exists",
    )
}

fn transformation(dir: &Path, error: &str) -> Result<(), String> {
    let with = |second: &str| {
        scene("16", "12", "").replace(
            r#"<translate z="3"/>"#,
            &format!(r#"<translate x="1e308"/><translate x="{second}"/><translate z="3"/>"#),
        )
    };
    write(dir, "far.xml", &with("1e308"));
    refused(&run(dir, &["plan", "far.xml"]), 1, error, "1e308 twice")?;
    write(dir, "back.xml", &with("-1e308"));
    accepted(&run(dir, &["plan", "back.xml"]), "1e308 and back")
}

fn not_writable(dir: &Path, error: &str) -> Result<(), String> {
    if !common::is_root() {
        return Err("needs root, to own files as other users".into());
    }
    // Another user's private image in a folder anyone may write.
    let team = dir.join("team");
    fs::create_dir(&team).unwrap();
    fs::set_permissions(&team, fs::Permissions::from_mode(0o777)).unwrap();
    fs::set_permissions(dir.join("tiny.xml"), fs::Permissions::from_mode(0o644)).unwrap();
    let theirs = team.join("x.png");
    fs::write(&theirs, "theirs").unwrap();
    std::os::unix::fs::lchown(&theirs, Some(4242), Some(4242)).unwrap();
    fs::set_permissions(&theirs, fs::Permissions::from_mode(0o600)).unwrap();
    let nobody = [
        "setpriv",
        "--reuid=65534",
        "--regid=65534",
        "--clear-groups",
    ];
    let o = run_with(dir, &nobody, &["tiny.xml", "-out", "team/x.png"]);
    refused(&o, 1, error, "another user's mode-600 file")?;
    if fs::read(&theirs).unwrap() != b"theirs" {
        return Err("the file was replaced".into());
    }
    fs::set_permissions(&theirs, fs::Permissions::from_mode(0o666)).unwrap();
    let o = run_with(dir, &nobody, &["tiny.xml", "-out", "team/x.png"]);
    accepted(&o, "a file anyone may write")
}

fn link_loop(dir: &Path, error: &str) -> Result<(), String> {
    std::os::unix::fs::symlink("loop.png", dir.join("loop.png")).unwrap();
    refused(
        &run(dir, &["tiny.xml", "-out", "loop.png"]),
        1,
        error,
        "a loop",
    )?;
    if !fs::symlink_metadata(dir.join("loop.png"))
        .unwrap()
        .is_symlink()
    {
        return Err("the link was replaced".into());
    }
    // 40 links in a row are followed, as the kernel follows them.
    let mut next = "end.png".to_owned();
    for k in 0..40 {
        let name = format!("l{k}.png");
        std::os::unix::fs::symlink(&next, dir.join(&name)).unwrap();
        next = name;
    }
    accepted(&run(dir, &["tiny.xml", "-out", &next]), "40 links")?;
    match dir.join("end.png").exists() {
        true => Ok(()),
        false => Err("the chain of 40 links was not written through".into()),
    }
}

fn read_only(dir: &Path, error: &str) -> Result<(), String> {
    let path = dir.join("x.png");
    fs::write(&path, "old").unwrap();
    fs::set_permissions(&path, fs::Permissions::from_mode(0o444)).unwrap();
    refused(&run(dir, &["tiny.xml", "-out", "x.png"]), 1, error, "0444")?;
    refused(
        &run(dir, &["export-pov", "tiny.xml", "-out", "x.png"]),
        1,
        error,
        "0444",
    )?;
    if fs::read(&path).unwrap() != b"old" {
        return Err("the read-only file was replaced".into());
    }
    fs::set_permissions(&path, fs::Permissions::from_mode(0o644)).unwrap();
    accepted(&run(dir, &["tiny.xml", "-out", "x.png"]), "0644")
}

/// The format's side limit: one pixel more is refused before rendering,
/// the limit itself is written.
fn side_limit(dir: &Path, error: &str, ext: &str, max: u32) -> Result<(), String> {
    let over = (max + 1).to_string();
    write(dir, "over.xml", &scene(&over, "1", ""));
    write(dir, "tall.xml", &scene("1", &over, ""));
    let out = format!("x.{ext}");
    for s in ["over.xml", "tall.xml"] {
        refused(
            &run(dir, &[s, "-out", &out]),
            1,
            error,
            &format!("{s} to {ext}"),
        )?;
    }
    write(dir, "at.xml", &scene(&max.to_string(), "1", ""));
    accepted(
        &run(dir, &["at.xml", "-out", &out]),
        &format!("{max} to {ext}"),
    )
}

fn jpeg_gif_tga_size(dir: &Path, error: &str) -> Result<(), String> {
    for ext in ["jpg", "gif", "tga"] {
        let error = error.replacen("jpg", ext, 1);
        side_limit(dir, &error, ext, 65_535)?;
    }
    Ok(())
}

fn webp_size(dir: &Path, error: &str) -> Result<(), String> {
    side_limit(dir, error, "webp", 16_383)
}

fn image_to_special(dir: &Path, error: &str) -> Result<(), String> {
    common::mkfifo(&dir.join("pipe.png"));
    refused(
        &run(dir, &["tiny.xml", "-out", "pipe.png"]),
        1,
        error,
        "a FIFO",
    )?;
    std::os::unix::fs::symlink("/dev/null", dir.join("null.png")).unwrap();
    refused(
        &run(dir, &["tiny.xml", "-out", "null.png"]),
        1,
        "null.png: is a character device, not an image file",
        "a link to /dev/null",
    )?;
    accepted(&run(dir, &["tiny.xml", "-out", "x.png"]), "a regular file")
}

fn text_to_special(dir: &Path, error: &str) -> Result<(), String> {
    let pipe = dir.join("pipe.pov");
    common::mkfifo(&pipe);
    let o = run(dir, &["export-pov", "tiny.xml", "-out", "pipe.pov"]);
    refused(&o, 1, error, "a FIFO nobody reads")?;
    // With a reader, the text goes into the FIFO, which stays one.
    let reader = std::thread::spawn(move || fs::read_to_string(pipe).unwrap());
    let start = std::time::Instant::now();
    loop {
        let o = run(dir, &["export-pov", "tiny.xml", "-out", "pipe.pov"]);
        if o.status.success() {
            break;
        }
        if start.elapsed().as_secs() > 10 {
            return Err(format!("a FIFO with a reader: {}", stderr(&o)));
        }
    }
    let text = reader.join().unwrap();
    if !text.contains("sphere") {
        return Err(format!("the FIFO got {text:?}"));
    }
    accepted(
        &run(dir, &["export-pov", "tiny.xml", "-out", "/dev/null"]),
        "/dev/null",
    )?;
    if fs::metadata("/dev/null").unwrap().is_file() {
        return Err("/dev/null was replaced".into());
    }
    // The shell's pipe through /proc's links (`-out /dev/stdout | less`):
    // written into; no file is made beside it (none can be, in /proc).
    let edit = ["edit", "tiny.xml", "--set", "model.depth=3", "-out"];
    for out in ["/dev/stdout", "/proc/self/fd/1"] {
        for args in [&["export-pov", "tiny.xml", "-out"][..], &edit] {
            let args = [args, &[out]].concat();
            let o = run(dir, &args);
            accepted(&o, &format!("{args:?} into a pipe"))?;
            if !stdout(&o).contains("sphere") {
                return Err(format!("{args:?}: the pipe got {:?}", stdout(&o)));
            }
        }
    }
    // The shell's redirection to a file (`-out /dev/stdout > s.pov`): the
    // text in the file the shell opened.
    let o = run_with(
        dir,
        &["sh", "-c", r#"exec "$0" "$@" >redirected.xml"#],
        &[&edit[..], &["/dev/stdout"]].concat(),
    );
    accepted(&o, "edit -out /dev/stdout > redirected.xml")?;
    let text = fs::read_to_string(dir.join("redirected.xml")).unwrap();
    if !text.contains("depth=\"3\"") {
        return Err(format!("the redirected file got {text:?}"));
    }
    Ok(())
}

fn full_disk(dir: &Path, error: &str) -> Result<(), String> {
    let o = run(dir, &["export-pov", "tiny.xml", "-out", "/dev/full"]);
    refused(&o, 1, &format!("/dev/full: {error}"), "/dev/full")?;
    let o = run_with(
        dir,
        &["sh", "-c", r#"exec "$0" "$@" >/dev/full"#],
        &["plan", "tiny.xml"],
    );
    refused(&o, 1, error, "stdout on /dev/full")
}

fn closed_stdout(dir: &Path, error: &str) -> Result<(), String> {
    let closed = ["sh", "-c", r#"exec "$0" "$@" >&-"#];
    for args in [
        &["plan", "tiny.xml"][..],
        &["split", "tiny.xml", "--tasks", "3"],
        &["explain", "tiny.xml", "8", "6"],
        &["-time", "tiny.xml", "-out", "t.png"],
        &["--help"],
        &["--version"],
    ] {
        refused(
            &run_with(dir, &closed, args),
            1,
            error,
            &format!("{args:?}"),
        )?;
    }
    if dir.join("t.png").exists() {
        return Err("-time rendered before finding stdout closed".into());
    }
    // A reader that stops early: no error.
    let head = [
        "bash",
        "-c",
        r#"set -o pipefail; "$0" "$@" | head -c 10 >/dev/null"#,
    ];
    accepted(
        &run_with(
            dir,
            &head,
            &["explain", "tiny.xml", "8", "6", "--json", "--aa", "16"],
        ),
        "| head",
    )?;
    accepted(&run(dir, &["plan", "tiny.xml"]), "a stdout")
}

fn sticky_links(dir: &Path, error: &str) -> Result<(), String> {
    if !common::is_root() {
        return Err("needs root, to own files as other users".into());
    }
    // A /tmp of our own: anyone may write, the sticky bit set, owned by
    // root. A link in it owned by user 4242 points to a file elsewhere.
    let sticky = dir.join("tmp");
    fs::create_dir(&sticky).unwrap();
    fs::set_permissions(&sticky, fs::Permissions::from_mode(0o1777)).unwrap();
    let elsewhere = dir.join("elsewhere");
    fs::create_dir(&elsewhere).unwrap();
    fs::set_permissions(&elsewhere, fs::Permissions::from_mode(0o777)).unwrap();
    fs::set_permissions(dir.join("tiny.xml"), fs::Permissions::from_mode(0o644)).unwrap();
    let link = sticky.join("out.png");
    std::os::unix::fs::symlink(elsewhere.join("victim.png"), &link).unwrap();
    std::os::unix::fs::lchown(&link, Some(4242), Some(4242)).unwrap();
    let nobody = [
        "setpriv",
        "--reuid=65534",
        "--regid=65534",
        "--clear-groups",
    ];
    let o = run_with(dir, &nobody, &["tiny.xml", "-out", "tmp/out.png"]);
    refused(&o, 1, error, "another user's link in a sticky folder")?;
    if elsewhere.join("victim.png").exists() {
        return Err("the link was followed".into());
    }
    // The user's own link is followed.
    std::os::unix::fs::lchown(&link, Some(65534), Some(65534)).unwrap();
    let o = run_with(dir, &nobody, &["tiny.xml", "-out", "tmp/out.png"]);
    accepted(&o, "one's own link")?;
    if !elsewhere.join("victim.png").exists() {
        return Err("one's own link was not written through".into());
    }
    Ok(())
}

// ----- sheet, assemble, explain -----

fn sheet_columns(dir: &Path, error: &str) -> Result<(), String> {
    accepted(&run(dir, &["tiny.xml", "-out", "a.png"]), "an image")?;
    for n in ["0", "-1"] {
        let o = run(dir, &["sheet", "-out", "s.png", "--columns", n, "a.png"]);
        refused(&o, 2, error, &format!("--columns {n}"))?;
    }
    accepted(
        &run(dir, &["sheet", "-out", "s.png", "--columns", "1", "a.png"]),
        "--columns 1",
    )
}

fn sheet_image(dir: &Path, error: &str) -> Result<(), String> {
    // A PNG whose header says 16385 × 16384: refused from the header,
    // nothing decoded (its pixels are not even there).
    let file = fs::File::create(dir.join("past.png")).unwrap();
    let mut encoder = png::Encoder::new(file, 16_385, 16_384);
    encoder.set_color(png::ColorType::Rgb);
    let mut writer = encoder.write_header().unwrap();
    // One IDAT chunk, for decoders that read the header up to the pixels.
    writer.write_chunk(png::chunk::IDAT, &[0x78, 0x01]).unwrap();
    drop(writer);
    refused(
        &run(dir, &["sheet", "-out", "s.png", "past.png"]),
        1,
        error,
        "16385 x 16384",
    )?;
    accepted(&run(dir, &["tiny.xml", "-out", "a.png"]), "an image")?;
    accepted(&run(dir, &["sheet", "-out", "s.png", "a.png"]), "16 x 12")
}

fn sheet_pixels(dir: &Path, error: &str) -> Result<(), String> {
    // 2200 pictures of 16384 × 1 in one column: cells of 16384 × (1 + 22)
    // with 8-pixel gaps make a sheet of about 16400 × 68200, over 2^30.
    let strip = image::RgbImage::new(16_384, 1);
    let mut names = Vec::new();
    for k in 0..2200 {
        let name = format!("s{k}.png");
        strip.save(dir.join(&name)).unwrap();
        names.push(name);
    }
    let mut args = vec!["sheet", "-out", "sheet.png", "--columns", "1"];
    args.extend(names.iter().map(String::as_str));
    let guard = ["timeout", "120"];
    refused(&run_with(dir, &guard, &args), 1, error, "16400 x 68200")?;
    if dir.join("sheet.png").exists() {
        return Err("a sheet was written".into());
    }
    accepted(
        &run(dir, &["sheet", "-out", "sheet.png", "s0.png", "s1.png"]),
        "two strips",
    )
}

fn assemble_open_parts(dir: &Path, error: &str) -> Result<(), String> {
    // 40 parts of one column each: every row crosses all 40.
    write(dir, "wide.xml", &scene("40", "2", ""));
    let mut parts = Vec::new();
    for x in 0..40 {
        let (region, out) = (format!("{x},0,{},2", x + 1), format!("p{x}.png"));
        accepted(
            &run(dir, &["wide.xml", "--region", &region, "-out", &out]),
            "a part",
        )?;
        parts.push(out);
    }
    let assemble = |nofile: &str| {
        let mut args = vec!["assemble", "-out", "a.png"];
        args.extend(parts.iter().map(String::as_str));
        let limit = format!("--nofile={nofile}");
        run_with(dir, &["prlimit", &limit, "--"], &args)
    };
    // At most 24 open files, soft and hard: refused before writing.
    refused(&assemble("24:24"), 1, error, "40 parts, 24 files")?;
    if dir.join("a.png").exists() {
        return Err("an image was written".into());
    }
    // A soft limit of 24 under a hard one of 4096 is raised.
    accepted(&assemble("24:4096"), "40 parts, soft 24, hard 4096")
}

fn explain_pixel(dir: &Path, error: &str) -> Result<(), String> {
    for (x, y) in [("16", "0"), ("0", "12"), ("4294967295", "0")] {
        refused(
            &run(dir, &["explain", "tiny.xml", x, y]),
            2,
            error,
            &format!("({x}, {y})"),
        )?;
    }
    refused(
        &run(dir, &["explain", "tiny.xml", "-1", "0"]),
        2,
        "<X> expects a pixel number",
        "(-1, 0)",
    )?;
    accepted(&run(dir, &["explain", "tiny.xml", "15", "11"]), "(15, 11)")
}

fn explain_tree(dir: &Path, _: &str) -> Result<(), String> {
    // 256 rays of 300 bounces between two mirrors: their trees whole take
    // more than 384 MiB; written as they are made, one tree at a time.
    write(dir, "mirrors.xml", &mirrors_text(300, 16, 12));
    let limit = format!("--as={}", 384u64 << 20);
    let script = r#"exec "$0" "$@" >/dev/null"#;
    let guard = [
        "timeout",
        "120",
        "prlimit",
        limit.as_str(),
        "--",
        "sh",
        "-c",
        script,
    ];
    let args = ["explain", "mirrors.xml", "8", "6", "--json", "--aa", "16"];
    accepted(
        &run_with(dir, &guard, &args),
        "--aa 16 of 300 bounces in 384 MiB",
    )
}

// ----- lsp -----

/// `rayoflight lsp` with `input` on its stdin (closed after it).
fn lsp_with(dir: &Path, input: &[u8]) -> Output {
    use std::io::Write;
    let mut child = Command::new(bin())
        .arg("lsp")
        .current_dir(dir)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary runs");
    child.stdin.take().unwrap().write_all(input).unwrap();
    child.wait_with_output().unwrap()
}

fn lsp_message(dir: &Path, error: &str) -> Result<(), String> {
    let framed = |body: &str| format!("Content-Length: {}\r\n\r\n{body}", body.len());
    let session = |middle: &str| {
        [
            framed(
                r#"{"jsonrpc":"2.0","id":1,"method":"initialize","params":{"capabilities":{}}}"#,
            ),
            framed(r#"{"jsonrpc":"2.0","method":"initialized","params":{}}"#),
            middle.to_owned(),
            framed(r#"{"jsonrpc":"2.0","id":2,"method":"shutdown"}"#),
            framed(r#"{"jsonrpc":"2.0","method":"exit"}"#),
        ]
        .concat()
    };
    // One byte over the limit, announced: refused at its header (the
    // editor then goes without sending it: status 1).
    let over = format!("Content-Length: {}\r\n\r\n", 536_870_913u64);
    refused(
        &lsp_with(dir, session(&over).as_bytes()),
        1,
        error,
        "over the limit",
    )?;
    // A message under it is taken.
    let open = framed(
        r#"{"jsonrpc":"2.0","method":"textDocument/didOpen","params":{"textDocument":{"uri":"file:///s.xml","languageId":"xml","version":1,"text":"<scene/>"}}}"#,
    );
    accepted(
        &lsp_with(dir, session(&open).as_bytes()),
        "a message under it",
    )
}
