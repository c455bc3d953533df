//! Every input is checked before any work (through the built binary): a
//! thread count past the machine's bound, a scene or output that is a FIFO
//! or a device, an oversized file, an output folder that does not exist, a
//! format too small for the image. Each is refused at once, in one line
//! naming the user's path, and nothing is written. Names stay the user's
//! bytes.
#![cfg(unix)]

use crate::common;

use crate::common::{TINY, files_in, mirrors_text, stderr};
use std::ffi::OsStr;
use std::fs;
use std::os::unix::ffi::OsStrExt;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs the binary headless in `dir`; fails the test if it has not ended
/// within `limit` (it is killed: a hang must not hang the suite).
fn run_within(dir: &Path, args: &[&OsStr], limit: Duration) -> Output {
    // Renders never open a window; subcommands never do anyway.
    let headless: &[&str] = if args.first().is_some_and(|a| *a == "edit") {
        &[]
    } else {
        &["--no-gui"]
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .args(headless)
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "{args:?} still running after {limit:?}; stderr: {}",
                stderr(&out)
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}

fn args(list: &[&str]) -> Vec<&'static OsStr> {
    list.iter()
        .map(|s| OsStr::new(Box::leak(s.to_string().into_boxed_str())))
        .collect()
}

/// A refusal: `status`, one line starting with `starts`, nothing written.
fn refused(dir: &Path, given: &[&str], status: i32, starts: &str) -> String {
    let before = files_in(dir);
    let o = run_within(dir, &args(given), Duration::from_secs(5));
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(status), "{given:?}: {err}");
    assert!(err.starts_with(starts), "{given:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{given:?}: {err}");
    assert!(!err.contains(".rayoflight-"), "a temporary name: {err}");
    assert_eq!(files_in(dir), before, "{given:?} wrote something");
    err
}

/// A folder with the tiny scene and a slow one (minutes of work: a
/// refusal that came after rendering would time out).
#[test]
fn a_thread_count_past_the_bound_is_a_usage_error_at_once() {
    let dir = common::folder_with(&[
        ("tiny.xml", TINY),
        ("slow.xml", &mirrors_text(10_000, 640, 360)),
    ]);
    let err = refused(
        dir.path(),
        &["tiny.xml", "--threads", "1000000000", "-out", "t.png"],
        2,
        "rayoflight: --threads expects an integer from 1 to ",
    );
    assert!(err.contains("four per core"), "{err}");
}

#[test]
fn fifos_and_devices_are_refused_before_opening_them() {
    let dir = common::folder_with(&[
        ("tiny.xml", TINY),
        ("slow.xml", &mirrors_text(10_000, 640, 360)),
    ]);
    common::mkfifo(&dir.path().join("pipe.xml"));
    common::mkfifo(&dir.path().join("pipe.png"));
    refused(
        dir.path(),
        &["pipe.xml"],
        1,
        "pipe.xml: is a FIFO, not a scene file",
    );
    refused(
        dir.path(),
        &["slow.xml", "-out", "pipe.png"],
        1,
        "pipe.png: is a FIFO, not an image file",
    );
    // The edited text to a FIFO nobody reads: refused, not blocked on.
    let o = run_within(
        dir.path(),
        &args(&[
            "edit",
            "tiny.xml",
            "--set",
            "model.depth=3",
            "-out",
            "pipe.png",
        ]),
        Duration::from_secs(5),
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(stderr(&o), "pipe.png: a FIFO that no program is reading\n");
    // /dev/zero never ends: refused from its metadata, not read.
    refused(
        dir.path(),
        &["/dev/zero", "-out", "z.png"],
        1,
        "/dev/zero: is a character device, not a scene file",
    );
}

#[test]
fn an_oversized_scene_is_refused_without_reading_it() {
    let dir = common::folder_with(&[
        ("tiny.xml", TINY),
        ("slow.xml", &mirrors_text(10_000, 640, 360)),
    ]);
    // Sparse: a GiB and one byte that takes no room on disk.
    let big = fs::File::create(dir.path().join("big.xml")).unwrap();
    big.set_len((1 << 30) + 1).unwrap();
    let start = Instant::now();
    refused(
        dir.path(),
        &["big.xml", "-out", "b.png"],
        1,
        "big.xml: the file is 1073741825 bytes, more than the limit",
    );
    assert!(start.elapsed() < Duration::from_secs(2), "it read the file");
}

#[test]
fn the_output_is_checked_before_rendering() {
    let dir = common::folder_with(&[
        ("tiny.xml", TINY),
        ("slow.xml", &mirrors_text(10_000, 640, 360)),
    ]);
    refused(
        dir.path(),
        &["slow.xml", "-out", "no/such/folder/out.png"],
        1,
        "no/such/folder/out.png: the folder no/such/folder does not exist",
    );
    refused(
        dir.path(),
        &["slow.xml", "-out", "tiny.xml/out.png"],
        1,
        "tiny.xml/out.png: tiny.xml is not a folder",
    );
    fs::create_dir(dir.path().join("dir.png")).unwrap();
    refused(
        dir.path(),
        &["slow.xml", "-out", "dir.png"],
        1,
        "dir.png: is a directory",
    );
    // JPEG holds 65535 pixels a side: a wider image is refused before its
    // (endless) render.
    fs::write(dir.path().join("wide.xml"), mirrors_text(10_000, 70_000, 2)).unwrap();
    refused(
        dir.path(),
        &["wide.xml", "-out", "wide.jpg"],
        1,
        "wide.jpg: jpg cannot hold a 70000×2 image (at most 65535 pixels a side)",
    );
}

#[test]
fn output_names_are_the_users_bytes() {
    let dir = common::folder_with(&[
        ("tiny.xml", TINY),
        ("slow.xml", &mirrors_text(10_000, 640, 360)),
    ]);
    let name = OsStr::from_bytes(b"bad\xff.png");
    let o = run_within(
        dir.path(),
        &[OsStr::new("tiny.xml"), OsStr::new("-out"), name],
        Duration::from_secs(20),
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        dir.path().join(name).is_file(),
        "{:?}",
        files_in(dir.path())
    );
    // An empty name is a usage error, said on one line.
    refused(dir.path(), &["tiny.xml", "-out", ""], 2, "rayoflight: ");
}
