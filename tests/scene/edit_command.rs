//! `rayoflight edit` and the render's `--set`, driven through the built
//! binary: what the scene file holds afterwards, byte for byte, and that
//! every refusal leaves it as it was.

use crate::common;

use crate::common::{files_in, rayoflight, stderr, stdout};
use std::fs;
use std::path::Path;
use std::process::Output;

/// Two spheres and a light, 8×8, with comments and formatting that an edit
/// must keep.
const SCENE: &str = r#"<?xml version="1.0"?>
<!-- Two spheres and a light, 8x8. -->
<scene>
  <!-- GREEN sphere, right -->
  <sphere>
    <color red="0.2" green="0.8" blue="0.2"/>
    <material ka="0.3" kd="0.3" ks="0.3" m="20"/>
    <transformation><translate x="2" y="0" z="-2"/></transformation>
  </sphere>
  <!-- RED sphere, left -->
  <sphere>
    <color red="1.0" green="0.2" blue="0.0"/>
    <material ka="0.4" kd="0.5" ks="0.3" m="1"/>
    <transformation><translate x="-2" y="0" z="-2"/></transformation>
  </sphere>
  <light x="1" y="-4" z="-2"/>
  <camera width="8" height="8" eyeDistance="4">
    <transformation><translate x="0" y="0" z="-20"/></transformation>
  </camera>
  <model type="phong" depth="2"/>
</scene>
"#;

/// A temporary directory holding `s.xml`.
fn succeeds(o: &Output) {
    assert!(o.status.success(), "{}", stderr(o));
    assert_eq!(stderr(o), "");
}

/// `SCENE` with its one occurrence of `from` replaced by `to`.
fn scene_with(from: &str, to: &str) -> String {
    assert_eq!(SCENE.matches(from).count(), 1, "{from}");
    SCENE.replacen(from, to, 1)
}

#[test]
fn edit_in_place_changes_only_the_edited_value() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    let o = rayoflight(
        dir.path(),
        &["edit", "s.xml", "--set", "object[2].material.ka=0.5"],
    );
    succeeds(&o);
    assert_eq!(stdout(&o), "");
    assert_eq!(
        fs::read_to_string(&scene).unwrap(),
        scene_with(r#"ka="0.4""#, r#"ka="0.5""#)
    );
    assert_eq!(files_in(dir.path()), ["s.xml"], "no temporary file left");
}

#[test]
fn several_edits_keep_every_other_byte() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    let o = rayoflight(
        dir.path(),
        &[
            "edit",
            "s.xml",
            "--set=light[1].x=-1.5",
            "--set",
            "model.type=whitted",
            "--set",
            "object[1].transformation[1].z=-3",
        ],
    );
    succeeds(&o);
    let expected = scene_with(r#"<light x="1""#, r#"<light x="-1.5""#)
        .replacen(r#"type="phong""#, r#"type="whitted""#, 1)
        .replacen(
            r#"<translate x="2" y="0" z="-2"/>"#,
            r#"<translate x="2" y="0" z="-3"/>"#,
            1,
        );
    assert_eq!(fs::read_to_string(&scene).unwrap(), expected);
}

#[test]
fn out_writes_elsewhere_and_leaves_the_scene_untouched() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    for (args, out) in [
        (
            &["edit", "s.xml", "--set", "camera.width=4", "-out", "a.xml"][..],
            "a.xml",
        ),
        (
            &["edit", "--out=b.xml", "s.xml", "--set", "camera.width=4"],
            "b.xml",
        ),
        (
            &["edit", "s.xml", "-o", "c.xml", "--set", "camera.width=4"],
            "c.xml",
        ),
    ] {
        succeeds(&rayoflight(dir.path(), args));
        assert_eq!(
            fs::read_to_string(dir.path().join(out)).unwrap(),
            scene_with(r#"width="8""#, r#"width="4""#),
            "{args:?}"
        );
    }
    assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE);
    // An edit that changes nothing still writes the copy asked for.
    succeeds(&rayoflight(
        dir.path(),
        &["edit", "s.xml", "--set", "camera.width=8", "-out", "d.xml"],
    ));
    assert_eq!(fs::read_to_string(dir.path().join("d.xml")).unwrap(), SCENE);
    assert_eq!(
        files_in(dir.path()),
        ["a.xml", "b.xml", "c.xml", "d.xml", "s.xml"]
    );
}

