//! Output faults, driven through the built binary: a full disk (a small
//! tmpfs, filled), a read-only directory, a read-only image. Each must give
//! a clear error (exit 1), leave no partial file and keep the old file as
//! it was.
//!
//! Permission checks do not apply to root, so where the tests run as root
//! the binary is run as `nobody` (util-linux `runuser`).
#![cfg(unix)]

use crate::common;

use crate::common::{TINY, files_in, stderr};
use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::{Command, Output};

/// Runs the binary headless; as `nobody` when we are root, so that file
/// permissions mean something.
fn run(dir: &Path, args: &[&str], unprivileged: bool) -> Output {
    let bin = env!("CARGO_BIN_EXE_rayoflight");
    let mut command = if unprivileged && common::is_root() {
        let mut c = Command::new("runuser");
        c.args(["-u", "nobody", "--", bin]);
        c
    } else {
        Command::new(bin)
    };
    command
        .arg("--no-gui")
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .output()
        .expect("the binary runs")
}

/// A directory anyone may enter, holding the tiny scene.
#[test]
fn a_full_disk_is_reported_and_the_old_image_kept() {
    // A full file system of its own: an 8 KiB tmpfs, filled, mounted in a
    // private mount namespace (unshare) so that nothing else sees it.
    let dir = common::folder_with(&[("tiny.xml", TINY)]);
    let full = dir.path().join("full");
    fs::create_dir(&full).unwrap();
    let script = format!(
        "mount -t tmpfs -o size=8k tmpfs '{full}' && echo old > '{full}/out.png' \
         && (dd if=/dev/zero of='{full}/filler' bs=1k count=64 2>/dev/null; true) \
         && '{bin}' --no-gui tiny.xml -out full/out.png; status=$?; \
         ls -A '{full}' >&2; cat '{full}/out.png' >&2; exit $status",
        full = full.display(),
        bin = env!("CARGO_BIN_EXE_rayoflight"),
    );
    let mut command = Command::new("unshare");
    if !common::is_root() {
        command.arg("--map-root-user");
    }
    let o = command
        .args(["--mount", "sh", "-c", &script])
        .current_dir(dir.path())
        .env_remove("DISPLAY")
        .output()
        .expect("unshare runs");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("full/out.png: No space left on device"),
        "{err}"
    );
    // No temporary file left, the old image as it was.
    assert!(err.ends_with("filler\nout.png\nold\n"), "{err}");
}

#[test]
fn a_read_only_directory_is_reported_without_leftovers() {
    let dir = common::folder_with(&[("tiny.xml", TINY)]);
    let out = dir.path().join("ro");
    fs::create_dir(&out).unwrap();
    fs::set_permissions(&out, fs::Permissions::from_mode(0o555)).unwrap();
    let o = run(dir.path(), &["tiny.xml", "-out", "ro/x.png"], true);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with("ro/x.png: ") && stderr(&o).contains("ermission denied"),
        "{}",
        stderr(&o)
    );
    assert!(files_in(&out).is_empty());
}

#[test]
fn a_read_only_image_is_not_replaced() {
    let dir = common::folder_with(&[("tiny.xml", TINY)]);
    let image = dir.path().join("tiny.png");
    fs::write(&image, b"old").unwrap();
    fs::set_permissions(&image, fs::Permissions::from_mode(0o444)).unwrap();
    let o = run(dir.path(), &["tiny.xml"], false);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("read-only"), "{}", stderr(&o));
    assert_eq!(fs::read(&image).unwrap(), b"old");
    assert_eq!(files_in(dir.path()), ["tiny.png", "tiny.xml"]);
}

#[test]
fn an_unreadable_scene_is_reported() {
    let dir = common::folder_with(&[("tiny.xml", TINY)]);
    fs::set_permissions(
        dir.path().join("tiny.xml"),
        fs::Permissions::from_mode(0o000),
    )
    .unwrap();
    let o = run(dir.path(), &["tiny.xml"], true);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with("tiny.xml: ") && stderr(&o).contains("ermission denied"),
        "{}",
        stderr(&o)
    );
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}
