//! The POV-Ray 3.7 translation of a scene (docs/scene-format.md,
//! Cross-checking with POV-Ray), used to cross-check our renders against an
//! independent raytracer.
//!
//! Our world is right-handed with y down; POV-Ray's is left-handed with y up.
//! The mirror F = diag(1, −1, 1) maps one onto the other: every point
//! (x, y, z) becomes (x, −y, z) and every matrix M becomes F·M·F. POV-Ray's
//! `matrix <…>` keyword is written for row vectors, so its first nine numbers
//! are the 3×3 part transposed (column j of our matrix is its row j) and the
//! translation comes last.
//!
//! The finish reproduces the scene format's formulas (docs/scene-format.md,
//! Illumination) exactly: `pigment { rgb 1 }`
//! so that the diffuse term is not multiplied by the object's colour, the
//! ambient term `ka·C` as an ambient colour (with `ambient_light rgb 1`),
//! `brilliance 1`, `phong ks phong_size m`, `specular 0`, `reflection { ks }`,
//! and `no_shadow` on every object (lights are never occluded). Terms the
//! model does not use are left out, except `diffuse 0` for `ambient` (POV-Ray's
//! default diffuse is 0.6). `max_trace_level` is the reflection depth plus one
//! and `adc_bailout 0` follows every reflection to the end. The file starts
//! with `#version 3.7;` so that POV-Ray applies no 3.6 compatibility settings.
//!
//! Render the result with
//! `povray -A +FN File_Gamma=1.0 +W<w> +H<h> +I<file>.pov +O<out>.png`
//! (no anti-aliasing, PNG, no gamma). POV-Ray caps `max_trace_level` at 256,
//! so whitted depths above 255 cannot be cross-checked.
//!
//! Numbers are written in Rust's shortest round-trip form (`{:?}`), which
//! POV-Ray's parser reads back to the same `f64` (`1e-7`, `1e20` included).

use std::fmt::Write as _;
use std::path::Path;

use glam::{DAffine3, DVec3};

use crate::scene::{Illumination, Object, Scene};

/// The largest `max_trace_level` POV-Ray accepts.
pub const POV_MAX_TRACE_LEVEL: u32 = 256;

/// POV-Ray's command-line flags for a cross-check (docs/scene-format.md,
/// Cross-checking with POV-Ray), before `+W +H +I +O`.
pub const POV_FLAGS: &str = "-A +FN File_Gamma=1.0";

/// Translates `scene` to POV-Ray 3.7 scene language (docs/scene-format.md,
/// Cross-checking with POV-Ray).
pub fn export(scene: &Scene) -> String {
    export_named(scene, None)
}

/// The files a translation names in its header comment: the scene it
/// came from, and the file it is written to (whose render command it
/// gives: `+I` that file, `+O` its name with `-pov.png`, beside it, so that
/// POV-Ray's image never overwrites RayOfLight's own `NAME.png`).
#[derive(Debug, Clone, Copy)]
pub struct Header<'a> {
    pub scene: &'a Path,
    pub written_to: &'a Path,
}

/// Like [`export`], with the [`Header`]'s names in the header comment and
/// its render command. The names come from outside: each is written so
/// that it stays inside its comment line (no control character: a newline
/// would start POV-Ray code) and is one word for a shell.
pub fn export_named(scene: &Scene, header: Option<Header>) -> String {
    let mut out = String::new();
    write_scene(&mut out, scene, header).expect("writing to a String cannot fail");
    out
}

/// `name` as a comment holds it: every control character (a line break
/// would end the comment) and Unicode line separator shown as `?`.
fn in_comment(name: &str) -> String {
    name.chars()
        .map(
            |c| match c.is_control() || matches!(c, '\u{2028}' | '\u{2029}') {
                true => '?',
                false => c,
            },
        )
        .collect()
}

/// `word` as one word for a shell: single-quoted unless it only holds
/// characters no shell treats apart.
fn shell_word(word: &str) -> String {
    if !word.is_empty() && word.chars().all(plain) {
        return word.to_owned();
    }
    format!("'{}'", word.replace('\'', "'\\''"))
}

