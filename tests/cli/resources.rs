//! Resources: under a memory or open-file limit (`prlimit`, util-linux),
//! the binary succeeds in bounded memory or refuses in one line, before
//! the work, saying what it needs: never an abort with a backtrace.
//!
//! - `explain --json` of 16 rays of 10 000 bounces (134 MB of JSON) in
//!   256 MB of address space: it writes as it traces (it held 1.3 GB).
//! - Threads that do not spend the address space (glibc's arenas): a
//!   render fits in the same limit with 8 threads as with 2.
//! - Passes and EXR files in about the plain render's memory: 3 bytes a
//!   pixel for a pass's picture, 8 for the depth's, 12 for an EXR (they
//!   took 27 to 42), and past what the system gives, a refusal naming the
//!   bytes before the first ray.
//! - `sheet`: a render's largest image (16384²) is taken; an image past a
//!   render's pixels is refused from its header; a sheet past its size
//!   limit or its memory is refused before anything is decoded.
//! - `assemble`: 2000 parts across a row under a soft limit of 1024 open
//!   files (the soft limit is raised to the hard one); under a hard limit
//!   too low, refused before any pixel is read, the limit named.
//! - `edit` out of descriptors says so, blaming no other program.
//! - A write past the file-size limit fails in one line, nothing left.
#![cfg(target_os = "linux")]

use crate::common;

use crate::common::{files_in, rayoflight, stderr};
use rayoflight::cluster::part::{self, Part};
use rayoflight::render::region::Region;
use rayoflight::render::request::RenderRequest;
use rayoflight::scene;
use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const MB: u64 = 1 << 20;

/// The binary under `prlimit` with these limits (`--as=…`, `--nofile=…`),
/// run in `dir`.
fn limited(limits: &[String], dir: &Path, args: &[&str]) -> Command {
    let mut c = Command::new("prlimit");
    c.args(limits)
        .arg(env!("CARGO_BIN_EXE_rayoflight"))
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    c
}

fn address_space(bytes: u64) -> Vec<String> {
    vec![format!("--as={bytes}")]
}

fn run(mut c: Command) -> Output {
    c.output().expect("prlimit (util-linux) runs the binary")
}

/// A refusal: exit 1, one line on stderr, no backtrace.
fn one_line_refusal(o: &Output, what: &str) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{what}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err}");
    assert!(
        !err.contains("backtrace") && !err.contains("panicked"),
        "{err}"
    );
    err.trim_end().to_owned()
}

fn sphere(width: u32, height: u32) -> String {
    common::TINY.replace(
        r#"width="16" height="12""#,
        &format!(r#"width="{width}" height="{height}""#),
    )
}

#[test]
fn explain_json_of_256_megabytes_of_rays_streams_in_256_mb() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(
        dir.path().join("mirrors.xml"),
        common::mirrors_text(10_000, 64, 48),
    )
    .unwrap();
    let mut c = limited(
        &address_space(256 * MB),
        dir.path(),
        &["explain", "mirrors.xml", "10", "10", "--json", "--aa", "4"],
    );
    let mut child = c
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read as it comes: the count, the start and the end.
    let mut stdout = child.stdout.take().unwrap();
    let (mut count, mut start, mut end) = (0usize, Vec::new(), Vec::new());
    let mut chunk = vec![0; 1 << 16];
    loop {
        let n = stdout.read(&mut chunk).unwrap();
        if n == 0 {
            break;
        }
        if start.len() < 64 {
            start.extend_from_slice(&chunk[..n.min(64)]);
        }
        end.extend_from_slice(&chunk[..n]);
        let keep = end.len().saturating_sub(64);
        end.drain(..keep);
        count += n;
    }
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    // 16 rays of 10 001 hits each, and the first one's again at the top.
    assert!(count > 100_000_000, "{count} bytes");
    assert!(start.starts_with(br#"{"x":10,"y":10,"traced":[10,10],"model":"whitted","rgb8":["#));
    assert!(end.ends_with(b"\"reason\":\"depth\"}}]}\n"), "{end:?}");
}

/// Under an address-space limit the threads do not spend it: each one
/// that allocates took an arena of glibc's that reserves 64 MiB, so the
/// 4096² depth pass that fits in 256 MB with the default threads was
/// refused with `--threads 4` three runs out of four, with `--threads 8`
/// every time (src/cli/allocator.rs: one arena under a limit).
#[test]
fn more_threads_fit_in_the_same_address_space() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("s4k.xml"), sphere(4096, 4096)).unwrap();
    for threads in ["8", "8", "4"] {
        let o = run(limited(
            &address_space(256 * MB),
            d,
            &[
                "--no-gui",
                "s4k.xml",
                "-q",
                "--threads",
                threads,
                "--pass",
                "depth",
                "-out",
                "depth.png",
            ],
        ));
        assert!(o.status.success(), "--threads {threads}: {}", stderr(&o));
    }
}

