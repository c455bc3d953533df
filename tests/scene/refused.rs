//! The loader's errors: every malformed scene under `tests/malformed/` must be
//! refused with the exact `line:column` of the culprit and a message naming
//! the element and attribute at fault (docs/scene-format.md: Elements,
//! Numbers, Everything else in the file and Error messages).
//!
//! Columns count characters, not bytes (a tab is one), so several cases put
//! tabs and multi-byte characters before the culprit on its line.

use std::path::{Path, PathBuf};

use rayoflight::scene::{self, LoadError, LoadErrorKind, Position};

use crate::common;

/// File, expected `(line, column)` (`None`: the error has no position), and
/// words the message must contain.
type Case = (
    &'static str,
    Option<(usize, usize)>,
    &'static [&'static str],
);

#[rustfmt::skip]
const CASES: &[Case] = &[
("01_empty_file.xml", Some((1, 1)), &["no <scene>"]),
    ("02_doctype.xml", Some((2, 1)), &["DOCTYPE"]),
    ("03_root_not_scene.xml", Some((3, 1)), &["<world>", "<scene>"]),
    ("04_unclosed_tag.xml", Some((3, 3)), &["not closed"]),
    ("05_unclosed_element.xml", Some((5, 1)), &["<sphere>", "not closed"]),
    ("06_unclosed_quote.xml", Some((3, 3)), &["not closed"]),
    ("07_mismatched_end_tag.xml", Some((4, 3)), &["</sphere>", "</plane>"]),
    ("08_unmatched_end_tag.xml", Some((4, 1)), &["</sphere>"]),
    ("09_garbage_after_root.xml", Some((4, 1)), &["garbage", "after"]),
    ("10_element_after_root.xml", Some((4, 1)), &["<scene>", "after"]),
    ("11_unquoted_attribute.xml", Some((3, 12)), &["<light>", "quotes"]),
    ("12_attribute_without_value.xml", Some((3, 29)), &["<light>", "="]),
    ("13_unknown_entity.xml", Some((3, 10)), &["<light>", "attribute x", "&pi;"]),
    ("14_unterminated_reference.xml", Some((3, 22)), &["<light>", "attribute z", ";"]),
    ("15_text_content.xml", Some((3, 11)), &["hello"]),
    ("16_text_before_root.xml", Some((2, 1)), &["oops"]),
    ("17_entity_in_text.xml", Some((3, 11)), &["&amp;"]),
    ("18_xml_decl_not_first.xml", Some((2, 3)), &["declaration"]),
    ("19_double_hyphen_comment.xml", Some((2, 10)), &["--", "comment"]),
    ("20_second_model.xml", Some((4, 3)), &["second <model>"]),
    ("21_second_camera.xml", Some((4, 3)), &["second <camera>"]),
    ("22_missing_camera.xml", None, &["<camera>"]),
    ("23_duplicate_color.xml", Some((6, 5)), &["second <color>", "<sphere>"]),
    ("24_duplicate_transformation.xml", Some((4, 5)), &["second <transformation>", "<camera>"]),
    ("25_duplicate_light_color.xml", Some((4, 40)), &["second <color>", "<light>"]),
    ("26_duplicate_attribute.xml", Some((3, 28)), &["<light>", "attribute x", "repeated"]),
    ("27_comma_decimal.xml", Some((4, 12)), &["<color>", "red=\"1,5\"", "not a number"]),
    ("28_hex_number.xml", Some((3, 10)), &["<light>", "x=\"0x10\"", "not a number"]),
    ("29_infinite.xml", Some((3, 30)), &["<material>", "kd=\"inf\"", "finite"]),
    ("30_overflow_to_infinity.xml", Some((4, 38)), &["<translate>", "z=\"1e400\"", "finite"]),
    ("31_nan_angle.xml", Some((4, 31)), &["<rotate-y>", "angle", "finite"]),
    ("32_empty_value.xml", Some((3, 16)), &["<light>", "y=\"\"", "not a number"]),
    ("33_width_float.xml", Some((2, 11)), &["<camera>", "width=\"600.0\"", "integer", "1 to 4294967295"]),
    ("34_height_exponent.xml", Some((2, 23)), &["<camera>", "height=\"6e2\"", "integer"]),
    ("35_width_zero.xml", Some((2, 11)), &["<camera>", "width=\"0\"", "integer", "1 to"]),
    ("36_height_negative.xml", Some((2, 22)), &["<camera>", "height=\"-10\"", "integer"]),
    ("37_depth_negative.xml", Some((3, 25)), &["<model>", "depth=\"-1\"", "integer", "0 to 10000"]),
    ("38_depth_too_large.xml", Some((3, 25)), &["<model>", "depth=\"10001\"", "0 to 10000"]),
    ("39_depth_overflow.xml", Some((3, 25)), &["<model>", "depth", "0 to 10000"]),
    ("40_eye_distance_zero.xml", Some((2, 32)), &["<camera>", "eyeDistance=\"0\"", "> 0"]),
    ("41_eye_distance_negative.xml", Some((2, 32)), &["<camera>", "eyeDistance=\"-2\"", "> 0"]),
    ("42_negative_ka.xml", Some((4, 15)), &["<material> attribute ka=\"-1\" must be >= 0"]),
    ("43_negative_light_color.xml", Some((4, 30)), &["<color>", "blue=\"-0.5\"", ">= 0"]),
    ("44_image_too_large.xml", Some((3, 3)), &["<camera>", "100000 x 100000", "268435456"]),
    ("45_scale_factor_with_x.xml", Some((4, 39)), &["<scale>", "factor", "x"]),
    ("46_scale_y_then_factor.xml", Some((4, 34)), &["<scale>", "factor"]),
    ("47_zero_scale.xml", Some((4, 5)), &["singular", "<transformation>"]),
    ("48_zero_scale_component.xml", Some((3, 5)), &["singular", "<transformation>"]),
    ("49_unknown_model.xml", Some((3, 10)), &["type=\"raytrace\"", "ambient", "lambert", "phong", "whitted"]),
    ("50_unknown_attribute_typo.xml", Some((4, 24)), &["<material>", "kd2", "unknown attribute"]),
    ("51_attribute_on_scene.xml", Some((1, 8)), &["<scene>", "version"]),
    ("52_attribute_on_sphere.xml", Some((3, 11)), &["<sphere>", "radius"]),
    ("53_unknown_element.xml", Some((3, 3)), &["<sphere2>", "<scene>", "unknown element"]),
    ("54_child_in_leaf.xml", Some((4, 39)), &["<x>", "<color>"]),
    ("55_unknown_transform_step.xml", Some((5, 7)), &["<rotate>", "<transformation>"]),
    ("56_nested_scene.xml", Some((3, 3)), &["<scene>", "unknown element"]),
    ("57_missing_light_y.xml", Some((3, 3)), &["<light>", "y", "missing"]),
    ("58_missing_rotate_angle.xml", Some((3, 26)), &["<rotate-z>", "angle", "missing"]),
    ("59_missing_model_type.xml", Some((3, 3)), &["<model>", "type", "missing"]),
    ("60_missing_color_green.xml", Some((4, 5)), &["<color>", "green", "missing"]),
    ("61_missing_eye_distance.xml", Some((2, 3)), &["<camera>", "eyeDistance", "missing"]),
    ("62_tabs_before_culprit.xml", Some((4, 22)), &["<material>", "m=\"-3\"", ">= 0"]),
    ("63_utf8_before_culprit.xml", Some((3, 45)), &["<light>", "z=\"∞\"", "not a number"]),
    ("64_utf8_element_name.xml", Some((3, 15)), &["<sphère>", "unknown element"]),
    ("65_crlf_line_ends.xml", Some((3, 22)), &["<light>", "z=\"a\""]),
    ("66_bom_not_counted.xml", Some((1, 8)), &["<sphere2>"]),
    // XML reads a lone CR as a line break, and CR LF as one (section 2.11).
    ("67_cr_line_ends.xml", Some((3, 22)), &["<light>", "z=\"a\""]),
    ("68_mixed_line_ends.xml", Some((4, 22)), &["<light>", "z=\"a\""]),
    // Composing finite steps can overflow: at the step that made it so.
    ("69_composed_overflow.xml", Some((6, 7)), &["<transformation>", "<translate>", "overflows"]),
    ("70_scale_overflow.xml", Some((4, 7)), &["<transformation>", "<scale>", "overflows"]),
    ("71_scale_inverse_overflow.xml", Some((3, 26)), &["<transformation>", "<scale>", "overflows"]),
    // Not well-formed XML that quick-xml alone lets through (the lines are
    // xmllint's: `xmllint_finds_the_same_lines`).
    ("72_two_byte_order_marks.xml", Some((1, 1)), &["byte-order mark"]),
    ("73_nul_in_comment.xml", Some((3, 10)), &["U+0000", "comment"]),
    ("74_control_in_comment.xml", Some((3, 8)), &["U+0001", "comment"]),
    ("75_utf16_declared.xml", Some((1, 31)), &["UTF-16", "UTF-8"]),
    ("76_attributes_without_space.xml", Some((4, 31)), &["<color>", "whitespace"]),
    ("77_bad_pi_target.xml", Some((4, 7)), &["xm--", "whitespace"]),
    ("78_control_in_attribute.xml", Some((3, 14)), &["<light>", "attribute x", "U+000C"]),
    ("79_reference_to_control.xml", Some((3, 10)), &["<light>", "attribute x", "U+000C", "character reference"]),
    ("80_cdata_before_root.xml", Some((1, 1)), &["CDATA", "outside"]),
    ("81_reserved_pi_target.xml", Some((2, 5)), &["xml", "reserved"]),
    ("82_xml_version_2.xml", Some((1, 16)), &["version", "2.0"]),
    ("83_standalone_maybe.xml", Some((2, 15)), &["standalone", "maybe"]),
    ("84_control_in_pi.xml", Some((3, 8)), &["U+0002", "processing instruction"]),
    ("85_nonchar_in_comment.xml", Some((3, 8)), &["U+FFFF", "comment"]),
    ("86_declaration_without_space.xml", Some((1, 20)), &["declaration", "whitespace"]),
    ("87_reference_to_nonchar.xml", Some((3, 22)), &["<light>", "attribute z", "U+FFFE", "character reference"]),
];

