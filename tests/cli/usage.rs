//! The command line, driven through the built binary as a user would: exit
//! statuses, messages on stderr, and what is (not) written to disk.
//! Every render runs with `--no-gui`, which the GUI build needs to stay
//! headless and the headless build accepts.

use crate::common;

use crate::common::{TINY, files_in, rayoflight, stderr, stdout};
use std::fs;
use std::process::Command;

/// A temporary directory holding `tiny.xml`.
#[test]
fn renders_a_png_next_to_the_scene_by_default() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["--no-gui", "tiny.xml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o), "", "silent without -time");
    let image = image::open(dir.path().join("tiny.png")).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (16, 12));
    assert_eq!(files_in(dir.path()), ["tiny.png", "tiny.xml"]);
}

#[test]
fn time_prints_render_nanoseconds_and_out_picks_the_format() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(
        dir.path(),
        &["-time", "tiny.xml", "-out", "x.jpg", "--no-gui"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let ns = out
        .strip_prefix("render: ")
        .and_then(|s| s.strip_suffix(" ns\n"))
        .unwrap_or_else(|| panic!("unexpected stdout {out:?}"));
    assert!(ns.parse::<u64>().unwrap() > 0);
    let bytes = fs::read(dir.path().join("x.jpg")).unwrap();
    assert_eq!(
        image::guess_format(&bytes).unwrap(),
        image::ImageFormat::Jpeg
    );
}

#[test]
fn threads_and_aa_do_not_change_the_default_image() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let run = |args: &[&str]| {
        let o = rayoflight(dir.path(), args);
        assert!(o.status.success(), "{}", stderr(&o));
    };
    run(&["--no-gui", "tiny.xml", "-out", "a.png", "--threads", "1"]);
    run(&["--no-gui", "tiny.xml", "-out", "b.png", "--threads", "3"]);
    run(&["--no-gui", "tiny.xml", "-out", "c.png", "--aa", "3"]);
    let read = |n: &str| image::open(dir.path().join(n)).unwrap().to_rgb8();
    assert_eq!(read("a.png"), read("b.png"));
    assert_ne!(read("a.png"), read("c.png"), "--aa 3 smooths the edges");
}

#[test]
fn no_arguments_prints_usage_and_exits_2() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["--no-gui"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).starts_with("Usage: rayoflight"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn help_and_version_succeed_on_stdout() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["--help"]);
    assert!(o.status.success());
    assert!(stdout(&o).contains("-o, --out <FILE>"), "{}", stdout(&o));
    let o = rayoflight(dir.path(), &["-V"]);
    assert!(o.status.success());
    assert!(stdout(&o).starts_with("rayoflight "));
}

#[test]
fn unknown_flag_is_a_usage_error_that_names_it() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["tiny.xml", "--frobnicate"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("unknown flag '--frobnicate'"),
        "{}",
        stderr(&o)
    );
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}

#[test]
fn bad_flag_values_are_usage_errors() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    for args in [
        &["tiny.xml", "--threads", "0"][..],
        &["tiny.xml", "--aa", "17"],
        &["tiny.xml", "-out"],
        &["tiny.xml", "other.xml"],
    ] {
        let o = rayoflight(dir.path(), args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}

#[test]
fn missing_scene_fails_with_its_name() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["--no-gui", "nope.xml"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.starts_with("nope.xml: "), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}

#[test]
fn scene_that_is_a_directory_fails() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    fs::create_dir(dir.path().join("d.xml")).unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", "d.xml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).starts_with("d.xml: "), "{}", stderr(&o));
    assert_eq!(files_in(dir.path()), ["d.xml", "tiny.xml"]);
}

#[test]
fn unknown_extension_lists_the_supported_ones() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["--no-gui", "tiny.xml", "-out", "x.xyz"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("\"xyz\"") && err.contains("png, jpg, jpeg"),
        "{err}"
    );
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}