#[test]
fn edits_apply_in_the_order_given() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    // Adding first makes object[3] exist for the --set after it.
    succeeds(&rayoflight(
        dir.path(),
        &[
            "edit",
            "s.xml",
            "--add",
            "sphere",
            "--set",
            "object[3].color.red=0.5",
        ],
    ));
    let text = fs::read_to_string(&scene).unwrap();
    let added = text
        .strip_prefix(&SCENE[..SCENE.find("  <light").unwrap()])
        .unwrap_or_else(|| panic!("the objects before are kept:\n{text}"));
    assert!(
        added.starts_with(
            "  <sphere>\n    <color red=\"0.5\" green=\"1\" blue=\"1\"/>\n  </sphere>\n  <light"
        ),
        "{text}"
    );

    // The other way round, object[3] does not exist yet: nothing is done.
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    let o = rayoflight(
        dir.path(),
        &[
            "edit",
            "s.xml",
            "--set",
            "object[3].color.red=0.5",
            "--add",
            "sphere",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr(&o),
        "rayoflight: s.xml: object[3]: the scene has 2 objects\n"
    );
    assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE);

    // Interleaved flags keep their relative order: remove object 1, then
    // the old object 2 is object[1].
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    succeeds(&rayoflight(
        dir.path(),
        &[
            "edit",
            "s.xml",
            "--set",
            "object[2].material.m=2",
            "--remove",
            "object[1]",
            "--set",
            "object[1].material.kd=0.25",
        ],
    ));
    let text = fs::read_to_string(&scene).unwrap();
    assert!(
        text.contains(r#"<material ka="0.4" kd="0.25" ks="0.3" m="2"/>"#),
        "{text}"
    );
    assert!(!text.contains("GREEN"), "{text}");
}

#[test]
fn remove_takes_the_comment_above_along() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    succeeds(&rayoflight(
        dir.path(),
        &["edit", "s.xml", "--remove", "object[2]"],
    ));
    let start = SCENE.find("  <!-- RED").unwrap();
    let end = SCENE.find("  <light").unwrap();
    let expected = format!("{}{}", &SCENE[..start], &SCENE[end..]);
    assert_eq!(fs::read_to_string(&scene).unwrap(), expected);
}

#[test]
fn an_edit_that_changes_nothing_does_not_touch_the_file() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    let before = fs::metadata(&scene).unwrap();
    // The value it has, in other spellings.
    for value in ["0.4", "0.40", "4e-1"] {
        let set = format!("object[2].material.ka={value}");
        succeeds(&rayoflight(dir.path(), &["edit", "s.xml", "--set", &set]));
    }
    let after = fs::metadata(&scene).unwrap();
    assert_eq!(after.modified().unwrap(), before.modified().unwrap());
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        assert_eq!(after.ino(), before.ino(), "not replaced");
    }
    assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE);
}