/// A character that needs no quoting anywhere (shell or POV-Ray).
fn plain(c: char) -> bool {
    c.is_ascii_alphanumeric() || "+-_./=,:@%".contains(c)
}

/// POV-Ray's option naming the file `name` (`+I`/`+O`, or the INI-style
/// `Input_File_Name="…"` that takes spaces), as one shell word; `None`
/// when no option can hold it (a double quote, a control character).
fn pov_option(short: &str, long: &str, name: &str) -> Option<String> {
    if name.chars().all(plain) {
        return Some(format!("{short}{name}"));
    }
    if name.chars().any(|c| c == '"' || c.is_control()) {
        return None;
    }
    Some(shell_word(&format!("{long}=\"{name}\"")))
}

fn write_scene(out: &mut String, scene: &Scene, header: Option<Header>) -> std::fmt::Result {
    let model = scene.model;
    let cam = &scene.camera;
    writeln!(
        out,
        "// POV-Ray 3.7 translation of a RayOfLight scene \
         (docs/scene-format.md, Cross-checking with POV-Ray)."
    )?;
    if let Some(h) = header {
        writeln!(out, "// Source: {}", in_comment(&h.scene.to_string_lossy()))?;
    }
    writeln!(
        out,
        "// Model: {} depth {} ({} reflection level(s) followed); {} object(s), {} light(s).",
        model.illumination.name(),
        model.depth,
        model.reflection_depth(),
        scene.objects.len(),
        scene.lights.len()
    )?;
    let (input, image) = match header {
        Some(h) => {
            let image = h.written_to.with_file_name(format!(
                "{}-pov.png",
                h.written_to
                    .file_stem()
                    .map_or("scene".into(), |s| s.to_string_lossy())
            ));
            (
                h.written_to.to_string_lossy().into_owned(),
                image.to_string_lossy().into_owned(),
            )
        }
        None => ("scene.pov".to_owned(), "scene-pov.png".to_owned()),
    };
    let (w, h) = (cam.width, cam.height);
    match (
        pov_option("+I", "Input_File_Name", &input),
        pov_option("+O", "Output_File_Name", &image),
    ) {
        (Some(input), Some(image)) => writeln!(
            out,
            "// Render: povray {POV_FLAGS} +W{w} +H{h} {input} {image}"
        )?,
        _ => writeln!(
            out,
            "// Render: povray {POV_FLAGS} +W{w} +H{h} +I<this file> +O<an image>: \
             this file's name holds a double quote or a control character, \
             which POV-Ray's command line cannot take ({})",
            in_comment(&input)
        )?,
    }
    if model.reflection_depth() + 1 > POV_MAX_TRACE_LEVEL {
        writeln!(
            out,
            "// WARNING: POV-Ray caps max_trace_level at {POV_MAX_TRACE_LEVEL}; \
             depth {} cannot be reproduced.",
            model.reflection_depth()
        )?;
    }
    writeln!(out)?;
    // Without it POV-Ray 3.7 may apply 3.6 compatibility settings.
    writeln!(out, "#version 3.7;")?;
    writeln!(out)?;
    writeln!(out, "global_settings {{")?;
    writeln!(out, "  assumed_gamma 1.0")?;
    writeln!(out, "  ambient_light rgb 1")?;
    writeln!(
        out,
        "  max_trace_level {}",
        model.reflection_depth().saturating_add(1)
    )?;
    writeln!(out, "  adc_bailout 0")?;
    writeln!(out, "}}")?;
    writeln!(out, "background {{ rgb 0 }}")?;
    writeln!(out)?;

    // Camera: the screen z = 0 spans [-1, 1] on its shorter side.
    let s = 2.0 / f64::from(cam.width.min(cam.height));
    let w = f64::from(cam.width) * s;
    let h = f64::from(cam.height) * s;
    let e = cam.eye_distance;
    writeln!(out, "camera {{")?;
    writeln!(out, "  perspective")?;
    writeln!(out, "  location <0, 0, {}>", num(-e))?;
    writeln!(out, "  direction <0, 0, {}>", num(e))?;
    writeln!(out, "  right x*{}", num(w))?;
    writeln!(out, "  up y*{}", num(h))?;
    writeln!(out, "  {}", pov_matrix(&cam.transform.to_world()))?;
    writeln!(out, "}}")?;
    writeln!(out)?;

    for light in &scene.lights {
        writeln!(
            out,
            "light_source {{ {} rgb {} }}",
            vector(mirror_point(light.position)),
            vector(light.color)
        )?;
    }
    if !scene.lights.is_empty() {
        writeln!(out)?;
    }

    for object in &scene.objects {
        write_object(out, object, model.illumination)?;
    }
    Ok(())
}