#[test]
fn output_equal_to_the_scene_is_refused() {
    let (dir, scene) = common::scene_file("tiny.xml", TINY);
    fs::create_dir(dir.path().join("sub")).unwrap();
    // The same file reached through another path, and a scene whose name
    // would make the default output be itself.
    fs::write(dir.path().join("s.png"), TINY).unwrap();
    for args in [
        &["--no-gui", "tiny.xml", "-out", "sub/../tiny.xml"][..],
        &["--no-gui", "s.png"],
        &["export-pov", "tiny.xml", "-out", "./tiny.xml"],
    ] {
        let o = rayoflight(dir.path(), args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(
            stderr(&o).contains("refusing to overwrite the scene"),
            "{}",
            stderr(&o)
        );
    }
    assert_eq!(fs::read_to_string(&scene).unwrap(), TINY);
    assert_eq!(fs::read_to_string(dir.path().join("s.png")).unwrap(), TINY);
}

#[test]
fn missing_output_directory_fails_without_leftovers() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(
        dir.path(),
        &["--no-gui", "tiny.xml", "-out", "no/such/dir/x.png"],
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).starts_with("no/such/dir/x.png: "),
        "{}",
        stderr(&o)
    );
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}

#[test]
fn output_that_is_a_directory_fails() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    fs::create_dir(dir.path().join("out.png")).unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", "tiny.xml", "-out", "out.png"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).starts_with("out.png: "), "{}", stderr(&o));
    assert_eq!(files_in(dir.path()), ["out.png", "tiny.xml"]);
}

