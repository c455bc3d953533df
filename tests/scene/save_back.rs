//! Save-back: writing a scene edited in the app into its XML source text,
//! keeping every byte that did not need to change (`scene::edit`).

use std::path::Path;

use crate::common::Rng;

use rayoflight::math::{Transform, TransformStep, Vec3};
use rayoflight::scene::edit::EditError;
use rayoflight::scene::fresh::to_xml;
use rayoflight::scene::splice::rewrite_by_index as rewrite;
use rayoflight::scene::{self, Camera, Illumination, Light, Material, Model, Object, Scene, Shape};

const EXAMPLE: &str = rayoflight::EXAMPLE_SCENE;

/// Comments everywhere, tabs, single quotes, odd attribute order and
/// spacing, attributes over several lines, empty elements with a space
/// before `/>`, numbers spelled oddly, the camera before the objects.
const ODD: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<!-- A scene written by hand, oddly. -->
<scene>
	<!-- the camera comes first -->
	<camera eyeDistance='4.0'   width="320"
	        height = "200" >
		<transformation><!-- back off -->
			<translate z="-20" x='+0'/>   <!-- trailing comment -->
		</transformation>
	</camera>

	<sphere>	<!-- red ball -->
		<transformation>
			<scale factor="1.50"/>
			<rotate-y angle=".5"/>
		</transformation>
		<color blue="0.0" red="1.0" green='0.20' />
	</sphere>
	<sphere />
	<!-- a floor -->
	<plane>
		<material m="20" ka="0.1"/>
	</plane>
	<light z="-2" x="1e0" y="-4" />
	<light x="5" y="5" z="5"><color red="0.5" green="0.5" blue="0.5"/></light>
	<!-- end of lights -->
</scene>
<!-- after the root -->
"#;

/// Everything on one line.
const FLAT: &str = r#"<scene><sphere><color red="1" green="0" blue="0"/></sphere><sphere></sphere><light x="1" y="2" z="3"/><camera width="10" height="10" eyeDistance="1"/></scene>"#;

/// CRLF line ends and a byte-order mark.
const CRLF: &str = "\u{feff}<?xml version=\"1.0\"?>\r\n<scene>\r\n  <!-- crlf -->\r\n  <sphere/>\r\n  <light x=\"0\" y=\"0\" z=\"0\"/>\r\n  <camera width=\"8\" height=\"6\" eyeDistance=\"2\"/>\r\n</scene>\r\n";

fn path() -> &'static Path {
    Path::new("test.xml")
}