fn write_object(out: &mut String, object: &Object, model: Illumination) -> std::fmt::Result {
    writeln!(out, "{}", object.shape.pov())?;
    writeln!(out, "  {}", pov_matrix(&object.transform.to_world()))?;
    writeln!(out, "  pigment {{ rgb 1 }}")?;
    let mat = object.material;
    let ambient = object.color * mat.ka;
    write!(out, "  finish {{ ambient rgb {}", vector(ambient))?;
    match model {
        Illumination::Ambient => write!(out, " diffuse 0")?,
        Illumination::Lambert => write!(out, " diffuse {} brilliance 1", num(mat.kd))?,
        Illumination::Phong | Illumination::Whitted => write!(
            out,
            " diffuse {} brilliance 1 phong {} phong_size {} specular 0",
            num(mat.kd),
            num(mat.ks),
            num(mat.m)
        )?,
    }
    if model == Illumination::Whitted {
        write!(out, " reflection {{ {} }}", num(mat.ks))?;
    }
    writeln!(out, " }}")?;
    writeln!(out, "  no_shadow")?;
    writeln!(out, "}}")?;
    Ok(())
}

/// A number in shortest round-trip form; `-0` is written as `0`.
fn num(x: f64) -> String {
    if x == 0.0 {
        "0".to_string()
    } else {
        format!("{x:?}")
    }
}

fn vector(v: DVec3) -> String {
    format!("<{}, {}, {}>", num(v.x), num(v.y), num(v.z))
}

/// The mirror F applied to a point: (x, y, z) → (x, −y, z).
pub fn mirror_point(p: DVec3) -> DVec3 {
    DVec3::new(p.x, -p.y, p.z)
}

/// F·M·F with F = diag(1, −1, 1): the same map seen in POV-Ray's frame.
pub fn mirror_matrix(m: &DAffine3) -> DAffine3 {
    let f = DAffine3::from_scale(DVec3::new(1.0, -1.0, 1.0));
    // Multiplying by ±1 is exact, so the product is the sign-flipped matrix.
    f * *m * f
}

/// The twelve numbers of POV-Ray's `matrix` for our column-vector matrix `m`
/// (already in POV-Ray's frame): each column of the 3×3 part, then the
/// translation.
pub fn pov_matrix_numbers(m: &DAffine3) -> [f64; 12] {
    let a = m.matrix3;
    let t = m.translation;
    [
        a.x_axis.x, a.x_axis.y, a.x_axis.z, a.y_axis.x, a.y_axis.y, a.y_axis.z, a.z_axis.x,
        a.z_axis.y, a.z_axis.z, t.x, t.y, t.z,
    ]
}

