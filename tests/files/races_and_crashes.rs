//! The CLI at the system's edges, through the built
//! binary: links another user planted in a shared folder, as the last
//! part of a path or a folder part, renames racing a write, files of
//! other users, hard links, concurrent writers, signals, names that hold
//! code or terminal escapes, a loop of links.
//!
//! Tests that act as other users need root (CI runs as root): they make
//! those users' files themselves and run the binary with `setpriv`. The
//! users are numbers (1 is Debian's `daemon`, 65534 `nobody`; 4001, 4002
//! and the group 4000 need no entry in /etc/passwd).
#![cfg(unix)]

use crate::common;

use crate::common::{TINY, files_in, stderr};
use std::fs;
use std::os::unix::fs::{MetadataExt, PermissionsExt, symlink};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_rayoflight");

/// Whether a test that needs root can run: it must in CI.
fn root_or_skip(test: &str) -> bool {
    if common::is_root() {
        return true;
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "{test} needs root, and CI runs as root"
    );
    eprintln!("{test}: skipped, it needs root");
    false
}

/// A folder every user may enter and read (a tempdir is 0700).
fn open_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fs::set_permissions(dir.path(), fs::Permissions::from_mode(0o755)).unwrap();
    dir
}

/// The binary run as `uid`:`gid` (with `groups` as its other groups) in
/// `dir`.
fn run_as(uid: u32, gid: u32, groups: &[u32], dir: &Path, args: &[&str]) -> Output {
    let mut cmd = Command::new("setpriv");
    cmd.arg(format!("--reuid={uid}"))
        .arg(format!("--regid={gid}"));
    if groups.is_empty() {
        cmd.arg("--clear-groups");
    } else {
        let list: Vec<String> = groups.iter().map(u32::to_string).collect();
        cmd.arg(format!("--groups={}", list.join(",")));
    }
    cmd.arg(BIN)
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("setpriv runs")
}

/// A shell command run as `uid` (the kernel's own verdict, for comparison).
fn shell_as(uid: u32, dir: &Path, script: &str) -> Output {
    Command::new("setpriv")
        .args([
            &format!("--reuid={uid}"),
            &format!("--regid={uid}"),
            "--clear-groups",
            "sh",
            "-c",
            script,
        ])
        .current_dir(dir)
        .output()
        .unwrap()
}

fn rayoflight(dir: &Path, args: &[&str]) -> Output {
    common::rayoflight(dir, args)
}

fn chown(path: &Path, uid: u32, gid: u32) {
    std::os::unix::fs::lchown(path, Some(uid), Some(gid)).unwrap();
}

fn mode(path: &Path, mode: u32) {
    fs::set_permissions(path, fs::Permissions::from_mode(mode)).unwrap();
}

/// Sets `fs.protected_symlinks` for as long as it lives, then puts the old
/// value back; `None` where /proc/sys cannot be written (a container).
struct ProtectedSymlinks(String);

const PROTECTED: &str = "/proc/sys/fs/protected_symlinks";

impl ProtectedSymlinks {
    fn on() -> Option<ProtectedSymlinks> {
        let old = fs::read_to_string(PROTECTED).ok()?;
        fs::write(PROTECTED, "1").ok()?;
        Some(ProtectedSymlinks(old.trim().to_owned()))
    }
}

impl Drop for ProtectedSymlinks {
    fn drop(&mut self) {
        let _ = fs::write(PROTECTED, &self.0);
    }
}