fn parse(text: &str) -> Scene {
    scene::parse(text, path()).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Rewrites `text` for `edited` and checks that it loads as `edited`.
fn save(text: &str, edited: &Scene) -> String {
    let out = rewrite(text, path(), edited).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let back = scene::parse(&out, path()).unwrap_or_else(|e| panic!("{e}\n{out}"));
    assert_eq!(&back, edited, "rewritten text:\n{out}");
    out
}

fn transform(steps: Vec<TransformStep>) -> Transform {
    Transform::from_steps(steps).unwrap()
}

/// The lines removed from `a` and the lines added in `b` (a longest common
/// subsequence diff).
fn diff(a: &str, b: &str) -> (Vec<String>, Vec<String>) {
    let a: Vec<&str> = a.split('\n').collect();
    let b: Vec<&str> = b.split('\n').collect();
    let (n, m) = (a.len(), b.len());
    let mut lcs = vec![vec![0usize; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            lcs[i][j] = if a[i] == b[j] {
                lcs[i + 1][j + 1] + 1
            } else {
                lcs[i + 1][j].max(lcs[i][j + 1])
            };
        }
    }
    let (mut i, mut j) = (0, 0);
    let (mut removed, mut added) = (Vec::new(), Vec::new());
    while i < n || j < m {
        if i < n && j < m && a[i] == b[j] {
            i += 1;
            j += 1;
        } else if j < m && (i == n || lcs[i][j + 1] >= lcs[i + 1][j]) {
            added.push(b[j].to_owned());
            j += 1;
        } else {
            removed.push(a[i].to_owned());
            i += 1;
        }
    }
    (removed, added)
}

/// Checks that `out` differs from `text` exactly by the lines given.
fn assert_diff(text: &str, out: &str, removed: &[&str], added: &[&str]) {
    let (r, a) = diff(text, out);
    assert_eq!(
        (r, a),
        (
            removed.iter().map(|s| s.to_string()).collect(),
            added.iter().map(|s| s.to_string()).collect()
        ),
        "rewritten text:\n{out}"
    );
}

// ----- round trips -----

#[test]
fn unchanged_scenes_are_kept_byte_for_byte() {
    for text in [EXAMPLE, ODD, FLAT, CRLF] {
        let s = parse(text);
        assert_eq!(rewrite(text, path(), &s).unwrap(), text);
    }
}

#[test]
fn an_edit_undone_restores_the_values_and_the_rest() {
    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[0]).color.x = 0.25;
    let out = save(ODD, &s);
    std::sync::Arc::make_mut(&mut s.objects[0]).color.x = 1.0;
    let back = save(&out, &s);
    // The value comes back as Rust writes it; everything else is identical.
    assert_diff(
        ODD,
        &back,
        &["\t\t<color blue=\"0.0\" red=\"1.0\" green='0.20' />"],
        &["\t\t<color blue=\"0.0\" red=\"1\" green='0.20' />"],
    );
}

// ----- one edit of each kind -----

#[test]
fn material_value() {
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[1]).material.kd = 0.75;
    std::sync::Arc::make_mut(&mut s.objects[1]).material.m = 1.0; // unchanged: the text keeps "1"
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#" <material ka="0.4" kd="0.5" ks="0.3" m="1"/>"#],
        &[r#" <material ka="0.4" kd="0.75" ks="0.3" m="1"/>"#],
    );
}

#[test]
fn colour_keeps_the_spelling_of_the_other_components() {
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[1]).color.y = 0.125;
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#" <color red="1.0" green="0.2" blue="0.0"/>"#],
        &[r#" <color red="1.0" green="0.125" blue="0.0"/>"#],
    );
}

#[test]
fn colour_in_single_quotes_and_odd_order() {
    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[0]).color = Vec3::new(1.0, 0.3, 0.0);
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &["\t\t<color blue=\"0.0\" red=\"1.0\" green='0.20' />"],
        &["\t\t<color blue=\"0.0\" red=\"1.0\" green='0.3' />"],
    );
}

#[test]
fn light_position() {
    let mut s = parse(EXAMPLE);
    s.lights[0].position = Vec3::new(1.0, -5.5, -2.0);
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#"<light x="1" y="-4" z="-2">"#],
        &[r#"<light x="1" y="-5.5" z="-2">"#],
    );
    // "1e0" is 1: not rewritten when only z changes.
    let mut s = parse(ODD);
    s.lights[0].position.z = 3.0;
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &["\t<light z=\"-2\" x=\"1e0\" y=\"-4\" />"],
        &["\t<light z=\"3\" x=\"1e0\" y=\"-4\" />"],
    );
}

#[test]
fn camera_width_height_and_eye_distance() {
    let mut s = parse(EXAMPLE);
    s.camera.width = 800;
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#"<camera width="600" height="600" eyeDistance="4">"#],
        &[r#"<camera width="800" height="600" eyeDistance="4">"#],
    );
    // Attributes over two lines, spaces around `=`.
    let mut s = parse(ODD);
    s.camera.height = 240;
    s.camera.eye_distance = 2.5;
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &[
            "\t<camera eyeDistance='4.0'   width=\"320\"",
            "\t        height = \"200\" >",
        ],
        &[
            "\t<camera eyeDistance='2.5'   width=\"320\"",
            "\t        height = \"240\" >",
        ],
    );
}