/// The `matrix <…>` statement for an object-to-world (or camera-to-world)
/// matrix of our frame.
fn pov_matrix(m: &DAffine3) -> String {
    let n = pov_matrix_numbers(&mirror_matrix(m));
    let mut s = String::from("matrix <");
    for (i, x) in n.iter().enumerate() {
        if i > 0 {
            s.push_str(if i % 3 == 0 { ",  " } else { ", " });
        }
        s.push_str(&num(*x));
    }
    s.push('>');
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Transform, TransformStep};
    use crate::scene::{Camera, Light, Material, Model, Shape};
    use glam::DMat3;

    /// Applies POV-Ray's row-vector matrix to a point, as POV-Ray does.
    fn pov_apply(n: &[f64; 12], p: DVec3) -> DVec3 {
        DVec3::new(
            p.x * n[0] + p.y * n[3] + p.z * n[6] + n[9],
            p.x * n[1] + p.y * n[4] + p.z * n[7] + n[10],
            p.x * n[2] + p.y * n[5] + p.z * n[8] + n[11],
        )
    }

    #[test]
    fn mirror_flips_exactly_the_y_terms() {
        let m = DAffine3 {
            matrix3: DMat3::from_cols_array(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]),
            translation: DVec3::new(10.0, 11.0, 12.0),
        };
        let f = mirror_matrix(&m);
        // Columns (x_axis, y_axis, z_axis) of F·M·F.
        assert_eq!(f.matrix3.x_axis, DVec3::new(1.0, -2.0, 3.0));
        assert_eq!(f.matrix3.y_axis, DVec3::new(-4.0, 5.0, -6.0));
        assert_eq!(f.matrix3.z_axis, DVec3::new(7.0, -8.0, 9.0));
        assert_eq!(f.translation, DVec3::new(10.0, -11.0, 12.0));
        assert_eq!(
            mirror_point(DVec3::new(1.0, 2.0, 3.0)),
            DVec3::new(1.0, -2.0, 3.0)
        );
    }

    #[test]
    fn pov_matrix_is_transposed_with_translation_last() {
        let m = DAffine3 {
            matrix3: DMat3::from_cols_array(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]),
            translation: DVec3::new(10.0, 11.0, 12.0),
        };
        let n = pov_matrix_numbers(&m);
        assert_eq!(
            n,
            [
                1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0
            ]
        );
        // POV-Ray's row-vector product gives what our column-vector product gives.
        let p = DVec3::new(0.5, -1.25, 2.0);
        assert_eq!(pov_apply(&n, p), m.transform_point3(p));
        assert_eq!(
            pov_matrix(&m),
            "matrix <1.0, -2.0, 3.0,  -4.0, 5.0, -6.0,  7.0, -8.0, 9.0,  10.0, -11.0, 12.0>"
        );
    }

    #[test]
    fn mirrored_matrix_commutes_with_mirrored_points() {
        let t = Transform::from_steps(vec![
            TransformStep::Scale(DVec3::new(2.0, 0.5, -3.0)),
            TransformStep::RotateX(0.3),
            TransformStep::RotateY(-1.1),
            TransformStep::RotateZ(2.0),
            TransformStep::Translate(DVec3::new(1.0, -2.0, 5.0)),
        ])
        .unwrap();
        let n = pov_matrix_numbers(&mirror_matrix(&t.to_world()));
        for p in [DVec3::ZERO, DVec3::X, DVec3::new(0.3, -0.7, 1.9)] {
            let ours = mirror_point(t.to_world().transform_point3(p));
            let pov = pov_apply(&n, mirror_point(p));
            assert!((ours - pov).length() < 1e-12, "{ours} vs {pov}");
        }
    }

    #[test]
    fn numbers_round_trip() {
        for x in [0.1, 1.0 / 3.0, 1e-7, 1e20, -2.5e-300, 100000.0] {
            assert_eq!(num(x).parse::<f64>().unwrap(), x);
        }
        assert_eq!(num(-0.0), "0");
    }

    fn scene(model: Illumination) -> Scene {
        Scene {
            objects: vec![
                Object {
                    shape: Shape::Sphere,
                    color: DVec3::new(1.0, 0.5, 0.0),
                    material: Material {
                        ka: 0.5,
                        kd: 0.25,
                        ks: 0.75,
                        m: 8.0,
                    },
                    transform: Transform::from_steps(vec![TransformStep::Translate(DVec3::new(
                        1.0, 2.0, 3.0,
                    ))])
                    .unwrap(),
                },
                Object {
                    shape: Shape::Plane,
                    color: DVec3::ONE,
                    material: Material::default(),
                    transform: Transform::default(),
                },
            ]
            .into_iter()
            .map(std::sync::Arc::new)
            .collect(),
            lights: vec![Light {
                position: DVec3::new(1.0, -4.0, -2.0),
                color: DVec3::new(2.0, 1.0, 0.5),
            }],
            camera: Camera {
                width: 320,
                height: 160,
                eye_distance: 4.0,
                transform: Transform::from_steps(vec![TransformStep::Translate(DVec3::new(
                    0.0, 0.0, -20.0,
                ))])
                .unwrap(),
            },
            model: Model {
                illumination: model,
                depth: 3,
            },
        }
    }

    #[test]
    fn whitted_scene_has_every_term() {
        let header = Header {
            scene: Path::new("scenes/a.xml"),
            written_to: Path::new("out/b.pov"),
        };
        let pov = export_named(&scene(Illumination::Whitted), Some(header));
        assert!(pov.contains("// Source: scenes/a.xml"), "{pov}");
        assert!(
            pov.contains("+W320 +H160 +Iout/b.pov +Oout/b-pov.png\n"),
            "{pov}"
        );
        assert!(pov.contains("\n#version 3.7;\n"), "{pov}");
        assert!(pov.contains("max_trace_level 4"), "{pov}");
        assert!(pov.contains("adc_bailout 0"));
        assert!(pov.contains("background { rgb 0 }"));
        assert!(pov.contains("location <0, 0, -4.0>"));
        assert!(pov.contains("direction <0, 0, 4.0>"));
        assert!(pov.contains("right x*4.0"), "{pov}");
        assert!(pov.contains("up y*2.0"), "{pov}");
        assert!(pov.contains("matrix <1.0, 0, 0,  0, 1.0, 0,  0, 0, 1.0,  0, 0, -20.0>"));
        assert!(pov.contains("light_source { <1.0, 4.0, -2.0> rgb <2.0, 1.0, 0.5> }"));
        assert!(pov.contains(
            "sphere { 0, 1\n  matrix <1.0, 0, 0,  0, 1.0, 0,  0, 0, 1.0,  1.0, -2.0, 3.0>"
        ));
        assert!(
            pov.contains(
                "finish { ambient rgb <0.5, 0.25, 0> diffuse 0.25 brilliance 1 \
             phong 0.75 phong_size 8.0 specular 0 reflection { 0.75 } }"
            ),
            "{pov}"
        );
        assert!(pov.contains("plane { z, 0"));
        assert_eq!(pov.matches("no_shadow").count(), 2);
        assert_eq!(pov.matches("pigment { rgb 1 }").count(), 2);
    }

    #[test]
    fn names_stay_in_their_comment_and_are_one_shell_word() {
        let header = Header {
            scene: Path::new("a\n#fopen F \"pwned.txt\" write\r.xml"),
            written_to: Path::new("it's \u{1b}[2J\n#debug.pov"),
        };
        let pov = export_named(&scene(Illumination::Phong), Some(header));
        let head: Vec<&str> = pov.lines().take_while(|l| !l.is_empty()).collect();
        assert!(head.iter().all(|l| l.starts_with("// ")), "{pov}");
        assert!(!pov.contains('\u{1b}') && !pov.contains('\r'), "{pov}");
        assert!(
            pov.contains("// Source: a?#fopen F \"pwned.txt\" write?.xml\n"),
            "{pov}"
        );
        assert!(
            pov.contains("+I<this file> +O<an image>: this file's name holds"),
            "{pov}"
        );
        assert!(pov.contains("(it's ?[2J?#debug.pov)\n"), "{pov}");
        let spaced = Header {
            scene: Path::new("a.xml"),
            written_to: Path::new("it's here.pov"),
        };
        let pov = export_named(&scene(Illumination::Phong), Some(spaced));
        assert!(
            pov.contains(
                "+H160 'Input_File_Name=\"it'\\''s here.pov\"' \
                 'Output_File_Name=\"it'\\''s here-pov.png\"'\n"
            ),
            "{pov}"
        );
    }

    #[test]
    fn models_drop_the_terms_they_do_not_use() {
        let amb = export(&scene(Illumination::Ambient));
        assert!(
            amb.contains("finish { ambient rgb <0.5, 0.25, 0> diffuse 0 }"),
            "{amb}"
        );
        assert!(amb.contains("max_trace_level 1"));
        let lam = export(&scene(Illumination::Lambert));
        assert!(lam.contains("diffuse 0.25 brilliance 1 }"), "{lam}");
        assert!(!lam.contains("phong"));
        let pho = export(&scene(Illumination::Phong));
        assert!(
            pho.contains("phong 0.75 phong_size 8.0 specular 0 }"),
            "{pho}"
        );
        assert!(!pho.contains("reflection {"));
        assert!(pho.contains("max_trace_level 1"));
    }
}