#[test]
fn passes_and_exr_take_about_the_plain_renders_memory_or_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("s4k.xml"), sphere(4096, 4096)).unwrap();
    fs::write(d.join("s3k.xml"), sphere(3072, 3072)).unwrap();
    // 4096²: the plain render keeps 50 MB of pixels; a pass's picture the
    // same, the depth's 134 MB (t in f64 until the range is known). Each
    // took 450 MB (27 bytes a pixel) and aborted in 256 MB.
    for args in [
        &["--pass", "normal", "-out", "normal.png"][..],
        &["--pass", "depth", "-out", "depth.png"][..],
        &["-out", "plain.png"][..],
    ] {
        let mut all = vec!["--no-gui", "s4k.xml", "-q"];
        all.extend_from_slice(args);
        let o = run(limited(&address_space(256 * MB), d, &all));
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    }
    // 3072² in EXR: 113 MB of f32 values, the file encoded into a
    // scratch file, not memory (it took 350 MB).
    let o = run(limited(
        &address_space(256 * MB),
        d,
        &[
            "--no-gui",
            "s3k.xml",
            "-q",
            "--pass",
            "depth",
            "-out",
            "depth.exr",
        ],
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    let exr = image::open(d.join("depth.exr")).unwrap().to_rgb32f();
    assert_eq!(exr.dimensions(), (3072, 3072));
    let t = exr.get_pixel(1536, 1536).0[0];
    assert!((t - 4.0).abs() < 1e-3, "t = {t} at the sphere's front");
    // Past what the system gives: refused before the first ray, in one
    // line that names the bytes, nothing written.
    for (args, pixels) in [
        (
            &["-out", "big.exr"][..],
            "at 4096×4096 needs 268 MB of memory (268435456 bytes)",
        ),
        (
            &["--pass", "depth", "-out", "big.png"][..],
            "needs 201 MB of memory (201326592 bytes)",
        ),
    ] {
        let mut all = vec!["--no-gui", "s4k.xml", "-q"];
        all.extend_from_slice(args);
        let o = run(limited(&address_space(160 * MB), d, &all));
        let err = one_line_refusal(&o, &format!("{args:?}"));
        assert!(err.contains(pixels), "{err}");
        assert!(err.contains(", but only "), "{err}");
    }
    assert!(
        !files_in(d).iter().any(|f| f.starts_with("big")),
        "{:?}",
        files_in(d)
    );
    // The plain render too.
    let o = run(limited(
        &address_space(64 * MB),
        d,
        &["--no-gui", "s4k.xml", "-q", "-out", "big.png"],
    ));
    let err = one_line_refusal(&o, "plain");
    assert!(
        err.starts_with("big.png: rendering the image at 4096×4096 needs "),
        "{err}"
    );
}

/// The start of a PNG of a `width × height` RGB image (signature, IHDR,
/// the first IDAT) and its end, with no pixels: what a decoder reads
/// before the pixels.
fn png_header_only(width: u32, height: u32) -> Vec<u8> {
    fn crc(bytes: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 == 1 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc(&body).to_be_bytes());
        out
    };
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0, 0, 0, 1]));
    png.extend(chunk(b"IEND", &[]));
    png
}