#[test]
fn model_type_and_depth() {
    let mut s = parse(EXAMPLE);
    s.model = Model {
        illumination: Illumination::Lambert,
        depth: 2,
    };
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#"<model type="whitted" depth="2"/>"#],
        &[r#"<model type="lambert" depth="2"/>"#],
    );
    s.model.depth = 7;
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#"<model type="whitted" depth="2"/>"#],
        &[r#"<model type="lambert" depth="7"/>"#],
    );
}

#[test]
fn model_added_when_missing_and_not_default() {
    let mut s = parse(ODD);
    assert_eq!(s.model, Model::default());
    s.model.illumination = Illumination::Whitted;
    let out = save(ODD, &s);
    assert_diff(ODD, &out, &[], &["\t<model type=\"whitted\"/>"]);
    assert!(out.contains("\t<!-- end of lights -->\n\t<model type=\"whitted\"/>\n</scene>"));

    let mut s = parse(ODD);
    s.model.depth = 3;
    let out = save(ODD, &s);
    assert_diff(ODD, &out, &[], &["\t<model type=\"phong\" depth=\"3\"/>"]);
}

#[test]
fn model_depth_added_as_an_attribute() {
    let text = EXAMPLE.replace(
        r#"<model type="whitted" depth="2"/>"#,
        r#"<model type='whitted'/>"#,
    );
    let mut s = parse(&text);
    s.model.depth = 4;
    let out = save(&text, &s);
    assert_diff(
        &text,
        &out,
        &["<model type='whitted'/>"],
        &["<model type='whitted' depth='4'/>"],
    );
}

#[test]
fn transformation_values_edited_in_place() {
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[0]).transform =
        transform(vec![TransformStep::Translate(Vec3::new(2.0, 1.5, -2.0))]);
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#"  <translate x="2" y="0" z="-2"/>"#],
        &[r#"  <translate x="2" y="1.5" z="-2"/>"#],
    );
    // A missing attribute (y defaults to 0) is appended; comments stay.
    let mut s = parse(ODD);
    s.camera.transform = transform(vec![TransformStep::Translate(Vec3::new(0.0, -1.0, -20.0))]);
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &["\t\t\t<translate z=\"-20\" x='+0'/>   <!-- trailing comment -->"],
        &["\t\t\t<translate z=\"-20\" x='+0' y='-1'/>   <!-- trailing comment -->"],
    );
}

#[test]
fn transformation_steps_rewritten() {
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[1]).transform = transform(vec![
        TransformStep::RotateZ(0.25),
        TransformStep::Scale(Vec3::new(1.0, 2.0, 0.5)),
        TransformStep::Translate(Vec3::new(-2.0, 0.0, -2.0)),
    ]);
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[],
        &[
            r#"  <rotate-z angle="0.25"/>"#,
            r#"  <scale x="1" y="2" z="0.5"/>"#,
        ],
    );
    // The camera's transformation keeps its own odd indentation.
    let mut s = parse(EXAMPLE);
    s.camera.transform = transform(vec![
        TransformStep::RotateX(-0.1),
        TransformStep::Translate(Vec3::new(0.0, 0.0, -20.0)),
    ]);
    let out = save(EXAMPLE, &s);
    assert_diff(EXAMPLE, &out, &[], &[r#"   <rotate-x angle="-0.1"/>"#]);
    assert!(out.contains("  <transformation>\n   <rotate-x angle=\"-0.1\"/>\n   <translate x=\"0\" y=\"0\" z=\"-20\"/>\n </transformation>\n</camera>"));
}

#[test]
fn steps_removed_when_emptied_and_transformation_added_when_missing() {
    // Removing every step removes the steps, not the <transformation>
    // element the user did not remove (nor the comments it may hold).
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[0]).transform = Transform::default();
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#"  <translate x="2" y="0" z="-2"/>"#],
        &[],
    );
    assert!(out.contains(" <transformation>\n </transformation>\n</sphere>"));

    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[2]).transform =
        transform(vec![TransformStep::RotateX(1.5)]);
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &[],
        &[
            "\t\t<transformation>",
            "\t\t\t<rotate-x angle=\"1.5\"/>",
            "\t\t</transformation>",
        ],
    );
    assert!(out.contains("<plane>\n\t\t<material m=\"20\" ka=\"0.1\"/>\n\t\t<transformation>"));
}