#[cfg(unix)]
#[test]
fn the_scene_keeps_its_mode() {
    use std::os::unix::fs::PermissionsExt;
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    fs::set_permissions(&scene, fs::Permissions::from_mode(0o640)).unwrap();
    succeeds(&rayoflight(
        dir.path(),
        &["edit", "s.xml", "--set", "model.depth=3"],
    ));
    let mode = fs::metadata(&scene).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
    assert_eq!(
        fs::read_to_string(&scene).unwrap(),
        scene_with(r#"depth="2""#, r#"depth="3""#)
    );
}

#[cfg(unix)]
#[test]
fn through_a_symbolic_link_the_target_changes_and_the_link_stays() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    fs::create_dir(dir.path().join("sub")).unwrap();
    std::os::unix::fs::symlink("../s.xml", dir.path().join("sub/link.xml")).unwrap();
    succeeds(&rayoflight(
        dir.path(),
        &["edit", "sub/link.xml", "--set", "model.depth=3"],
    ));
    let link = fs::symlink_metadata(dir.path().join("sub/link.xml")).unwrap();
    assert!(link.file_type().is_symlink());
    assert_eq!(
        fs::read_to_string(&scene).unwrap(),
        scene_with(r#"depth="2""#, r#"depth="3""#)
    );
    assert_eq!(files_in(&dir.path().join("sub")), ["link.xml"]);
}

/// Every refusal: its exit status, its one-line message, and the scene
/// left byte for byte as it was, with nothing written beside it.
#[test]
fn refused_edits_name_the_problem_and_touch_nothing() {
    let cases: &[(&[&str], i32, &str)] = &[
        (
            &["--set", "object[1].material.kx=1"],
            2,
            "rayoflight: s.xml: object[1].material.kx: no such value; paths are model.type, ",
        ),
        (
            &["--set", "object[5].material.ka=1"],
            2,
            "rayoflight: s.xml: object[5]: the scene has 2 objects",
        ),
        (
            &["--remove", "light[2]"],
            2,
            "rayoflight: s.xml: light[2]: the scene has 1 light",
        ),
        (
            &["--remove", "camera"],
            2,
            "rayoflight: s.xml: camera: not an element; elements are object[N], light[N]",
        ),
        (
            &["--set", "object[1].material.ka=abc"],
            2,
            "rayoflight: s.xml: object[1].material.ka: not a number: 'abc'",
        ),
        (
            &["--set", "object[1].material.ka=-1"],
            2,
            "rayoflight: s.xml: object[1].material.ka: must be >= 0, got -1",
        ),
        (
            &["--set", "model.type=raytrace"],
            2,
            "rayoflight: s.xml: model.type: must be one of ambient, lambert, phong, whitted",
        ),
        (
            &["--set", "object[1].material.ka"],
            2,
            "rayoflight: --set expects PATH=VALUE, such as object[1].material.ka=0.5, \
             not \"object[1].material.ka\"; see 'rayoflight edit --help'",
        ),
        (
            &["--add", "cube"],
            2,
            "rayoflight: s.xml: cube: not an element that can be added; those are sphere, plane and light",
        ),
        (
            &[],
            2,
            "rayoflight: nothing to do: give at least one --set, --remove or --add",
        ),
        (
            &["--set", "model.depth=3", "--frobnicate"],
            2,
            "rayoflight: unknown flag '--frobnicate'; see 'rayoflight edit --help'",
        ),
        // A later edit refused: the earlier ones are not written either.
        (
            &["--set", "model.depth=3", "--set", "camera.width=0"],
            2,
            "rayoflight: s.xml: camera.width: must be a whole number from 1 to",
        ),
        (
            &["--set", "model.depth=3", "-out", "no/such/dir/x.xml"],
            1,
            "no/such/dir/x.xml: ",
        ),
    ];
    for (flags, status, message) in cases {
        let (dir, scene) = common::scene_file("s.xml", SCENE);
        let args: Vec<&str> = ["edit", "s.xml"].iter().chain(*flags).copied().collect();
        let o = rayoflight(dir.path(), &args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(*status), "{args:?}: {err}");
        assert!(err.starts_with(message), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE, "{args:?}");
        assert_eq!(files_in(dir.path()), ["s.xml"], "{args:?}");
    }
}

#[test]
fn a_scene_that_does_not_load_is_an_error_with_its_position() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    let broken = "<scene>\n  <camera width=\"4\" height=\"4\" eyeDistance=\"1\"/>\n  <material ka=\"-1\"/>\n</scene>\n";
    fs::write(&scene, broken).unwrap();
    let o = rayoflight(dir.path(), &["edit", "s.xml", "--set", "model.depth=3"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.starts_with("s.xml:3:3: "), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert_eq!(fs::read_to_string(&scene).unwrap(), broken);

    let o = rayoflight(
        dir.path(),
        &["edit", "missing.xml", "--set", "model.depth=3"],
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).starts_with("missing.xml: "), "{}", stderr(&o));
    assert_eq!(files_in(dir.path()), ["s.xml"]);
}

#[cfg(unix)]
#[test]
fn a_read_only_scene_is_not_replaced() {
    use std::os::unix::fs::PermissionsExt;
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    fs::set_permissions(&scene, fs::Permissions::from_mode(0o444)).unwrap();
    let o = rayoflight(dir.path(), &["edit", "s.xml", "--set", "model.depth=3"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("read-only"), "{}", stderr(&o));
    assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE);
    assert_eq!(files_in(dir.path()), ["s.xml"]);
}

#[test]
fn edit_help_lists_the_paths() {
    let (dir, _) = common::scene_file("s.xml", SCENE);
    let o = rayoflight(dir.path(), &["edit", "--help"]);
    succeeds(&o);
    let help = stdout(&o);
    assert!(help.contains("Usage: rayoflight edit scene.xml"), "{help}");
    assert!(help.contains("object[N].material.<ka|kd|ks|m>"), "{help}");
}

// ----- --set on a render -----

fn pixels(dir: &Path, name: &str) -> image::RgbImage {
    image::open(dir.join(name)).unwrap().to_rgb8()
}

#[test]
fn set_on_a_render_gives_the_image_of_the_edited_file() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    let sets = ["object[2].material.ka=0.9", "light[1].x=-3"];
    // No --no-gui: --set alone makes the render headless, in the GUI build
    // too (there is no display here).
    let o = rayoflight(
        dir.path(),
        &[
            "s.xml", "--set", sets[0], "--set", sets[1], "-out", "set.png",
        ],
    );
    succeeds(&o);
    assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE, "never written");

    let edit = [
        "edit", "s.xml", "--set", sets[0], "--set", sets[1], "-out", "e.xml",
    ];
    succeeds(&rayoflight(dir.path(), &edit));
    succeeds(&rayoflight(
        dir.path(),
        &["--no-gui", "e.xml", "-out", "e.png"],
    ));
    succeeds(&rayoflight(
        dir.path(),
        &["--no-gui", "s.xml", "-out", "plain.png"],
    ));
    assert_eq!(
        fs::read(dir.path().join("set.png")).unwrap(),
        fs::read(dir.path().join("e.png")).unwrap()
    );
    assert_ne!(
        pixels(dir.path(), "set.png"),
        pixels(dir.path(), "plain.png")
    );
    assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE);
}