/// Item 1: in a sticky folder everyone may write, a link that another user
/// planted is not followed by any command that writes (render, edit -out,
/// export-pov -out) — as the kernel's rule refuses `echo x > link` — and
/// the file it points to is untouched. The caller's own link, and the
/// folder owner's, are followed.
#[test]
fn links_another_user_planted_in_a_shared_folder_are_not_followed() {
    if !root_or_skip("links_another_user_planted_in_a_shared_folder_are_not_followed") {
        return;
    }
    let dir = open_dir();
    let root = dir.path();
    fs::write(root.join("scene.xml"), TINY).unwrap();
    mode(&root.join("scene.xml"), 0o644);
    // The victim's file, which user 65534 may write through its folder.
    let victim = root.join("victim");
    fs::create_dir(&victim).unwrap();
    mode(&victim, 0o777);
    let important = victim.join("important.txt");
    fs::write(&important, "important\n").unwrap();
    mode(&important, 0o666);
    // The shared folder, root's, sticky and writable by all; user 1 plants
    // a link to the victim's file.
    let shared = root.join("shared");
    fs::create_dir(&shared).unwrap();
    mode(&shared, 0o1777);
    let planted = shared.join("x.png");
    symlink(&important, &planted).unwrap();
    chown(&planted, 1, 1);

    let kernel = ProtectedSymlinks::on();
    if kernel.is_some() {
        // The oracle: the kernel refuses the same write.
        let o = shell_as(65534, root, "echo x > shared/x.png");
        assert!(!o.status.success(), "the kernel followed the link");
    }
    for args in [
        vec!["scene.xml", "-out", "shared/x.png"],
        vec![
            "edit",
            "scene.xml",
            "--set",
            "camera.width=8",
            "-out",
            "shared/x.png",
        ],
        vec!["export-pov", "scene.xml", "-out", "shared/x.png"],
    ] {
        let o = run_as(65534, 65534, &[], root, &args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert_eq!(
            stderr(&o),
            "shared/x.png: not followed: the symbolic link shared/x.png is another user's, \
             in the shared folder shared (sticky and writable by all): the kernel's \
             fs.protected_symlinks rule\n",
            "{args:?}"
        );
        assert_eq!(fs::read_to_string(&important).unwrap(), "important\n");
        assert!(fs::symlink_metadata(&planted).unwrap().is_symlink());
        assert_eq!(files_in(&shared), ["x.png"], "{args:?} left a file");
    }
    drop(kernel);

    // The caller's own link is followed: the file it points to is replaced.
    let own = shared.join("own.png");
    symlink(&important, &own).unwrap();
    chown(&own, 65534, 65534);
    let o = run_as(
        65534,
        65534,
        &[],
        root,
        &["scene.xml", "-out", "shared/own.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(fs::read(&important).unwrap().starts_with(b"\x89PNG"));
    assert!(fs::symlink_metadata(&own).unwrap().is_symlink());

    // So is a link of the folder's owner.
    let theirs = root.join("theirs");
    fs::create_dir(&theirs).unwrap();
    chown(&theirs, 1, 1);
    mode(&theirs, 0o1777);
    let target = victim.join("b.pov");
    fs::write(&target, "old").unwrap();
    mode(&target, 0o666);
    symlink(&target, theirs.join("b.pov")).unwrap();
    chown(&theirs.join("b.pov"), 1, 1);
    let o = run_as(
        65534,
        65534,
        &[],
        root,
        &["export-pov", "scene.xml", "-out", "theirs/b.pov"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        fs::read_to_string(&target)
            .unwrap()
            .contains("#version 3.7;")
    );
}

/// Item 3: in a setgid folder that a group may write, a member may not
/// replace another member's private image nor their read-only-for-others
/// scene (the kernel's `access(W_OK)`, not the folder's permission, is
/// what counts), and nothing changes owner. A file the member may write is
/// replaced keeping its group and mode; root keeps the owner too, and the
/// extended attributes.
#[test]
fn a_file_the_caller_may_not_write_is_not_replaced_and_replaced_files_keep_their_owner() {
    if !root_or_skip("a_file_the_caller_may_not_write_is_not_replaced") {
        return;
    }
    let (a, b, group) = (4001, 4002, 4000);
    let dir = open_dir();
    let root = dir.path();
    let shared = root.join("team");
    fs::create_dir(&shared).unwrap();
    chown(&shared, a, group);
    mode(&shared, 0o2775);
    let file = |name: &str, text: &[u8], m: u32| {
        let p = shared.join(name);
        fs::write(&p, text).unwrap();
        chown(&p, a, group);
        mode(&p, m);
        p
    };
    let image = file("private.png", b"a's image", 0o600);
    let scene = file("scene.xml", TINY.as_bytes(), 0o644);
    let other = file("other.xml", TINY.as_bytes(), 0o644);

    let o = run_as(
        b,
        b,
        &[group],
        &shared,
        &["other.xml", "-out", "private.png"],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(
        stderr(&o),
        "private.png: permission denied: you may not write this file\n"
    );
    let o = run_as(
        b,
        b,
        &[group],
        &shared,
        &["edit", "scene.xml", "--set", "camera.width=8"],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(
        stderr(&o),
        "scene.xml: permission denied: you may not write this file\n"
    );
    assert_eq!(fs::read(&image).unwrap(), b"a's image");
    assert_eq!(fs::read_to_string(&scene).unwrap(), TINY);
    for p in [&image, &scene] {
        let m = fs::metadata(p).unwrap();
        assert_eq!((m.uid(), m.gid()), (a, group), "{}", p.display());
    }
    assert_eq!(files_in(&shared), ["other.xml", "private.png", "scene.xml"]);

    // A file of a's that the group may write: b replaces it; b cannot give
    // it back to a, but it keeps its group and mode.
    let group_file = file("group.png", b"old", 0o664);
    let o = run_as(b, b, &[group], &shared, &["other.xml", "-out", "group.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = fs::metadata(&group_file).unwrap();
    assert_eq!((m.gid(), m.mode() & 0o7777), (group, 0o664));
    assert!(fs::read(&group_file).unwrap().starts_with(b"\x89PNG"));

    // Root replaces a's file: owner, group, mode and attributes stay.
    let kept = file("kept.xml", TINY.as_bytes(), 0o640);
    let xattr = rustix::fs::setxattr(
        &kept,
        "user.rayoflight-test",
        b"hello",
        rustix::fs::XattrFlags::empty(),
    )
    .is_ok();
    let o = rayoflight(&shared, &["edit", "kept.xml", "--set", "camera.width=8"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(fs::read_to_string(&kept).unwrap().contains("width=\"8\""));
    let m = fs::metadata(&kept).unwrap();
    assert_eq!((m.uid(), m.gid(), m.mode() & 0o7777), (a, group, 0o640));
    if xattr {
        let mut value = [0u8; 16];
        let n = rustix::fs::getxattr(&kept, "user.rayoflight-test", &mut value[..]).unwrap();
        assert_eq!(&value[..n], b"hello");
    } else {
        eprintln!("this file system keeps no user attributes: not checked");
    }
    let _ = other;
}

/// Item 4: `edit` on a file with two names writes the file itself: the
/// other name sees the new text, the inode is the same, no copy is left.
/// A render over an image with two names does the same.
#[test]
fn hard_links_keep_sharing_the_new_text() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.xml");
    fs::write(&a, TINY).unwrap();
    fs::hard_link(&a, dir.path().join("b.xml")).unwrap();
    let inode = fs::metadata(&a).unwrap().ino();
    let o = rayoflight(dir.path(), &["edit", "a.xml", "--set", "camera.width=8"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let b = fs::read_to_string(dir.path().join("b.xml")).unwrap();
    assert!(b.contains("width=\"8\""), "{b}");
    assert_eq!(fs::read_to_string(&a).unwrap(), b);
    assert_eq!(fs::metadata(&a).unwrap().ino(), inode);
    assert_eq!(fs::metadata(&a).unwrap().nlink(), 2);
    assert_eq!(files_in(dir.path()), ["a.xml", "b.xml"]);

    fs::write(dir.path().join("img.png"), "old").unwrap();
    fs::hard_link(dir.path().join("img.png"), dir.path().join("copy.png")).unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", "a.xml", "-out", "img.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let copy = fs::read(dir.path().join("copy.png")).unwrap();
    assert!(copy.starts_with(b"\x89PNG"));
    assert_eq!(fs::read(dir.path().join("img.png")).unwrap(), copy);
    assert_eq!(
        files_in(dir.path()),
        ["a.xml", "b.xml", "copy.png", "img.png"]
    );
}

/// `n` spheres, each with its own `ka`.
fn spheres(n: usize) -> String {
    let mut text = String::from("<scene>\n");
    for i in 0..n {
        text.push_str(&format!(
            "  <sphere><material ka=\"0.1\" kd=\"0.5\" ks=\"0.2\" m=\"10\"/>\
             <transformation><translate x=\"{i}\" z=\"30\"/></transformation></sphere>\n"
        ));
    }
    text.push_str("  <light x=\"0\" y=\"-3\" z=\"-3\"/>\n");
    text.push_str("  <camera width=\"16\" height=\"12\" eyeDistance=\"2\"/>\n</scene>\n");
    text
}

fn spawn(dir: &Path, args: &[&str]) -> Child {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Item 5: twenty `edit`s at once, each setting another sphere's `ka`:
/// every one of the twenty changes is in the file.
#[test]
fn concurrent_edits_keep_every_change() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.xml");
    fs::write(&path, spheres(20)).unwrap();
    let children: Vec<Child> = (1..=20)
        .map(|i| {
            let set = format!("object[{i}].material.ka=0.{}1", 10 + i);
            spawn(dir.path(), &["edit", "q.xml", "--set", &set])
        })
        .collect();
    for child in children {
        let o = child.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let text = fs::read_to_string(&path).unwrap();
    for i in 1..=20 {
        assert!(
            text.contains(&format!("ka=\"0.{}1\"", 10 + i)),
            "edit {i} lost"
        );
    }
    assert_eq!(files_in(dir.path()), ["q.xml"]);
}

/// Whether a temporary file of ours with bytes in it is in `dir` (the
/// empty one that checks the folder takes new files, before any work, is
/// not the write).
fn writing_in(dir: &Path) -> bool {
    fs::read_dir(dir).into_iter().flatten().flatten().any(|e| {
        e.file_name().to_string_lossy().starts_with(".rayoflight-")
            && e.metadata().is_ok_and(|m| m.len() > 0)
    })
}

/// Waits until a temporary file of ours appears in `dir` (or `child`
/// ends); returns whether one did.
fn wait_for_temporary(dir: &Path, child: &mut Child) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(60) {
        if writing_in(dir) {
            return true;
        }
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    false
}

fn signal(child: &Child, signal: rustix::process::Signal) {
    let pid = rustix::process::Pid::from_child(child);
    rustix::process::kill_process(pid, signal).unwrap();
}

/// Item 5, a writer that takes no lock (an editor saving by rename): it
/// writes between `edit`'s read and its rename (the edit is stopped there
/// with SIGSTOP while the editor writes). `edit` reads the file again
/// before renaming, merges its change onto the editor's and keeps both.
#[test]
fn a_writer_without_the_lock_is_merged_not_lost() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.xml");
    // Big enough that writing it takes far longer than noticing it.
    let text = spheres(150_000);
    fs::write(&path, &text).unwrap();
    let mut child = spawn(
        dir.path(),
        &["edit", "q.xml", "--set", "object[2].material.ka=0.75"],
    );
    assert!(wait_for_temporary(dir.path(), &mut child), "no write seen");
    signal(&child, rustix::process::Signal::STOP);
    // The editor's save: a new light, through a rename.
    let theirs = text.replace("  <camera", "  <light x=\"9\" y=\"9\" z=\"9\"/>\n  <camera");
    let editor = dir.path().join("editor.tmp");
    fs::write(&editor, &theirs).unwrap();
    fs::rename(&editor, &path).unwrap();
    signal(&child, rustix::process::Signal::CONT);
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let now = fs::read_to_string(&path).unwrap();
    assert!(
        now.contains("<light x=\"9\" y=\"9\" z=\"9\"/>"),
        "the editor's light lost"
    );
    assert_eq!(now.matches("ka=\"0.75\"").count(), 1, "the edit lost");
    assert_eq!(files_in(dir.path()), ["q.xml"]);
}

/// Item 6: SIGINT, SIGTERM and SIGHUP sent when the temporary file appears
/// (render, a --region part, edit, sheet): the temporary file is gone, the
/// old file untouched, the exit says so with 128 + the signal.
#[test]
fn a_signal_during_a_write_leaves_nothing_behind() {
    use rustix::process::Signal;
    let dir = tempfile::tempdir().unwrap();
    let big = TINY.replace(
        "width=\"16\" height=\"12\"",
        "width=\"4000\" height=\"3000\"",
    );
    fs::write(dir.path().join("big.xml"), &big).unwrap();
    fs::write(dir.path().join("q.xml"), spheres(150_000)).unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", "big.xml", "-out", "a.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    fs::copy(dir.path().join("a.png"), dir.path().join("b.png")).unwrap();
    let cases: [(&[&str], &str, Signal, i32); 5] = [
        (
            &["--no-gui", "big.xml", "-out", "old.png"],
            "old.png",
            Signal::TERM,
            143,
        ),
        (
            &["--no-gui", "big.xml", "-out", "old.png"],
            "old.png",
            Signal::INT,
            130,
        ),
        (
            &[
                "--no-gui",
                "big.xml",
                "--region",
                "0,0,4000,2900",
                "-out",
                "old.png",
            ],
            "old.png",
            Signal::HUP,
            129,
        ),
        (
            &["edit", "q.xml", "--set", "camera.width=8"],
            "q.xml",
            Signal::TERM,
            143,
        ),
        (
            &["sheet", "-out", "old.png", "a.png", "b.png"],
            "old.png",
            Signal::TERM,
            143,
        ),
    ];
    for (args, target, sig, status) in cases {
        let q = fs::read(dir.path().join("q.xml")).unwrap();
        // The signal is sent when the temporary file is seen; a busy
        // machine may run the write to its end before it lands (the
        // process then dies of it after the rename, outside any write):
        // that attempt says nothing, and the case is run again.
        let mut attempts = 0;
        let (o, before, listing) = loop {
            attempts += 1;
            fs::write(dir.path().join("old.png"), b"the old file").unwrap();
            fs::write(dir.path().join("q.xml"), &q).unwrap();
            let before = fs::read(dir.path().join(target)).unwrap();
            let listing = files_in(dir.path());
            let mut child = spawn(dir.path(), args);
            // A write quicker than the watch (PNG bands deflate on every
            // core) ends before its temporary file is seen: that attempt
            // says nothing either.
            if !wait_for_temporary(dir.path(), &mut child) {
                assert!(
                    attempts < 10,
                    "{args:?}: no write seen in {attempts} attempts"
                );
                let _ = child.wait_with_output();
                continue;
            }
            signal(&child, sig);
            let o = child.wait_with_output().unwrap();
            let too_late = o.status.code().is_none()
                && fs::read(dir.path().join(target)).unwrap() != before
                && files_in(dir.path()) == listing;
            if too_late && attempts < 10 {
                continue;
            }
            break (o, before, listing);
        };
        assert_eq!(o.status.code(), Some(status), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).ends_with("interrupted: nothing was written\n"),
            "{args:?}: {}",
            stderr(&o)
        );
        assert_eq!(
            fs::read(dir.path().join(target)).unwrap(),
            before,
            "{args:?}"
        );
        assert_eq!(files_in(dir.path()), listing, "{args:?} left a file");
    }
}

/// Item 2: a scene file whose name holds a newline and POV-Ray code:
/// `export-pov`'s header keeps it inside a comment, names the file written
/// and an image beside it that is not RayOfLight's, and its command, run
/// by a shell, renders with POV-Ray and writes nothing else.
#[test]
fn a_file_name_never_becomes_pov_ray_code() {
    let dir = tempfile::tempdir().unwrap();
    let name = "s\n#fopen F \"pwned.txt\" write\n#write (F, \"x\")\n#fclose F\n.xml";
    fs::write(dir.path().join(name), TINY).unwrap();
    let o = rayoflight(dir.path(), &["export-pov", name, "-out", "my scene's.pov"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let pov = fs::read_to_string(dir.path().join("my scene's.pov")).unwrap();
    let header: Vec<&str> = pov.lines().take_while(|l| !l.is_empty()).collect();
    assert!(header.iter().all(|l| l.starts_with("// ")), "{pov}");
    let command = header
        .iter()
        .find_map(|l| l.strip_prefix("// Render: "))
        .expect("a render command");
    assert!(
        command.ends_with(
            "'Input_File_Name=\"my scene'\\''s.pov\"' 'Output_File_Name=\"my scene'\\''s-pov.png\"'"
        ),
        "{command}"
    );
    if !common::tool("povray", "povray") {
        return;
    }
    // POV-Ray reads its configuration from HOME: an empty one.
    let home = dir.path().join("home");
    fs::create_dir_all(home.join(".povray/3.7")).unwrap();
    fs::write(home.join(".povray/3.7/povray.conf"), "").unwrap();
    let o = Command::new("sh")
        .args(["-c", &format!("{command} -D")])
        .current_dir(dir.path())
        .env("HOME", &home)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.path().join("my scene's-pov.png").exists());
    assert!(!dir.path().join("pwned.txt").exists());
}

/// Item 2, the terminal: an error naming a file whose name holds escape
/// sequences and newlines is one line, the escapes shown, not obeyed.
#[test]
fn errors_show_escapes_in_names_on_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let name = "evil\u{1b}]0;owned\u{7}\n\u{1b}[2Jname.xml";
    fs::write(dir.path().join(name), "<scene>").unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", name]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert_eq!(err.matches('\n').count(), 1, "{err:?}");
    assert!(!err.contains('\u{1b}') && !err.contains('\u{7}'), "{err:?}");
    assert!(
        err.starts_with("evil\\e]0;owned\\x07\\n\\e[2Jname.xml:"),
        "{err:?}"
    );
}

/// Item 16: a loop of links as `-out` is refused before rendering, the
/// link left as it is; a link to the shell's pipe is named a pipe.
#[test]
fn a_loop_of_links_and_a_pipe_are_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.xml"), TINY).unwrap();
    symlink("loop.png", dir.path().join("loop.png")).unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", "s.xml", "-out", "loop.png"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        "loop.png: a loop of symbolic links (or more than 40 in a row)\n"
    );
    assert!(
        fs::symlink_metadata(dir.path().join("loop.png"))
            .unwrap()
            .is_symlink()
    );
    assert_eq!(files_in(dir.path()), ["loop.png", "s.xml"]);

    symlink("/dev/stdout", dir.path().join("out.png")).unwrap();
    let o = Command::new(BIN)
        .args(["--no-gui", "s.xml", "-out", "out.png"])
        .current_dir(dir.path())
        .stdout(Stdio::piped())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stderr(&o), "out.png: is a pipe, not an image file\n");
    let _: PathBuf = dir.path().join("unused");
}

/// Item 5, the app's side: a save waits for the lock an `edit` holds, and
/// then finds the file that `edit` wrote (a new light) and merges its own
/// unsaved edit onto it, instead of writing over it.
#[cfg(feature = "gui")]
#[test]
fn the_apps_save_waits_for_the_lock_and_merges() {
    use rayoflight::scene::edit::{Edit, Field, Value};
    use rayoflight::session::document::Reload;
    let (_dir, path, mut doc) = common::document_on(TINY);
    doc.apply(Edit::Set(
        Field::parse("object[1].material.ka").unwrap(),
        Value::Number(0.75),
    ))
    .unwrap();
    let lock = rayoflight::system::files::lock_for_update(&path).unwrap();
    let save = std::thread::spawn(move || doc.save());
    std::thread::sleep(Duration::from_millis(300));
    assert!(!save.is_finished(), "the save did not wait for the lock");
    // What `edit` does under its lock: a new text renamed into place.
    let theirs = TINY.replace("  <camera", "  <light x=\"9\" y=\"9\" z=\"9\"/>\n  <camera");
    let new = path.with_extension("new");
    fs::write(&new, &theirs).unwrap();
    fs::rename(&new, &path).unwrap();
    drop(lock);
    assert_eq!(save.join().unwrap().unwrap(), Reload::Merged);
    let now = fs::read_to_string(&path).unwrap();
    assert!(now.contains("<light x=\"9\" y=\"9\" z=\"9\"/>"), "{now}");
    assert!(now.contains("ka=\"0.75\""), "{now}");
}

/// An `edit` waiting for the lock another holds is still ended by SIGTERM
/// at once (nothing of its own to clean up yet), the file untouched.
#[test]
fn an_edit_waiting_for_the_lock_still_obeys_a_signal() {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.xml");
    fs::write(&path, TINY).unwrap();
    let lock = rayoflight::system::files::lock_for_update(&path).unwrap();
    let mut child = spawn(dir.path(), &["edit", "q.xml", "--set", "camera.width=8"]);
    std::thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "the edit did not wait");
    signal(&child, rustix::process::Signal::TERM);
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(5), "SIGTERM ignored");
        std::thread::sleep(Duration::from_millis(10));
    }
    let status = child.wait().unwrap();
    assert_eq!(status.signal(), Some(15), "{status:?}");
    drop(lock);
    assert_eq!(fs::read_to_string(&path).unwrap(), TINY);
    assert_eq!(files_in(dir.path()), ["q.xml"]);
}

/// Runs `attack` on a thread of its own as user `uid` (its group the
/// same number): what it makes is that user's, as another user on the
/// machine would make it. The test process keeps root.
fn as_user<T: Send + 'static>(uid: u32, attack: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::spawn(move || {
        become_user(uid);
        attack()
    })
    .join()
    .unwrap()
}

/// The calling thread becomes user `uid` (its group the same number),
/// the rest of the process staying as it is.
fn become_user(uid: u32) {
    use rustix::process::{Gid, Uid};
    let (gid, uid) = (Gid::from_raw(uid), Uid::from_raw(uid));
    rustix::thread::set_thread_res_gid(gid, gid, gid).unwrap();
    rustix::thread::set_thread_res_uid(uid, uid, uid).unwrap();
}

/// A folder of root's that no one else may enter, with a file in it: what
/// another user must never have written.
fn victim_file() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim.txt");
    fs::write(&victim, "export PATH=/usr/bin\n").unwrap();
    mode(&victim, 0o644);
    (dir, victim)
}