#[test]
fn missing_material_and_colour_are_inserted_in_order() {
    // The red ball has its transformation before its colour, and no
    // material: the material goes before the first sibling that ranks after
    // it (color < material < transformation), here the transformation.
    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[0]).material.ks = 0.5;
    let out = save(ODD, &s);
    assert_diff(ODD, &out, &[], &["\t\t<material ks=\"0.5\"/>"]);
    assert!(out.contains("<!-- red ball -->\n\t\t<material ks=\"0.5\"/>\n\t\t<transformation>"));

    // The plane has a material and no colour: the colour goes before it.
    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[2]).color = Vec3::new(0.5, 0.5, 0.5);
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &[],
        &["\t\t<color red=\"0.5\" green=\"0.5\" blue=\"0.5\"/>"],
    );
    assert!(
        out.contains("<plane>\n\t\t<color red=\"0.5\" green=\"0.5\" blue=\"0.5\"/>\n\t\t<material")
    );
}

#[test]
fn material_attribute_added_to_an_existing_material() {
    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[2]).material.kd = 0.9;
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &["\t\t<material m=\"20\" ka=\"0.1\"/>"],
        &["\t\t<material m=\"20\" ka=\"0.1\" kd=\"0.9\"/>"],
    );
}

#[test]
fn empty_element_opened_for_children() {
    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[1]).color = Vec3::new(0.0, 0.0, 1.0);
    std::sync::Arc::make_mut(&mut s.objects[1]).material.ka = 0.5;
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &["\t<sphere />"],
        &[
            "\t<sphere>",
            "\t\t<color red=\"0\" green=\"0\" blue=\"1\"/>",
            "\t\t<material ka=\"0.5\"/>",
            "\t</sphere>",
        ],
    );
    // A light colour on a light without children.
    let mut s = parse(EXAMPLE);
    s.lights[0].color = Vec3::new(2.0, 2.0, 2.0);
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[r#" <color red="1.0" green="1.0" blue="1.0"/>"#],
        &[r#" <color red="2" green="2" blue="2"/>"#],
    );
    let mut s = parse(ODD);
    s.lights[0].color = Vec3::new(0.0, 1.0, 0.0);
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &["\t<light z=\"-2\" x=\"1e0\" y=\"-4\" />"],
        &[
            "\t<light z=\"-2\" x=\"1e0\" y=\"-4\">",
            "\t\t<color red=\"0\" green=\"1\" blue=\"0\"/>",
            "\t</light>",
        ],
    );
}

#[test]
fn shape_change_renames_both_tags() {
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[0]).shape = Shape::Plane;
    let out = save(EXAMPLE, &s);
    let (removed, added) = diff(EXAMPLE, &out);
    assert_eq!(removed, ["<sphere>", "</sphere>"]);
    assert_eq!(added, ["<plane>", "</plane>"]);
    // An empty element, renamed and opened at once.
    let mut s = parse(ODD);
    std::sync::Arc::make_mut(&mut s.objects[1]).shape = Shape::Plane;
    std::sync::Arc::make_mut(&mut s.objects[1]).transform =
        transform(vec![TransformStep::RotateX(1.0)]);
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &["\t<sphere />"],
        &[
            "\t<plane>",
            "\t\t<transformation>",
            "\t\t\t<rotate-x angle=\"1\"/>",
            "\t\t</transformation>",
            "\t</plane>",
        ],
    );
}