#[test]
fn set_works_with_the_other_render_flags() {
    let (dir, scene) = common::scene_file("s.xml", SCENE);
    let set = "object[1].color.blue=1";
    succeeds(&rayoflight(
        dir.path(),
        &["edit", "s.xml", "--set", set, "-out", "e.xml"],
    ));
    for (args, out) in [
        (
            &[
                "s.xml", "--set", set, "--method", "default", "-out", "a.png",
            ][..],
            "a.png",
        ),
        (
            &["--threads", "1", "s.xml", "--set", set, "-out", "b.png"],
            "b.png",
        ),
        (&["-time", "s.xml", "--set", set, "-out", "c.png"], "c.png"),
    ] {
        succeeds(&rayoflight(dir.path(), args));
        assert_eq!(
            pixels(dir.path(), out),
            pixels(dir.path(), "a.png"),
            "{args:?}"
        );
    }
    succeeds(&rayoflight(
        dir.path(),
        &["--no-gui", "e.xml", "-out", "e.png"],
    ));
    assert_eq!(pixels(dir.path(), "a.png"), pixels(dir.path(), "e.png"));
    // Without -out, the image goes next to the scene as usual.
    succeeds(&rayoflight(dir.path(), &["s.xml", "--set", set]));
    assert_eq!(pixels(dir.path(), "s.png"), pixels(dir.path(), "e.png"));
    assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE);
}

#[test]
fn a_refused_set_on_a_render_writes_no_image() {
    for (args, message) in [
        (
            &["s.xml", "--set", "object[9].color.red=1"][..],
            "rayoflight: s.xml: object[9]: the scene has 2 objects\n",
        ),
        (
            &["s.xml", "--set", "camera.eyeDistance=0", "-out", "x.png"],
            "rayoflight: s.xml: camera.eyeDistance: must be > 0, got 0\n",
        ),
        (
            &["s.xml", "--set", "light[1].x"],
            "rayoflight: --set expects PATH=VALUE, such as object[1].material.ka=0.5, \
             not \"light[1].x\"; see 'rayoflight --help'\n",
        ),
        (
            &["s.xml", "--remove", "light[1]"],
            "rayoflight: unknown flag '--remove'; see 'rayoflight --help'\n",
        ),
    ] {
        let (dir, scene) = common::scene_file("s.xml", SCENE);
        let o = rayoflight(dir.path(), args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert_eq!(stderr(&o), message);
        assert_eq!(files_in(dir.path()), ["s.xml"]);
        assert_eq!(fs::read_to_string(&scene).unwrap(), SCENE);
    }
    // --set with no scene: the usage.
    let (dir, _) = common::scene_file("s.xml", SCENE);
    let o = rayoflight(dir.path(), &["--set", "model.depth=1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).starts_with("Usage: rayoflight"),
        "{}",
        stderr(&o)
    );
}

/// A file whose lines end with a lone CR (classic Mac
/// OS) gets an added element on a line of its own, ended the same way, as
/// LF and CRLF files do: the result is the LF file's, its endings CR. (It
/// was glued to the line before: `</sphere><sphere/>`.)
#[test]
fn an_added_element_has_a_line_of_its_own_in_every_line_ending() {
    let edit = |text: &str| {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("s.xml"), text).unwrap();
        succeeds(&rayoflight(
            dir.path(),
            &["edit", "s.xml", "--add", "sphere", "--add", "plane"],
        ));
        fs::read_to_string(dir.path().join("s.xml")).unwrap()
    };
    let lf = edit(SCENE);
    assert!(lf.contains("  </sphere>\n  <sphere/>\n"), "{lf}");
    for ending in ["\r\n", "\r"] {
        let got = edit(&SCENE.replace('\n', ending));
        assert_eq!(got, lf.replace('\n', ending), "{ending:?}");
    }
}

/// A file in UTF-16 without a byte order mark is named
/// as such (scenes are UTF-8), not `unexpected text "\u{0}"` at 1:1.
#[test]
fn a_utf16_file_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        (
            "le.xml",
            SCENE
                .encode_utf16()
                .flat_map(u16::to_le_bytes)
                .collect::<Vec<u8>>(),
        ),
        (
            "be.xml",
            SCENE.encode_utf16().flat_map(u16::to_be_bytes).collect(),
        ),
    ] {
        fs::write(dir.path().join(name), bytes).unwrap();
        let o = rayoflight(dir.path(), &["--no-gui", name, "-out", "x.png"]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        assert!(
            stderr(&o).contains("looks like UTF-16") && stderr(&o).contains("UTF-8"),
            "{name}: {}",
            stderr(&o)
        );
    }
}