/// A scene of `width`×`height` pixels (TINY's, larger): a write long
/// enough for a racer to act during it.
fn tiny_at(width: u32, height: u32) -> String {
    TINY.replace(
        r#"width="16" height="12""#,
        &format!(r#"width="{width}" height="{height}""#),
    )
}

/// A write can be redirected by no rename. In a sticky
/// folder that everyone may write, user 65534 keeps `out.png` (hard
/// linked, so rewritten in place) and `s.xml` (likewise), and as soon as
/// root's temporary file appears renames its own link to root's private
/// file over the name. Before, the rewrite opened the path again and
/// wrote the image or the attacker's scene text into root's file. Now the
/// write goes through the descriptor that was checked: root's file is
/// never touched; the write fails ("another program replaced the file")
/// or lands in the attacker's own file.
#[test]
fn a_rename_race_redirects_no_write() {
    if !root_or_skip("a_rename_race_redirects_no_write") {
        return;
    }
    let (_private, victim) = victim_file();
    let dir = open_dir();
    let shared = dir.path().join("shared");
    fs::create_dir(&shared).unwrap();
    mode(&shared, 0o1777);
    fs::write(dir.path().join("scene.xml"), tiny_at(600, 450)).unwrap();
    let before = fs::read(&victim).unwrap();
    let mut outcomes = Vec::new();
    for (round, target) in ["out.png", "s.xml", "out.png", "s.xml", "out.png", "s.xml"]
        .into_iter()
        .enumerate()
    {
        let (s, v, t) = (shared.clone(), victim.clone(), target.to_owned());
        // The attacker's file, a second name for it, and its link to
        // root's file, all its own.
        as_user(65534, move || {
            for name in [&t, ".evil", "second"] {
                let _ = fs::remove_file(s.join(name));
            }
            // A scene of 4 MB (a comment): its write lasts a while.
            let text = match t.as_str() {
                "s.xml" => tiny_at(600, 450) + &format!("<!-- {} -->\n", "x".repeat(4 << 20)),
                _ => String::from("mine"),
            };
            fs::write(s.join(&t), text).unwrap();
            fs::set_permissions(s.join(&t), fs::Permissions::from_mode(0o666)).unwrap();
            fs::hard_link(s.join(&t), s.join("second")).unwrap();
            symlink(&v, s.join(".evil")).unwrap();
        });
        let args: Vec<String> = match target {
            "s.xml" => ["edit", "shared/s.xml", "--set", "camera.width=601"]
                .map(String::from)
                .to_vec(),
            _ => ["scene.xml", "-out", "shared/out.png", "-q"]
                .map(String::from)
                .to_vec(),
        };
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        // The racer, user 65534 already, watches the folder itself and
        // renames the moment root's temporary file has bytes in it.
        let (s, t) = (shared.clone(), target.to_owned());
        let (ready, go) = std::sync::mpsc::channel();
        let racer = std::thread::spawn(move || {
            become_user(65534);
            ready.send(()).unwrap();
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(20) {
                if writing_in(&s) {
                    return fs::rename(s.join(".evil"), s.join(&t)).is_ok();
                }
                std::thread::sleep(Duration::from_micros(50));
            }
            false
        });
        go.recv().unwrap();
        let child = spawn(dir.path(), &args);
        let o = child.wait_with_output().unwrap();
        let raced = racer.join().unwrap();
        assert!(
            fs::read(&victim).unwrap() == before,
            "round {round}: {target} redirected into root's file ({})",
            stderr(&o)
        );
        assert!(
            files_in(&shared)
                .iter()
                .all(|n| !n.starts_with(".rayoflight-")),
            "round {round}: {:?}",
            files_in(&shared)
        );
        outcomes.push((target, raced, o.status.code(), stderr(&o)));
    }
    // The race was run: the rename landed every round, and where it
    // landed during the write, the write said it did not happen (`edit`
    // then reads the file now at the name to merge onto it, as it does
    // when an editor saves by rename: root's file, which is no scene).
    // A rename that came after the write (the race lost) leaves a
    // successful write of the attacker's own file.
    for (target, raced, code, err) in &outcomes {
        assert!(raced, "{outcomes:#?}");
        let expected = match *target {
            "s.xml" => "shared/s.xml:1:1: unexpected text",
            _ => {
                "shared/out.png: another program replaced the file while it was written; nothing was written\n"
            }
        };
        assert!(
            *code == Some(0) && err.is_empty() || *code == Some(1) && err.starts_with(expected),
            "{outcomes:#?}"
        );
    }
    let won = outcomes.iter().filter(|o| o.2 == Some(1)).count();
    eprintln!("the rename landed during the write in {won} rounds of 6");
    assert!(won >= 3, "the race was hardly run: {outcomes:#?}");
}

/// The kernel's rule holds for a link in any part of a
/// path, not only the last. User 65534 plants, in the shared folder,
/// links to folders of root's; every command that writes a file or makes
/// a folder refuses to go through them, and nothing lands in root's
/// folders. The caller's own folder link is followed.
#[test]
fn links_another_user_planted_as_folders_are_not_followed() {
    if !root_or_skip("links_another_user_planted_as_folders_are_not_followed") {
        return;
    }
    let private = tempfile::tempdir().unwrap();
    let theirs = private.path().join("dir");
    fs::create_dir(&theirs).unwrap();
    let page = theirs.join("rayoflight.1");
    fs::write(&page, "root's page\n").unwrap();
    let dir = open_dir();
    let root = dir.path();
    fs::write(root.join("scene.xml"), TINY).unwrap();
    let shared = root.join("shared");
    fs::create_dir(&shared).unwrap();
    mode(&shared, 0o1777);
    for name in ["d", "studydir", "mandir"] {
        symlink(&theirs, shared.join(name)).unwrap();
        chown(&shared.join(name), 65534, 65534);
    }
    let refused = |link: &str| {
        format!(
            "not followed: the symbolic link shared/{link} is another user's, in the shared \
             folder shared (sticky and writable by all): the kernel's fs.protected_symlinks rule"
        )
    };
    for (args, link) in [
        (vec!["scene.xml", "-out", "shared/d/out.png"], "d"),
        (
            vec!["export-pov", "scene.xml", "-out", "shared/d/out.pov"],
            "d",
        ),
        (
            vec![
                "edit",
                "scene.xml",
                "--set",
                "camera.width=8",
                "-out",
                "shared/d/s.xml",
            ],
            "d",
        ),
        (
            vec![
                "study",
                "--out",
                "shared/studydir",
                "--runs",
                "1",
                "scene.xml",
            ],
            "studydir",
        ),
        (vec!["man", "--dir", "shared/mandir"], "mandir"),
    ] {
        let o = rayoflight(root, &args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(&refused(link)),
            "{args:?}: {}",
            stderr(&o)
        );
        assert_eq!(files_in(&theirs), ["rayoflight.1"], "{args:?}");
        assert_eq!(fs::read_to_string(&page).unwrap(), "root's page\n");
    }
    // Root's own link to a folder is followed.
    symlink(&theirs, shared.join("mine")).unwrap();
    let o = rayoflight(root, &["scene.xml", "-out", "shared/mine/out.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(theirs.join("out.png").exists());
}

/// A file name cannot forge a line of output. `explain`
/// printed a name's line break raw (a file named `a\nFAKE LINE: render
/// ok.xml` made a line "FAKE LINE: render ok"), and so did `study`'s
/// table and failure summary; `study.csv` kept raw ESC and BEL bytes.
/// Now every name is one line, its controls shown as escapes, on the
/// terminal and in the CSV.
#[test]
fn file_names_forge_no_line_of_output() {
    let dir = tempfile::tempdir().unwrap();
    let name = "a\nFAKE LINE: render ok\u{1b}[2J\u{7}.xml";
    let shown = "a\\nFAKE LINE: render ok\\e[2J\\x07.xml";
    // A scene far from the origin, on which the study's f32 fails: the
    // failure summary names it too.
    let far = fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/study/example-1e7.xml"),
    )
    .unwrap();
    fs::write(dir.path().join(name), far).unwrap();
    let o = rayoflight(dir.path(), &["explain", name, "0", "0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = common::stdout(&o);
    assert!(out.lines().all(|l| !l.starts_with("FAKE LINE")), "{out}");
    assert!(out.contains(shown), "{out}");

    let o = rayoflight(dir.path(), &["study", "--out", "st", "--runs", "1", name]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = common::stdout(&o);
    assert!(!out.contains('\u{1b}') && !out.contains('\u{7}'), "{out:?}");
    assert!(out.lines().all(|l| !l.starts_with("FAKE LINE")), "{out}");
    let summary = out
        .lines()
        .find(|l| l.contains(" failures: "))
        .expect("failures");
    // The study names a scene by its file's stem.
    let stem = shown.trim_end_matches(".xml");
    assert!(summary.contains(&format!("f32 on {stem} (")), "{summary}");
    let csv = fs::read_to_string(dir.path().join("st/study.csv")).unwrap();
    assert!(!csv.contains('\u{1b}') && !csv.contains('\u{7}'), "{csv:?}");
    assert!(
        csv.contains("\"a\nFAKE LINE: render ok\\e[2J\\x07\","),
        "{csv}"
    );
}

/// `sheet` stopped by a signal while it decodes its
/// inputs (before any write) says so and exits 128 + the signal's number,
/// as every other command; the default action ended it silently.
#[test]
fn a_signal_while_the_sheet_decodes_is_said() {
    use rustix::process::Signal;
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("big.xml"), tiny_at(2400, 1800)).unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", "big.xml", "-out", "a.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let inputs: Vec<String> = (0..12).map(|k| format!("in{k}.png")).collect();
    for name in &inputs {
        fs::copy(dir.path().join("a.png"), dir.path().join(name)).unwrap();
    }
    let mut args = vec!["sheet", "-out", "sheet.png"];
    args.extend(inputs.iter().map(String::as_str));
    for (sig, status) in [(Signal::INT, 130), (Signal::TERM, 143), (Signal::HUP, 129)] {
        let mut child = spawn(dir.path(), &args);
        // The signal lands once an input is open: the sheet is reading
        // the images, nothing written yet.
        let fds = PathBuf::from(format!("/proc/{}/fd", child.id()));
        let start = Instant::now();
        let reading = || {
            fs::read_dir(&fds)
                .into_iter()
                .flatten()
                .flatten()
                .any(|fd| {
                    fs::read_link(fd.path())
                        .is_ok_and(|to| to.extension().is_some_and(|e| e == "png"))
                })
        };
        while !reading() {
            assert!(
                child.try_wait().unwrap().is_none(),
                "{sig:?}: it ended first"
            );
            assert!(start.elapsed() < Duration::from_secs(30));
        }
        signal(&child, sig);
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(status), "{sig:?}: {}", stderr(&o));
        assert_eq!(
            stderr(&o),
            "sheet.png: interrupted: nothing was written\n",
            "{sig:?}"
        );
        assert!(!dir.path().join("sheet.png").exists());
    }
}

/// A crash during the rewrite in place of a hard-linked
/// scene never leaves it mixed. `edit` of a 100 MB scene of two names is
/// killed (SIGKILL) at several points: while it copies the old bytes
/// aside (the file untouched), and 0, 5 and 20 ms after the rewrite's
/// record appears (the copy over the old bytes under way). The next
/// command that reads the file finishes the rewrite from the record: both
/// names show the whole new text, byte for byte what an uninterrupted
/// edit writes, and the record and its copies are gone. (Before, the file
/// kept the new text up to where the copy got and the old text after it,
/// shifted: a line became `<color red="0.978" green="" blue="0.5"/>`.)
#[test]
fn a_crash_during_a_rewrite_in_place_is_finished_by_the_next_reader() {
    use rustix::process::Signal;
    let dir = tempfile::tempdir().unwrap();
    let old = spheres(900_000);
    let edit = ["edit", "big.xml", "--set", "object[1].material.ka=0.123456"];
    // What an uninterrupted edit writes.
    fs::write(dir.path().join("big.xml"), &old).unwrap();
    assert!(rayoflight(dir.path(), &edit).status.success());
    let new = fs::read(dir.path().join("big.xml")).unwrap();
    assert_ne!(new, old.as_bytes());
    let record = dir.path().join(".big.xml.rayoflight-rewrite");
    let leftovers = |dir: &Path| -> Vec<String> {
        files_in(dir)
            .into_iter()
            .filter(|n| n.starts_with('.'))
            .collect()
    };
    // (what to wait for, then how long before the kill)
    let points: [(&str, u64); 4] = [("backup", 0), ("record", 0), ("record", 5), ("record", 20)];
    let mut mixed_at_kill = 0;
    for (wait_for, after_ms) in points {
        for name in files_in(dir.path()) {
            fs::remove_file(dir.path().join(name)).unwrap();
        }
        fs::write(dir.path().join("big.xml"), &old).unwrap();
        fs::hard_link(
            dir.path().join("big.xml"),
            dir.path().join("other-link.xml"),
        )
        .unwrap();
        let mut child = spawn(dir.path(), &edit);
        let start = Instant::now();
        let seen = loop {
            let here = match wait_for {
                "backup" => files_in(dir.path())
                    .iter()
                    .any(|n| n.ends_with(".rayoflight-backup")),
                _ => record.exists(),
            };
            if here || child.try_wait().unwrap().is_some() {
                break here;
            }
            assert!(start.elapsed() < Duration::from_secs(60));
            std::thread::sleep(Duration::from_micros(100));
        };
        assert!(seen, "{wait_for}: the edit ended before it was seen");
        std::thread::sleep(Duration::from_millis(after_ms));
        signal(&child, Signal::KILL);
        let _ = child.wait();
        let killed_mid_copy = record.exists();
        let at_kill = fs::read(dir.path().join("big.xml")).unwrap();
        let mixed = at_kill != old.as_bytes() && at_kill != new;
        mixed_at_kill += usize::from(mixed);
        // Any command that reads the file.
        let o = rayoflight(dir.path(), &["export-pov", "big.xml", "-out", "/dev/null"]);
        assert!(
            o.status.success(),
            "{wait_for}+{after_ms}ms: {}",
            stderr(&o)
        );
        let now = fs::read(dir.path().join("big.xml")).unwrap();
        let both = fs::read(dir.path().join("other-link.xml")).unwrap();
        assert!(now == both, "{wait_for}+{after_ms}ms: the names differ");
        match wait_for {
            "backup" => assert!(now == old.as_bytes(), "killed before the record: untouched"),
            _ => {
                assert!(
                    now == new,
                    "{wait_for}+{after_ms}ms: not the new text, whole"
                );
                assert!(!record.exists());
                assert_eq!(leftovers(dir.path()), Vec::<String>::new());
            }
        }
        eprintln!(
            "{wait_for} + {after_ms} ms: record left by the kill: {killed_mid_copy}, the file mixed: {mixed}"
        );
    }
    // The kills did land inside the copy: the readers had work to do.
    assert!(mixed_at_kill > 0, "no kill left the file mixed");
}

/// A write killed in the middle (`kill -9`, a power
/// cut) leaves its temporary file, as big as the file; the next write
/// beside it removes it, and the copy of a hard-linked file's old bytes
/// that no record names. Never a file being written (locked), another
/// user's, one just made, or a name that only looks like ours.
#[test]
fn what_a_killed_write_left_is_removed_by_the_next_write_beside_it() {
    use rustix::process::Signal;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.xml");
    fs::write(&path, spheres(150_000)).unwrap();
    // A real write killed in the middle.
    let mut child = spawn(
        dir.path(),
        &["edit", "q.xml", "--set", "object[2].material.ka=0.75"],
    );
    assert!(wait_for_temporary(dir.path(), &mut child), "no write seen");
    signal(&child, Signal::KILL);
    child.wait().unwrap();
    let left: Vec<String> = files_in(dir.path())
        .into_iter()
        .filter(|n| n.starts_with(".rayoflight-"))
        .collect();
    assert_eq!(left.len(), 1, "the killed write's temporary file stays");

    let an_hour_ago = std::time::SystemTime::now() - Duration::from_secs(3600);
    // "Just made" stays so however long the write below takes to start
    // on a loaded machine (its file younger than the write's 2 s).
    let just_now = std::time::SystemTime::now() + Duration::from_secs(600);
    let plant = |name: &str, old: bool| {
        let p = dir.path().join(name);
        fs::write(&p, vec![b'x'; 4096]).unwrap();
        fs::File::options()
            .write(true)
            .open(&p)
            .unwrap()
            .set_modified(if old { an_hour_ago } else { just_now })
            .unwrap();
        p
    };
    // The killed write's file, aged as after a restart.
    fs::File::options()
        .write(true)
        .open(dir.path().join(&left[0]))
        .unwrap()
        .set_modified(an_hour_ago)
        .unwrap();
    plant(".q.xml.Ab12Cd.rayoflight-backup", true);
    let kept = [
        plant(".rayoflight-fresh1.tmp", false),
        plant(".rayoflight-locked.tmp", true),
        plant(".q.xml.2.Ab12Cd.rayoflight-backup", true),
        plant(".rayoflight-seven77.tmp", true),
        plant("rayoflight-Ab12Cd.tmp", true),
    ];
    // A writer still at work holds its file locked.
    let held = fs::File::open(dir.path().join(".rayoflight-locked.tmp")).unwrap();
    held.lock().unwrap();
    let others = common::is_root().then(|| {
        let p = plant(".rayoflight-other1.tmp", true);
        chown(&p, 65534, 65534);
        p
    });

    let o = rayoflight(
        dir.path(),
        &["edit", "q.xml", "--set", "object[3].material.ka=0.5"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let now = files_in(dir.path());
    assert!(!now.contains(&left[0]), "the killed write's file: {now:?}");
    assert!(!now.contains(&".q.xml.Ab12Cd.rayoflight-backup".to_owned()));
    for p in kept.iter().chain(others.iter()) {
        assert!(p.exists(), "{} kept", p.display());
    }
    drop(held);

    // A backup a record still names is the rewrite's to finish: kept.
    let record = dir.path().join(".q.xml.rayoflight-rewrite");
    fs::write(&record, "not a record this version reads").unwrap();
    let named = plant(".q.xml.Zz99Yy.rayoflight-backup", true);
    let _ = rayoflight(
        dir.path(),
        &["edit", "q.xml", "--set", "object[3].material.ka=0.25"],
    );
    assert!(named.exists());
}