#[test]
fn objects_and_lights_added_after_the_last_of_their_kind() {
    let mut s = parse(EXAMPLE);
    s.objects.push(
        Object {
            shape: Shape::Plane,
            color: Vec3::ONE,
            material: Material::default(),
            transform: Transform::default(),
        }
        .into(),
    );
    s.objects.push(
        Object {
            shape: Shape::Sphere,
            color: Vec3::new(0.5, 0.25, 1.0),
            material: Material {
                m: 30.0,
                ..Material::default()
            },
            transform: transform(vec![TransformStep::UniformScale(0.5)]),
        }
        .into(),
    );
    s.lights.push(Light {
        position: Vec3::new(0.0, -10.0, 0.0),
        color: Vec3::ONE,
    });
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[],
        &[
            "<plane/>",
            "<sphere>",
            r#" <color red="0.5" green="0.25" blue="1"/>"#,
            r#" <material m="30"/>"#,
            " <transformation>",
            r#"  <scale factor="0.5"/>"#,
            " </transformation>",
            "</sphere>",
            r#"<light x="0" y="-10" z="0"/>"#,
        ],
    );
    assert!(out.contains("</sphere>\n<plane/>\n<sphere>\n"));
    assert!(out.contains("</light>\n<light x=\"0\" y=\"-10\" z=\"0\"/>\n<camera"));
}

#[test]
fn trailing_objects_and_lights_removed_with_their_lines() {
    let mut s = parse(EXAMPLE);
    s.objects.pop();
    s.lights.clear();
    let out = save(EXAMPLE, &s);
    assert_diff(
        EXAMPLE,
        &out,
        &[
            "<sphere>",
            r#" <color red="1.0" green="0.2" blue="0.0"/>"#,
            r#" <material ka="0.4" kd="0.5" ks="0.3" m="1"/>"#,
            " <transformation>",
            r#"  <translate x="-2" y="0" z="-2"/>"#,
            " </transformation>",
            "</sphere>",
            r#"<light x="1" y="-4" z="-2">"#,
            r#" <color red="1.0" green="1.0" blue="1.0"/>"#,
            "</light>",
        ],
        &[],
    );

    let mut s = parse(ODD);
    s.objects.truncate(1);
    s.lights.truncate(1);
    let out = save(ODD, &s);
    assert_diff(
        ODD,
        &out,
        &[
            "\t<sphere />",
            "\t<!-- a floor -->",
            "\t<plane>",
            "\t\t<material m=\"20\" ka=\"0.1\"/>",
            "\t</plane>",
            "\t<light x=\"5\" y=\"5\" z=\"5\"><color red=\"0.5\" green=\"0.5\" blue=\"0.5\"/></light>",
        ],
        &[],
    );
    // The comment directly above the plane described it and went with it;
    // the one below the last light stays.
    assert!(out.contains("<!-- end of lights -->"));
}

#[test]
fn one_line_files_stay_on_one_line() {
    let mut s = parse(FLAT);
    std::sync::Arc::make_mut(&mut s.objects[0]).material.ka = 0.5;
    std::sync::Arc::make_mut(&mut s.objects[1]).color = Vec3::new(0.0, 1.0, 0.0);
    s.lights[0].color = Vec3::new(0.5, 0.5, 0.5);
    let out = save(FLAT, &s);
    assert_eq!(
        out,
        r#"<scene><sphere><color red="1" green="0" blue="0"/><material ka="0.5"/></sphere><sphere>
  <color red="0" green="1" blue="0"/>
</sphere><light x="1" y="2" z="3">
  <color red="0.5" green="0.5" blue="0.5"/>
</light><camera width="10" height="10" eyeDistance="1"/></scene>"#
    );
    let mut s = parse(FLAT);
    s.objects.pop();
    let out = save(FLAT, &s);
    assert_eq!(out, FLAT.replace("<sphere></sphere>", ""));
}