#[test]
fn a_broken_scene_leaves_an_existing_image_untouched() {
    let (dir, scene) = common::scene_file("tiny.xml", TINY);
    let old = b"an older image".to_vec();
    fs::write(dir.path().join("tiny.png"), &old).unwrap();
    fs::write(
        &scene,
        "<scene>\n  <camera width=\"4\" height=\"4\" eyeDistance=\"1\"/>\n  <material ka=\"-1\"/>\n</scene>\n",
    )
    .unwrap();
    let o = rayoflight(dir.path(), &["--no-gui", "tiny.xml"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.starts_with("tiny.xml:3:3: "), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert_eq!(fs::read(dir.path().join("tiny.png")).unwrap(), old);
    assert_eq!(files_in(dir.path()), ["tiny.png", "tiny.xml"]);
}

#[test]
fn export_pov_writes_a_pov_file() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["export-pov", "tiny.xml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let pov = fs::read_to_string(dir.path().join("tiny.pov")).unwrap();
    assert!(pov.contains("camera") && pov.contains("sphere"), "{pov}");
}

/// The GUI build opens a window unless told not to: with no display it
/// says so, names --no-gui, and exits 2 without writing anything.
#[cfg(feature = "gui")]
#[test]
fn without_a_display_the_app_names_no_gui() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    for args in [&[][..], &["tiny.xml"]] {
        let o = rayoflight(dir.path(), args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert!(
            err.contains("no display") && err.contains("--no-gui"),
            "{err}"
        );
    }
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}

#[test]
fn study_writes_a_csv_row_per_method() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(
        dir.path(),
        &["study", "--out", "res", "--runs", "1", "tiny.xml"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = fs::read_to_string(dir.path().join("res/study.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("scene,method,time_ms,rays,max_diff,mean_diff,within1,failed")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let methods = rayoflight::render::methods();
    assert_eq!(rows.len(), methods.len());
    for (row, method) in rows.iter().zip(&methods) {
        assert_eq!(row.len(), 8, "{row:?}");
        assert_eq!((row[0], row[1]), ("tiny", method.name));
    }
    // The default is its own reference.
    assert_eq!(rows[0][4..], ["0", "0.0000", "1.000000", "false"]);
    // The table names every method on stdout.
    let out = stdout(&o);
    assert!(methods.iter().all(|m| out.contains(m.name)), "{out}");
}

#[test]
fn study_bad_usage_exits_2() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    for args in [
        &["study", "--aa", "2"][..],
        &["study", "--frobnicate"],
        &["study", "--runs", "0"],
        &["study", "--out"],
    ] {
        let o = rayoflight(dir.path(), args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!dir.path().join("study").exists());
    }
    // A scene that does not load is an error (1), named on stderr.
    let o = rayoflight(dir.path(), &["study", "--out", "res", "missing.xml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("missing.xml"), "{}", stderr(&o));
}

#[test]
fn study_draws_the_chart_and_a_picture_per_failure() {
    use rayoflight::study::chart::{CHART_SIZE, GAP};
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(
        dir.path(),
        &["study", "--out", "res", "--runs", "1", "tiny.xml"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let res = dir.path().join("res");
    let chart = image::open(res.join("study.png")).unwrap();
    assert_eq!((chart.width(), chart.height()), CHART_SIZE);
    let csv = fs::read_to_string(res.join("study.csv")).unwrap();
    let failed: Vec<String> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|row| row[7] == "true")
        .map(|row| row[1].to_owned())
        .collect();
    // The draft preview copies every second pixel: it misses the edge of
    // the sphere on a 16×12 image.
    assert!(failed.iter().any(|m| m == "draft"), "{csv}");
    let mut pictures: Vec<String> = files_in(&res)
        .into_iter()
        .filter(|f| f.starts_with("fail-"))
        .collect();
    pictures.sort();
    let mut expected: Vec<String> = failed
        .iter()
        .map(|m| format!("fail-tiny-{m}.png"))
        .collect();
    expected.sort();
    assert_eq!(pictures, expected);
    for name in &pictures {
        let picture = image::open(res.join(name)).unwrap();
        // Method | reference | difference, 16×12 each.
        assert_eq!(
            (picture.width(), picture.height()),
            (3 * 16 + 2 * GAP, 12),
            "{name}"
        );
    }
}

#[test]
fn plan_prints_what_auto_decides_and_writes_nothing() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = rayoflight(dir.path(), &["plan", "tiny.xml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for topic in [
        "precision: f64",
        "acceleration: ",
        "early stop: ",
        "terms: ",
    ] {
        assert!(text.contains(topic), "{topic} missing from:\n{text}");
    }
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
    let o = rayoflight(dir.path(), &["plan", "missing.xml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("missing.xml"), "{}", stderr(&o));
    let o = rayoflight(dir.path(), &["plan"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn method_renders_with_a_study_method() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let render = |method: &str| {
        let out = format!("{method}.png");
        let o = rayoflight(
            dir.path(),
            &["--no-gui", "tiny.xml", "--method", method, "-out", &out],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        image::open(dir.path().join(out)).unwrap().to_rgb8()
    };
    let plain = render("default");
    assert!(render("auto") == plain, "auto is the default image");
    let draft = render("draft");
    for (i, j, p) in draft.enumerate_pixels() {
        assert_eq!(p, plain.get_pixel(i & !1, j & !1), "draft at ({i}, {j})");
    }
    let o = rayoflight(dir.path(), &["--no-gui", "tiny.xml", "--method", "fastest"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("auto"), "{}", stderr(&o));
}

/// Runs the binary in `dir` with its stdout closed (`>&-`): the shell
/// closes descriptor 1, then runs it (std's Command cannot close one).
fn with_stdout_closed(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new("sh")
        .arg("-c")
        .arg(r#"exec "$0" "$@" >&-"#)
        .arg(env!("CARGO_BIN_EXE_rayoflight"))
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("sh runs")
}

#[test]
fn a_closed_stdout_is_an_error_for_every_command_that_prints() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    for args in [
        &["split", "tiny.xml", "--tasks", "2"][..],
        &["plan", "tiny.xml"],
        &["explain", "tiny.xml", "3", "4"],
        &["explain", "tiny.xml", "3", "4", "--json"],
        &["-time", "tiny.xml", "-out", "t.png"],
        &["--help"],
        &["plan", "--help"],
        &["--version"],
        &["study", "--out", "res", "tiny.xml", "--runs", "1"],
    ] {
        let o = with_stdout_closed(dir.path(), args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert_eq!(
            stderr(&o).trim_end(),
            "rayoflight: cannot write to stdout: it is closed",
            "{args:?}"
        );
    }
    // Found before the work: the render wrote no image, the study nothing.
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
    // What prints nothing does not need stdout.
    let o = with_stdout_closed(dir.path(), &["--no-gui", "tiny.xml", "-out", "t.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Output thrown away on purpose is no error.
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(r#"exec "$0" "$@" >/dev/null"#)
        .arg(env!("CARGO_BIN_EXE_rayoflight"))
        .args(["plan", "tiny.xml"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_full_stdout_is_an_error() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    if !std::path::Path::new("/dev/full").exists() {
        return;
    }
    for args in [
        &["plan", "tiny.xml"][..],
        &["--help"],
        &["-time", "tiny.xml", "-out", "t.png"],
    ] {
        let o = std::process::Command::new("sh")
            .arg("-c")
            .arg(r#"exec "$0" "$@" >/dev/full"#)
            .arg(env!("CARGO_BIN_EXE_rayoflight"))
            .args(args)
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(
            stderr(&o).contains("cannot write to stdout: No space left on device"),
            "{args:?}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn output_folders_are_checked_before_the_work() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    // The bench is a minute of work: its CSV's folder is checked first.
    let start = std::time::Instant::now();
    let o = rayoflight(
        dir.path(),
        &[
            "bench",
            "--csv",
            "nodir/x.csv",
            "--no-pov",
            "--runs",
            "1",
            "-q",
        ],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(start.elapsed().as_secs() < 10, "{:?}", start.elapsed());
    assert_eq!(
        stderr(&o).trim_end(),
        "nodir/x.csv: the folder nodir does not exist"
    );
    assert_eq!(stdout(&o), "", "no table printed before the refusal");
    // The study's files: one of them taken by a folder.
    fs::create_dir_all(dir.path().join("res/study.png")).unwrap();
    let o = rayoflight(dir.path(), &["study", "--out", "res", "tiny.xml", "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o).trim_end(),
        "res/study.png: is a directory, not a file"
    );
    assert_eq!(stdout(&o), "");
    assert_eq!(files_in(&dir.path().join("res")), ["study.png"]);
    // Every error names the path given, never a temporary file.
    for (args, path) in [
        (
            &["export-pov", "tiny.xml", "-out", "gone/x.pov"][..],
            "gone/x.pov",
        ),
        (
            &[
                "edit",
                "tiny.xml",
                "--set",
                "model.depth=2",
                "-out",
                "gone/x.xml",
            ],
            "gone/x.xml",
        ),
        (
            &["sheet", "-out", "gone/s.png", "missing.png"],
            "gone/s.png",
        ),
    ] {
        let o = rayoflight(dir.path(), args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert_eq!(
            stderr(&o).trim_end(),
            format!("{path}: the folder gone does not exist"),
            "{args:?}"
        );
    }
}

#[test]
fn negative_numbers_are_values_and_single_dash_words_are_named_whole() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    for (args, message) in [
        (
            &["tiny.xml", "--threads", "-1"][..],
            "--threads expects an integer from 1 to ",
        ),
        (
            &["bench", "--split-size", "-1"],
            "--split-size expects 0 (skip the section) or a side from 8 to 16384 pixels, not \"-1\"",
        ),
        (
            &["explain", "tiny.xml", "-1", "0"],
            "<X> expects a pixel number",
        ),
        (&["-frobnicate", "tiny.xml"], "unknown flag '-frobnicate';"),
        (
            &["-tme", "tiny.xml"],
            "unknown flag '-tme' (did you mean '-time'?)",
        ),
        (
            &["-outt", "x.png", "tiny.xml"],
            "unknown flag '-outt' (did you mean '-out'?)",
        ),
    ] {
        let o = rayoflight(dir.path(), args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(message), "{args:?}: {}", stderr(&o));
    }
    assert_eq!(files_in(dir.path()), ["tiny.xml"]);
}

/// Every flag but the scene is the command line's: `-q` alone renders
/// without a window, even where a display is said to be.
#[cfg(feature = "gui")]
#[test]
fn quiet_alone_renders_without_opening_the_app() {
    let (dir, _) = common::scene_file("tiny.xml", TINY);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .args(["-q", "tiny.xml"])
        .current_dir(dir.path())
        // A display that is not there: opening a window would fail.
        .env("DISPLAY", ":4242")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(files_in(dir.path()), ["tiny.png", "tiny.xml"]);
}

/// A scene that is not there is an error said plainly, exit 1, even with
/// a display where the app would open: no window waits for the file. A
/// mistyped `rayoflight help` says where help is.
#[test]
fn a_missing_scene_is_an_error_not_a_window() {
    let dir = tempfile::tempdir().unwrap();
    for (name, hint) in [("nosuch.xml", false), ("help", true)] {
        let o = Command::new(env!("CARGO_BIN_EXE_rayoflight"))
            .arg(name)
            .current_dir(dir.path())
            // A display that is not there: a window tried would fail
            // with status 2 and say so.
            .env("DISPLAY", ":987")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        let said = stderr(&o);
        assert!(
            said.starts_with(&format!("{name}: cannot read the scene file: ")),
            "{said}"
        );
        assert_eq!(said.contains("rayoflight --help"), hint, "{said}");
    }
}

/// `export-pov -out -` prints the POV-Ray text, as `new -` prints its
/// scene; it wrote a file named `-` before.
#[test]
fn export_pov_to_dash_prints() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.xml"), rayoflight::EXAMPLE_SCENE).unwrap();
    let o = rayoflight(dir.path(), &["export-pov", "s.xml", "-out", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.starts_with("// POV-Ray 3.7 translation"), "{text}");
    assert!(text.contains("+Is.pov"), "{text}");
    assert_eq!(files_in(dir.path()), ["s.xml"]);
}