#[test]
fn a_sheet_takes_the_largest_render_and_refuses_what_is_past_its_limits() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The largest square a render may be: 16384², 805 MB decoded (past
    // the image crate's default limit of 512 MB, which refused it).
    let side = 16384;
    let file = fs::File::create(d.join("huge.png")).unwrap();
    rayoflight::output::write_png(std::io::BufWriter::new(file), side, side, &[], |band| {
        band.fill(200);
        Ok(())
    })
    .unwrap();
    let o = rayoflight(d, &["sheet", "-out", "sheet.png", "huge.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (w, h) = image::image_dimensions(d.join("sheet.png")).unwrap();
    let gap = rayoflight::cluster::sheet::GAP;
    assert_eq!(
        (w, h),
        (
            side + 2 * gap,
            side + rayoflight::cluster::sheet::LABEL_HEIGHT + 2 * gap
        )
    );
    // An image past a render's pixels: refused from its header.
    fs::write(d.join("past.png"), png_header_only(side + 1, side)).unwrap();
    let o = rayoflight(d, &["sheet", "-out", "no.png", "past.png"]);
    let err = one_line_refusal(&o, "past the limit");
    assert_eq!(
        err,
        "past.png: a 16385×16384 image has more than the 268435456 pixels (2^28) a render may have"
    );
    // 5000 renders of 600×600: a 43176×44738 sheet (5.8 GB), refused by
    // its size before anything is decoded (it took 10.9 GB, or aborted).
    fs::write(d.join("small.xml"), sphere(600, 600)).unwrap();
    let o = rayoflight(d, &["--no-gui", "small.xml", "-out", "small.png", "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut args = vec!["sheet", "-out", "no.png"];
    args.extend(std::iter::repeat_n("small.png", 5000));
    let o = run(limited(&address_space(256 * MB), d, &args));
    let err = one_line_refusal(&o, "5000 images");
    assert!(
        err.contains(
            "make a 43176×44738 sheet (1931607888 pixels), more than the limit of 1073741824 (2^30)"
        ),
        "{err}"
    );
    // A sheet the memory cannot hold: refused, the bytes named.
    let o = run(limited(
        &address_space(96 * MB),
        d,
        &["sheet", "-out", "no.png", "huge.png"],
    ));
    let err = one_line_refusal(&o, "memory");
    assert!(
        err.starts_with("no.png: the 16400×16422 contact sheet needs "),
        "{err}"
    );
    assert!(!d.join("no.png").exists());
}

/// `count` parts of a `count × 3` image, one column each, written with
/// their records (as `--region` writes them, without rendering).
fn column_parts(dir: &Path, count: u32) -> (Vec<PathBuf>, Vec<u8>) {
    let text = sphere(count, 3);
    let scene = scene::parse(&text, Path::new("columns.xml")).unwrap();
    let options = RenderRequest::default().options(&scene);
    let mut whole = vec![0u8; count as usize * 3 * 3];
    let parts = (0..count)
        .map(|x| {
            let region = Region::new(x, 0, x + 1, 3).unwrap();
            let record = Part::new(&scene, &options, region).to_string();
            let path = PathBuf::from(format!("c{x}.png"));
            let file = fs::File::create(dir.join(&path)).unwrap();
            let mut y = 0;
            let colour = [x as u8, (x >> 8) as u8, 77];
            rayoflight::output::write_png(file, 1, 3, &[(part::KEYWORD, &record)], |band| {
                for row in band.chunks_exact_mut(3) {
                    row.copy_from_slice(&colour);
                    let at = (y * count as usize + x as usize) * 3;
                    whole[at..at + 3].copy_from_slice(&colour);
                    y += 1;
                }
                Ok(())
            })
            .unwrap();
            path
        })
        .collect();
    (parts, whole)
}

#[test]
fn assemble_raises_its_open_file_limit_or_refuses_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (parts, whole) = column_parts(d, 2000);
    let names: Vec<&str> = parts.iter().map(|p| p.to_str().unwrap()).collect();
    // 2000 parts across every row, a soft limit of 1024 under a hard 4096.
    let mut args = vec!["assemble", "-out", "whole.png"];
    args.extend(&names);
    let o = run(limited(&["--nofile=1024:4096".to_owned()], d, &args));
    assert!(o.status.success(), "{}", stderr(&o));
    let image = image::open(d.join("whole.png")).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (2000, 3));
    assert!(image.into_raw() == whole, "each column where it belongs");
    // 300 parts across under a hard limit of 256: refused before any
    // pixel is read, the limit named; nothing written.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (parts, _) = column_parts(d, 300);
    let names: Vec<&str> = parts.iter().map(|p| p.to_str().unwrap()).collect();
    let mut args = vec!["assemble", "-out", "whole.png"];
    args.extend(&names);
    let o = run(limited(&["--nofile=256:256".to_owned()], d, &args));
    let err = one_line_refusal(&o, "256 files");
    assert!(
        err.starts_with(
            "300 parts cross row 0 of the image and must be open together, but this process may open 256 files at once ("
        ),
        "{err}"
    );
    assert!(err.contains("hard limit 256"), "{err}");
    assert!(!d.join("whole.png").exists());
}

/// Under a file-size limit (`ulimit -f`, `prlimit --fsize`), a write that
/// would pass it fails like any other: one line, status 1, the temporary
/// file removed and the file it was to replace as it was. (SIGXFSZ ended
/// the process with status 153, its temporary file left beside the file.)
#[test]
fn a_file_size_limit_fails_the_write_and_leaves_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let scene = sphere(64, 48);
    fs::write(dir.path().join("scene.xml"), &scene).unwrap();
    fs::write(dir.path().join("old.png"), b"the old image").unwrap();
    let before = files_in(dir.path());
    // The limit is below the scene's size: every write of it passes it.
    let fsize = vec![format!("--fsize={}", scene.len() / 2)];
    for args in [
        &["scene.xml", "-out", "new.png"][..],
        &["scene.xml", "-out", "old.png"],
        &["edit", "scene.xml", "--set", "camera.width=65"],
        &["export-pov", "scene.xml", "-out", "scene.pov"],
    ] {
        let o = run(limited(&fsize, dir.path(), args));
        let err = one_line_refusal(&o, &args.join(" "));
        assert!(err.contains("File too large"), "{args:?}: {err}");
        assert_eq!(files_in(dir.path()), before, "{args:?}");
        assert_eq!(
            fs::read_to_string(dir.path().join("scene.xml")).unwrap(),
            scene
        );
        assert_eq!(
            fs::read(dir.path().join("old.png")).unwrap(),
            b"the old image"
        );
    }
}

/// Under an open-file limit, `edit` either edits or says in one line that
/// it ran out of descriptors, leaving the file as it was: never that
/// another program changed the file (with 5 descriptors, reading the file
/// again before the rename failed, and the failure was taken for a change
/// 8 times over).
#[test]
fn out_of_descriptors_edit_says_so_and_blames_no_one() {
    let dir = tempfile::tempdir().unwrap();
    let scene = sphere(16, 12);
    let mut edited_at = None;
    // (Under 4 the dynamic loader itself fails.)
    for nofile in 4..=12 {
        fs::write(dir.path().join("scene.xml"), &scene).unwrap();
        let limit = vec![format!("--nofile={nofile}")];
        let args = ["edit", "scene.xml", "--set", "camera.width=17"];
        let o = run(limited(&limit, dir.path(), &args));
        let now = fs::read_to_string(dir.path().join("scene.xml")).unwrap();
        assert_eq!(files_in(dir.path()), ["scene.xml"], "{nofile}");
        if o.status.success() {
            assert_eq!(now, scene.replace(r#"width="16""#, r#"width="17""#));
            edited_at.get_or_insert(nofile);
            continue;
        }
        let err = one_line_refusal(&o, &format!("--nofile={nofile}"));
        assert!(err.contains("Too many open files"), "{nofile}: {err}");
        assert!(!err.contains("another program"), "{nofile}: {err}");
        assert_eq!(now, scene, "{nofile}");
    }
    assert!(edited_at.is_some_and(|n| n <= 8), "{edited_at:?}");
}

/// `study` on a 4000×4000 scene under 256 MB of address
/// space refused in one line before printing anything, with or without
/// more threads; it aborted ("memory allocation of 144096000 bytes
/// failed") when it drew a failure's picture. The same scene at a size
/// that fits is studied.
#[test]
fn study_refuses_a_scene_past_the_memory_left_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let example = rayoflight::EXAMPLE_SCENE;
    let at = |w: u32, h: u32| {
        let start = example.find("<camera width=").unwrap();
        let end = start + example[start..].find("eyeDistance").unwrap();
        format!(
            "{}<camera width=\"{w}\" height=\"{h}\" {}",
            &example[..start],
            &example[end..]
        )
    };
    fs::write(dir.path().join("s4k.xml"), at(4000, 4000)).unwrap();
    fs::write(dir.path().join("small.xml"), at(64, 48)).unwrap();
    for threads in [&[][..], &["--threads", "8"][..]] {
        let mut args = vec!["study", "--out", "st", "--runs", "1"];
        args.extend(threads);
        args.push("s4k.xml");
        let o = run(limited(&address_space(256 << 20), dir.path(), &args));
        let err = one_line_refusal(&o, "study");
        assert!(
            err.starts_with("s4k: the study at 4000×4000 needs "),
            "{err}"
        );
        assert_eq!(common::stdout(&o), "", "nothing printed before");
    }
    let o = run(limited(
        &address_space(256 << 20),
        dir.path(),
        &["study", "--out", "st", "--runs", "1", "small.xml"],
    ));
    assert!(o.status.success(), "{}", stderr(&o));
}