#[test]
fn crlf_and_byte_order_mark_are_kept() {
    let mut s = parse(CRLF);
    std::sync::Arc::make_mut(&mut s.objects[0]).color = Vec3::new(0.0, 0.5, 0.0);
    s.lights.push(Light {
        position: Vec3::ONE,
        color: Vec3::ONE,
    });
    let out = save(CRLF, &s);
    assert!(out.starts_with('\u{feff}'));
    assert!(!out.replace("\r\n", "").contains('\n'), "{out:?}");
    assert_diff(
        CRLF,
        &out,
        &["  <sphere/>\r"],
        &[
            "  <sphere>\r",
            "    <color red=\"0\" green=\"0.5\" blue=\"0\"/>\r",
            "  </sphere>\r",
            "  <light x=\"1\" y=\"1\" z=\"1\"/>\r",
        ],
    );
}

#[test]
fn numbers_are_written_to_read_back_exactly() {
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[0]).material.ka = 0.1 + 0.2;
    std::sync::Arc::make_mut(&mut s.objects[0]).color.x = 1e-9;
    s.lights[0].position.x = -1e25;
    s.camera.eye_distance = 1.0 / 3.0;
    save(EXAMPLE, &s);
}

// ----- errors -----

#[test]
fn a_text_that_does_not_load_is_an_error() {
    let s = parse(EXAMPLE);
    let err = rewrite("<scene>", path(), &s).unwrap_err();
    assert!(matches!(err, EditError::Parse(_)), "{err}");
}

#[test]
fn invalid_edited_values_are_an_error() {
    let mut s = parse(EXAMPLE);
    std::sync::Arc::make_mut(&mut s.objects[0]).material.ka = -1.0;
    assert!(matches!(
        rewrite(EXAMPLE, path(), &s),
        Err(EditError::Invalid(_))
    ));
    let mut s = parse(EXAMPLE);
    s.lights[0].position.y = f64::NAN;
    assert!(matches!(
        rewrite(EXAMPLE, path(), &s),
        Err(EditError::Invalid(_))
    ));
    let mut s = parse(EXAMPLE);
    s.camera.width = 0;
    let err = rewrite(EXAMPLE, path(), &s).unwrap_err();
    assert!(err.to_string().contains("width"), "{err}");
}

// ----- random edits -----