fn malformed(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("malformed")
        .join(name)
}

fn load_err(path: &Path) -> LoadError {
    match scene::load(path) {
        Ok(_) => panic!("{} loaded but must be refused", path.display()),
        Err(e) => e,
    }
}

#[test]
fn every_malformed_scene_is_refused_at_the_right_place() {
    let mut failures = Vec::new();
    for &(name, expected, words) in CASES {
        let path = malformed(name);
        let err = load_err(&path);
        let message = err.to_string();
        let position = err.position().map(|p| (p.line, p.column));
        if position != expected {
            failures.push(format!(
                "{name}: position {position:?}, expected {expected:?}: {message}"
            ));
        }
        // Display is `path:line:col: message` (or `path: message`), one line.
        let prefix = match expected {
            Some((line, column)) => format!("{}:{line}:{column}: ", path.display()),
            None => format!("{}: ", path.display()),
        };
        if !message.starts_with(&prefix) {
            failures.push(format!(
                "{name}: message does not start with {prefix:?}: {message}"
            ));
        }
        if message.contains('\n') || message.contains('\r') {
            failures.push(format!("{name}: message spans several lines: {message:?}"));
        }
        for word in words {
            if !message.contains(word) {
                failures.push(format!("{name}: message lacks {word:?}: {message}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} problem(s):\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Cases whose line is not xmllint's, and why.
const NOT_XMLLINT_LINE: &[&str] = &[
    // The file ends inside the culprit: xmllint reports the end of the file,
    // RayOfLight the element or tag that is not closed.
    "04_unclosed_tag.xml",
    "06_unclosed_quote.xml",
];

/// Every case xmllint (libxml2) finds not well-formed is refused, and at
/// xmllint's line (but for the few above, where it points elsewhere).
#[test]
fn xmllint_finds_the_same_lines() {
    let files: Vec<PathBuf> = CASES.iter().map(|c| malformed(c.0)).collect();
    let Some(lines) = common::xmllint(&files) else {
        return;
    };
    let mut failures = Vec::new();
    let mut compared = 0;
    for ((name, _, _), xmllint) in CASES.iter().zip(lines) {
        let Some(xmllint) = xmllint else { continue };
        let ours = load_err(&malformed(name)).position().map(|p| p.line);
        if NOT_XMLLINT_LINE.contains(name) {
            assert!(ours.is_some(), "{name}: refused without a position");
            continue;
        }
        compared += 1;
        if ours != Some(xmllint) {
            failures.push(format!("{name}: line {ours:?}, xmllint {xmllint}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(compared >= 25, "{compared} cases compared");
}

#[test]
fn every_malformed_file_is_in_the_table() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("tests/malformed")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".xml"))
        .collect();
    files.sort();
    let mut listed: Vec<String> = CASES.iter().map(|c| c.0.to_owned()).collect();
    listed.sort();
    assert_eq!(files, listed);
    assert!(CASES.len() >= 35);
}

/// The error kind of the malformed file named `NN_<case>.xml`.
fn kind(case: &str) -> LoadErrorKind {
    let suffix = format!("_{case}.xml");
    let (name, _, _) = CASES
        .iter()
        .find(|c| c.0.ends_with(&suffix))
        .unwrap_or_else(|| panic!("no case {case}"));
    load_err(&malformed(name)).kind
}

#[test]
fn kinds_are_typed() {
    use LoadErrorKind as K;
    assert_eq!(kind("empty_file"), K::MissingRoot);
    assert_eq!(kind("doctype"), K::Doctype);
    assert_eq!(
        kind("root_not_scene"),
        K::RootNotScene {
            element: "world".into()
        }
    );
    assert!(matches!(kind("unclosed_tag"), K::Xml { .. }));
    assert!(matches!(kind("unclosed_element"), K::Xml { .. }));
    assert!(matches!(kind("mismatched_end_tag"), K::Xml { .. }));
    assert!(matches!(
        kind("garbage_after_root"),
        K::ContentAfterRoot { .. }
    ));
    assert!(matches!(kind("unknown_entity"), K::BadReference { .. }));
    assert!(matches!(kind("text_content"), K::UnexpectedText { .. }));
    assert_eq!(kind("second_model"), K::SecondModel);
    assert_eq!(kind("second_camera"), K::SecondCamera);
    assert_eq!(kind("missing_camera"), K::MissingCamera);
    assert_eq!(
        kind("duplicate_color"),
        K::DuplicateElement {
            element: "color",
            parent: "sphere"
        }
    );
    assert_eq!(
        kind("duplicate_attribute"),
        K::DuplicateAttribute {
            element: "light",
            attribute: "x"
        }
    );
    assert_eq!(
        kind("comma_decimal"),
        K::InvalidNumber {
            element: "color",
            attribute: "red",
            value: "1,5".into()
        }
    );
    assert!(matches!(kind("infinite"), K::NotFinite { .. }));
    assert_eq!(
        kind("width_float"),
        K::InvalidInteger {
            element: "camera",
            attribute: "width",
            value: "600.0".into(),
            min: 1,
            max: u64::from(u32::MAX)
        }
    );
    assert_eq!(
        kind("depth_too_large"),
        K::InvalidInteger {
            element: "model",
            attribute: "depth",
            value: "10001".into(),
            min: 0,
            max: 10_000
        }
    );
    assert_eq!(
        kind("negative_ka"),
        K::OutOfRange {
            element: "material",
            attribute: "ka",
            value: "-1".into(),
            rule: ">= 0"
        }
    );
    assert_eq!(
        kind("image_too_large"),
        K::ImageTooLarge {
            width: 100_000,
            height: 100_000,
            limit: scene::MAX_PIXELS
        }
    );
    assert_eq!(
        kind("scale_factor_with_x"),
        K::ScaleFactorWithAxes { attribute: "x" }
    );
    assert_eq!(kind("zero_scale"), K::SingularTransform);
    assert_eq!(
        kind("composed_overflow"),
        K::TransformOverflow { step: "translate" }
    );
    assert_eq!(
        kind("unknown_model"),
        K::UnknownModel {
            value: "raytrace".into()
        }
    );
    assert!(matches!(
        kind("unknown_attribute_typo"),
        K::UnknownAttribute { ref attribute, .. } if attribute == "kd2"
    ));
    assert!(matches!(
        kind("unknown_element"),
        K::UnknownElement { ref element, parent: "scene", .. } if element == "sphere2"
    ));
    assert_eq!(
        kind("missing_light_y"),
        K::MissingAttribute {
            element: "light",
            attribute: "y"
        }
    );
}

#[test]
fn directory_and_missing_file_are_errors_without_position() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let err = load_err(&dir);
    assert_eq!(err.kind, LoadErrorKind::IsDirectory);
    assert_eq!(err.position(), None);
    assert!(err.to_string().starts_with(&format!("{}: ", dir.display())));

    let missing = dir.join("malformed").join("no such file.xml");
    let err = load_err(&missing);
    assert!(
        matches!(
            err.kind,
            LoadErrorKind::Io {
                kind: std::io::ErrorKind::NotFound,
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(err.position(), None);
    assert!(err.to_string().contains("no such file.xml"), "{err}");
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("load_errors");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

#[test]
fn non_utf8_file_is_refused_at_the_bad_byte() {
    let path = scratch("latin1.xml");
    std::fs::write(&path, b"<scene>\n<!-- \xe9t\xe9 -->\n</scene>\n").expect("write");
    let err = load_err(&path);
    assert_eq!(err.kind, LoadErrorKind::NotUtf8 { offset: 13 });
    // Not well-formed XML (xmllint: "Input is not proper UTF-8"): its
    // line and column, as for every other such file.
    assert_eq!(err.position(), Some(Position { line: 2, column: 6 }));
    assert!(err.to_string().contains(":2:6: "), "{err}");
    assert!(err.to_string().contains("UTF-8"), "{err}");
}

#[test]
fn oversized_file_is_refused_before_reading() {
    // A sparse file: its metadata says 1 GiB + 1 byte, nothing is written.
    let path = scratch("huge.xml");
    let file = std::fs::File::create(&path).expect("create");
    file.set_len(scene::MAX_FILE_BYTES + 1).expect("set_len");
    drop(file);
    let err = load_err(&path);
    let _ = std::fs::remove_file(&path);
    assert_eq!(
        err.kind,
        LoadErrorKind::FileTooLarge {
            size: scene::MAX_FILE_BYTES + 1,
            limit: scene::MAX_FILE_BYTES
        }
    );
    assert_eq!(err.position(), None);
}

#[test]
fn too_many_lights_is_refused_at_the_first_one_over() {
    let camera = r#"<camera width="1" height="1" eyeDistance="1"/>"#;
    let light = "<light x=\"0\" y=\"0\" z=\"0\"/>\n";
    let mut text = format!("<scene>{camera}\n");
    text.reserve(light.len() * (scene::MAX_LIGHTS + 2));
    for _ in 0..=scene::MAX_LIGHTS {
        text.push_str(light);
    }
    text.push_str("</scene>\n");
    let err = scene::parse(&text, Path::new("many.xml")).expect_err("too many lights");
    assert_eq!(
        err.kind,
        LoadErrorKind::TooManyLights {
            limit: scene::MAX_LIGHTS
        }
    );
    // Line 1 holds the camera, lights start on line 2.
    assert_eq!(
        err.position(),
        Some(Position {
            line: scene::MAX_LIGHTS + 2,
            column: 1
        })
    );
}

#[test]
fn errors_in_strings_name_the_given_path() {
    let err = scene::parse("<scene>\n <sphere2/>\n</scene>", Path::new("scenes/x.xml"))
        .expect_err("unknown element");
    assert!(
        err.to_string()
            .starts_with("scenes/x.xml:2:2: unknown element <sphere2> in <scene>"),
        "{err}"
    );
    let err = scene::parse(
        "<scene>\n<camera width=\"1\" height=\"1\" eyeDistance=\"1\"/>\n<sphere><material\n      ka=\"-1\"/></sphere></scene>",
        Path::new("scenes/x.xml"),
    )
    .expect_err("negative ka");
    assert_eq!(
        err.to_string(),
        "scenes/x.xml:4:7: <material> attribute ka=\"-1\" must be >= 0"
    );
}

/// A small deterministic generator (no dependency needed).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 33) as usize
    }
}

#[test]
fn no_input_makes_the_loader_panic() {
    let example = rayoflight::EXAMPLE_SCENE;
    let path = Path::new("fuzz.xml");
    // Every prefix, and the text with each character removed.
    for (i, _) in example.char_indices() {
        let _ = scene::parse(&example[..i], path);
        let mut cut = example.to_owned();
        cut.remove(i);
        let _ = scene::parse(&cut, path);
    }
    // Random insertions and replacements of XML-significant characters.
    let pieces = [
        "<",
        ">",
        "/",
        "\"",
        "'",
        "=",
        "&",
        ";",
        "#",
        "&#",
        "&#x",
        "<!--",
        "-->",
        "<?",
        "?>",
        "<![CDATA[",
        "]]>",
        "<!DOCTYPE",
        " ",
        "\t",
        "\n",
        "é",
        "☀",
        "0",
        "-",
        "e",
        "inf",
        "<sphere>",
        "</sphere>",
        "<color/>",
        "x=\"1\"",
        "\u{feff}",
        "\r",
        "\r\n",
    ];
    let mut rng = Lcg(0x5eed);
    for _ in 0..20_000 {
        let mut text = example.to_owned();
        for _ in 0..1 + rng.next() % 4 {
            let mut at = rng.next() % (text.len() + 1);
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            let piece = pieces[rng.next() % pieces.len()];
            if rng.next().is_multiple_of(2) {
                text.insert_str(at, piece);
            } else {
                let mut end = (at + 1 + rng.next() % 3).min(text.len());
                while !text.is_char_boundary(end) {
                    end += 1;
                }
                text.replace_range(at..end, piece);
            }
        }
        if let Err(e) = scene::parse(&text, path) {
            let message = e.to_string();
            assert!(!message.contains('\n'), "{message:?}");
            if let Some(p) = e.position() {
                // At most one line per LF or CR (CR LF is one break).
                let lines = text.split(['\n', '\r']).count();
                assert!(
                    p.line >= 1 && p.line <= lines && p.column >= 1,
                    "{p:?} in {text:?}"
                );
            }
        }
    }
}