// The random scene edits, on the shared generator.
impl Rng {
    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }

    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A non-negative number: round, long, tiny or huge.
    fn positive(&mut self) -> f64 {
        match self.below(6) {
            0 => [0.0, 0.5, 1.0, 2.0, 10.0, 0.1][self.below(6)],
            1 => self.unit(),
            2 => self.unit() * 100.0,
            3 => self.unit() * 1e-12,
            4 => self.unit() * 1e20,
            _ => (self.below(100) as f64) / 10.0,
        }
    }

    fn signed(&mut self) -> f64 {
        let v = self.positive();
        if self.chance(50) { -v } else { v }
    }

    /// A non-zero number of moderate size (scale factors).
    fn factor(&mut self) -> f64 {
        let v = 0.1 + self.unit() * 3.0;
        if self.chance(20) { -v } else { v }
    }

    fn vec(&mut self, f: impl Fn(&mut Rng) -> f64) -> Vec3 {
        Vec3::new(f(self), f(self), f(self))
    }

    fn step(&mut self) -> TransformStep {
        match self.below(6) {
            0 => TransformStep::Translate(self.vec(|r| r.signed().clamp(-1e6, 1e6))),
            1 => TransformStep::RotateX(self.signed().clamp(-10.0, 10.0)),
            2 => TransformStep::RotateY(self.unit() * 6.0),
            3 => TransformStep::RotateZ(-self.unit()),
            4 => TransformStep::UniformScale(self.factor()),
            _ => TransformStep::Scale(self.vec(Rng::factor)),
        }
    }

    fn transform(&mut self, old: &Transform) -> Transform {
        let mut steps = old.steps().to_vec();
        match self.below(5) {
            0 => steps.clear(),
            1 => steps.push(self.step()),
            2 if !steps.is_empty() => {
                // Same kind, new values: edited in place.
                let i = self.below(steps.len());
                steps[i] = match steps[i] {
                    TransformStep::Translate(mut v) => {
                        v.y = self.signed();
                        TransformStep::Translate(v)
                    }
                    TransformStep::RotateX(_) => TransformStep::RotateX(self.unit()),
                    TransformStep::RotateY(_) => TransformStep::RotateY(self.unit()),
                    TransformStep::RotateZ(_) => TransformStep::RotateZ(self.unit()),
                    TransformStep::UniformScale(_) => TransformStep::UniformScale(self.factor()),
                    TransformStep::Scale(mut v) => {
                        v.z = self.factor();
                        TransformStep::Scale(v)
                    }
                };
            }
            3 if !steps.is_empty() => {
                steps.remove(self.below(steps.len()));
            }
            _ => steps = (0..self.below(4)).map(|_| self.step()).collect(),
        }
        Transform::from_steps(steps).unwrap_or_else(|_| old.clone())
    }

    fn object(&mut self) -> Object {
        Object {
            shape: if self.chance(50) {
                Shape::Sphere
            } else {
                Shape::Plane
            },
            color: if self.chance(50) {
                Vec3::ONE
            } else {
                self.vec(Rng::positive)
            },
            material: if self.chance(50) {
                Material::default()
            } else {
                Material {
                    ka: self.positive(),
                    ..Material::default()
                }
            },
            transform: self.transform(&Transform::default()),
        }
    }

    fn light(&mut self) -> Light {
        Light {
            position: self.vec(Rng::signed),
            color: if self.chance(50) {
                Vec3::ONE
            } else {
                self.vec(Rng::positive)
            },
        }
    }

    /// One random edit of `s`.
    fn edit(&mut self, s: &mut Scene) {
        match self.below(12) {
            0 if !s.objects.is_empty() => {
                let i = self.below(s.objects.len());
                let o = std::sync::Arc::make_mut(&mut s.objects[i]);
                match self.below(4) {
                    0 => o.material.ka = self.positive(),
                    1 => o.material.kd = self.positive(),
                    2 => o.material.ks = self.positive(),
                    _ => o.material.m = self.positive(),
                }
            }
            1 if !s.objects.is_empty() => {
                let i = self.below(s.objects.len());
                std::sync::Arc::make_mut(&mut s.objects[i]).color = self.vec(Rng::positive);
            }
            2 if !s.objects.is_empty() => {
                let i = self.below(s.objects.len());
                let t = self.transform(&s.objects[i].transform);
                std::sync::Arc::make_mut(&mut s.objects[i]).transform = t;
            }
            3 if !s.objects.is_empty() => {
                let i = self.below(s.objects.len());
                let o = std::sync::Arc::make_mut(&mut s.objects[i]);
                o.shape = match o.shape {
                    Shape::Sphere => Shape::Plane,
                    Shape::Plane => Shape::Sphere,
                };
            }
            4 => {
                let o = self.object();
                s.objects.push(o.into());
            }
            5 => {
                let n = self.below(s.objects.len() + 1);
                let keep = s.objects.len() - n.min(2);
                s.objects.truncate(keep);
            }
            6 if !s.lights.is_empty() => {
                let i = self.below(s.lights.len());
                if self.chance(50) {
                    s.lights[i].position = self.vec(Rng::signed);
                } else {
                    s.lights[i].color = self.vec(Rng::positive);
                }
            }
            7 => {
                if self.chance(50) {
                    let l = self.light();
                    s.lights.push(l);
                } else {
                    s.lights.pop();
                }
            }
            8 => {
                s.camera.width = 1 + self.below(2000) as u32;
                s.camera.height = 1 + self.below(2000) as u32;
            }
            9 => s.camera.eye_distance = 0.01 + self.positive(),
            10 => {
                let t = self.transform(&s.camera.transform);
                s.camera.transform = t;
            }
            _ => {
                s.model = Model {
                    illumination: Illumination::ALL[self.below(4)],
                    depth: if self.chance(50) {
                        1
                    } else {
                        self.below(11) as u32
                    },
                };
            }
        }
    }

    fn scene(&mut self) -> Scene {
        Scene {
            objects: (0..self.below(5)).map(|_| self.object().into()).collect(),
            lights: (0..self.below(3)).map(|_| self.light()).collect(),
            camera: Camera {
                width: 1 + self.below(1000) as u32,
                height: 1 + self.below(1000) as u32,
                eye_distance: 0.01 + self.positive(),
                transform: self.transform(&Transform::default()),
            },
            model: Model {
                illumination: Illumination::ALL[self.below(4)],
                depth: self.below(20) as u32,
            },
        }
    }
}

/// The texts the random tests start from: ours and the repository's scenes.
fn sources() -> Vec<String> {
    let mut texts: Vec<String> = [EXAMPLE, ODD, FLAT, CRLF].map(str::to_owned).to_vec();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden");
    if let Ok(entries) = std::fs::read_dir(dir) {
        let mut paths: Vec<_> = entries.flatten().map(|e| e.path()).collect();
        paths.sort();
        for p in paths {
            if p.extension().is_some_and(|e| e == "xml")
                && let Ok(text) = std::fs::read_to_string(&p)
                && scene::parse(&text, &p).is_ok()
            {
                texts.push(text);
            }
        }
    }
    texts
}

#[test]
fn random_edits_always_load_as_edited() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut checked = 0;
    for text in sources() {
        for _ in 0..60 {
            // A chain of saves: each one rewrites the text the previous one
            // wrote, as the app does when the user saves again.
            let mut current = text.clone();
            let mut s = parse(&current);
            for _ in 0..4 {
                for _ in 0..1 + rng.below(4) {
                    rng.edit(&mut s);
                }
                current = save(&current, &s);
                checked += 1;
            }
        }
    }
    assert!(checked >= 4 * 60 * 4);
}

#[test]
fn random_edits_touch_only_what_they_change() {
    // Value edits of one attribute change exactly one line of the example.
    let mut rng = Rng(42);
    for _ in 0..200 {
        let mut s = parse(EXAMPLE);
        match rng.below(4) {
            0 => {
                std::sync::Arc::make_mut(&mut s.objects[rng.below(2)])
                    .material
                    .kd = rng.positive() + 0.01
            }
            1 => s.lights[0].position.x = rng.signed() + 1e-3,
            2 => s.camera.height = 1 + rng.below(599) as u32,
            _ => {
                std::sync::Arc::make_mut(&mut s.objects[rng.below(2)])
                    .color
                    .z = rng.positive() + 1e-3
            }
        }
        let out = save(EXAMPLE, &s);
        let (removed, added) = diff(EXAMPLE, &out);
        assert_eq!((removed.len(), added.len()), (1, 1), "{out}");
    }
}

// ----- fresh files -----

#[test]
fn to_xml_round_trips_the_example() {
    let s = parse(EXAMPLE);
    let text = to_xml(&s);
    assert_eq!(parse(&text), s, "{text}");
    assert!(text.starts_with("<?xml version=\"1.0\"?>\n<scene>\n  <sphere>\n    <color "));
    // And the fresh file is itself a good source for save-back.
    let mut edited = s.clone();
    std::sync::Arc::make_mut(&mut edited.objects[0]).color.x = 0.9;
    save(&text, &edited);
}

#[test]
fn to_xml_round_trips_random_scenes() {
    let mut rng = Rng(7);
    for _ in 0..500 {
        let s = rng.scene();
        let text = to_xml(&s);
        assert_eq!(parse(&text), s, "{text}");
    }
    for text in sources() {
        let s = parse(&text);
        assert_eq!(parse(&to_xml(&s)), s);
    }
}
