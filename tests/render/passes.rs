//! Render passes: on every golden scene, ambient + diffuse + specular +
//! reflection = final to the last bit of the renderer's f64 sum, and final
//! rounded to 8 bits is the image; the EXR files hold those values, each
//! rounded once to f32, and their final rounds to the PNG render; the
//! geometric passes agree with the pick (object), are unit (normal) and
//! positive (depth).

use crate::common;

use crate::common::{rayoflight, stderr};
use rayoflight::render::request::RenderRequest;
use rayoflight::render::{self, Cancel, Pass, PassImage, Progress, object_ids, prepare};
use rayoflight::scene::{self, Scene};
use std::path::Path;

fn pass(scene: &Scene, request: &RenderRequest, pass: Pass) -> PassImage {
    let options = request.options(scene);
    let (image, _) = render::render_pass(
        scene,
        &options,
        pass,
        &Cancel::never(),
        &Progress::default(),
    )
    .unwrap()
    .unwrap();
    assert_eq!(image.pass, pass);
    image
}

const TERMS: [Pass; 4] = [
    Pass::Ambient,
    Pass::Diffuse,
    Pass::Specular,
    Pass::Reflection,
];

/// ((a + d) + s) + r in f32, the renderer's order.
fn add_f32(a: f32, d: f32, s: f32, r: f32) -> f32 {
    ((a + d) + s) + r
}

#[test]
fn the_terms_add_up_to_final_bit_for_bit_and_final_is_the_image() {
    let request = RenderRequest::default();
    let (mut reflecting, mut moved) = (0, 0);
    for path in common::golden_scenes() {
        let scene = scene::load(&path).unwrap();
        let name = path.display();
        let [a, d, s, r] = TERMS.map(|p| pass(&scene, &request, p));
        let last = pass(&scene, &request, Pass::Final);
        for (i, &f) in last.values.iter().enumerate() {
            let [a, d, s, r] = [&a, &d, &s, &r].map(|p| p.values[i] as f32);
            for v in [a, d, s, r] {
                assert!(v.is_finite());
            }
            assert_eq!(f as f32 as f64, f, "{name}: texel {i} is an f32");
            let sum = add_f32(a, d, s, r);
            assert_eq!(
                sum.to_bits(),
                (f as f32).to_bits(),
                "{name}: texel {i}: {sum} ≠ {f}"
            );
        }
        reflecting += usize::from(r.values.iter().any(|&v| v > 0.0));
        let image = render::render(&scene, &request.options(&scene)).unwrap();
        assert!(last.to_rgb8() == image, "{name}: final is not the image");
        // The terms are the renderer's f64 terms (explain's, which add up
        // to the pixel in f64) to the nearest f32, or an ulp or two off
        // where that keeps final's 8-bit value.
        let prepared = prepare(&scene, &request.options(&scene));
        let mut rng = common::Rng(17);
        for _ in 0..300 {
            let (x, y) = (
                rng.below(a.width as usize) as u32,
                rng.below(a.height as usize) as u32,
            );
            let e = prepared.explain(x, y).unwrap();
            let (terms, reflection) = match e.samples[0].bounces.first() {
                Some(b) => (b.terms, b.reflection),
                None => continue,
            };
            let exact = [terms.ambient, terms.diffuse, terms.specular, reflection];
            for (p, t) in [&a, &d, &s, &r].into_iter().zip(exact) {
                let v = p.at(x, y).unwrap();
                for c in 0..3 {
                    let (v, t) = (v[c] as f32, t[c] as f32);
                    if v != t {
                        moved += 1;
                        let steps = (v.to_bits() as i64 - t.to_bits() as i64).abs();
                        assert!(steps <= 2, "{name} ({x}, {y}): {v} for {t}");
                    }
                }
            }
        }
    }
    assert!(reflecting >= 5, "{reflecting} golden scenes reflect");
    // Moving a term is rare: a value a hair from a rounding boundary.
    assert!(moved < 20, "{moved} terms moved");
}

#[test]
fn supersampled_final_is_the_supersampled_image() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden/mirror-spheres.xml");
    let scene = scene::load(&path).unwrap();
    let request = RenderRequest {
        aa: Some(3),
        ..RenderRequest::default()
    };
    let image = render::render(&scene, &request.options(&scene)).unwrap();
    assert!(pass(&scene, &request, Pass::Final).to_rgb8() == image);
    // The term passes are means of their samples: close to final's
    // unclamped mean, not bit for bit (clamping comes first in final).
    let terms = TERMS.map(|p| pass(&scene, &request, p));
    assert!(terms[0].values.iter().any(|&v| v > 0.0));
}

#[test]
fn geometric_passes_hold_the_hit() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden/example-phong.xml");
    let scene = scene::load(&path).unwrap();
    let request = RenderRequest::default();
    let object = pass(&scene, &request, Pass::Object);
    let prepared = prepare(&scene, &request.options(&scene));
    let ids = object_ids(&prepared, &scene.camera, 1);
    let normal = pass(&scene, &request, Pass::Normal);
    let depth = pass(&scene, &request, Pass::Depth);
    let (mut hits, mut misses) = (0, 0);
    for y in 0..object.height {
        for x in 0..object.width {
            let id = object.at(x, y).unwrap();
            let expected = ids.at(x, y).map_or(0.0, |o| f64::from(o) + 1.0);
            assert_eq!(id, glam::DVec3::splat(expected), "({x}, {y})");
            let (n, t) = (normal.at(x, y).unwrap(), depth.at(x, y).unwrap().x);
            if expected > 0.0 {
                hits += 1;
                assert!((n.length() - 1.0).abs() < 1e-12 && t > 0.0 && t.is_finite());
            } else {
                misses += 1;
                assert!(n == glam::DVec3::ZERO && t == f64::INFINITY);
            }
        }
    }
    assert!(hits > 1000 && misses > 1000, "{hits} hits, {misses} misses");
    // Shown: nearest light, farthest dark, misses black; objects in
    // colours of their own.
    let (near, far) = depth.depth_range().unwrap();
    assert!(near < far);
    let shown = depth.to_rgb8();
    let lightest = shown.pixels().map(|p| p.0[0]).max().unwrap();
    assert_eq!(lightest, 255);
    let colours: std::collections::BTreeSet<[u8; 3]> =
        object.to_rgb8().pixels().map(|p| p.0).collect();
    assert_eq!(colours.len(), scene.objects.len() + 1);
}

fn read_exr(path: &Path) -> image::Rgb32FImage {
    image::open(path)
        .expect("an EXR the image crate reads")
        .to_rgb32f()
}

#[test]
fn exr_passes_add_up_in_f32_and_final_rounds_to_the_png() {
    let dir = tempfile::tempdir().unwrap();
    let request = RenderRequest::default();
    for name in ["example-whitted-d3", "coloured-lights", "mirror-corridor"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/golden")
            .join(format!("{name}.xml"));
        let scene = scene::load(&path).unwrap();
        let run = |args: &[&str]| {
            let mut all = vec!["--no-gui", path.to_str().unwrap()];
            all.extend_from_slice(args);
            let o = rayoflight(dir.path(), &all);
            assert!(o.status.success(), "{all:?}: {}", stderr(&o));
        };
        let mut layers = Vec::new();
        for p in TERMS.into_iter().chain([Pass::Final]) {
            let file = dir.path().join(format!("{}.exr", p.name()));
            run(&["--pass", p.name(), "-out", file.to_str().unwrap()]);
            let exr = read_exr(&file);
            let ours = pass(&scene, &request, p);
            assert_eq!(exr.dimensions(), (ours.width, ours.height));
            // The file holds the pass's values, each an f32 exactly.
            let values: Vec<f32> = ours.values.iter().map(|&v| v as f32).collect();
            assert!(exr.as_raw() == &values, "{name} {}", p.name());
            layers.push(exr);
        }
        // In the files, the terms add up to final bit for bit, in f32.
        let [a, d, s, r, f] = [0, 1, 2, 3, 4].map(|k| layers[k].as_raw());
        for i in 0..f.len() {
            let sum = add_f32(a[i], d[i], s[i], r[i]);
            assert_eq!(sum.to_bits(), f[i].to_bits(), "{name}: {i}");
        }
        // The plain render to .exr is the final pass; its values round to
        // the PNG render.
        run(&["-out", "plain.exr"]);
        run(&["-out", "plain.png"]);
        let (plain, png) = (
            read_exr(&dir.path().join("plain.exr")),
            image::open(dir.path().join("plain.png")).unwrap().to_rgb8(),
        );
        assert!(plain == read_exr(&dir.path().join("final.exr")));
        let rounded: Vec<u8> = plain
            .as_raw()
            .iter()
            .map(|&c| render::to_8bit(f64::from(c)))
            .collect();
        assert!(
            rounded == png.into_raw(),
            "{name}: final.exr does not round to the PNG"
        );
    }
}

#[test]
fn a_pass_png_is_its_8_bit_picture_and_bad_names_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.xml"), common::TINY).unwrap();
    let o = rayoflight(
        dir.path(),
        &["tiny.xml", "--pass", "depth", "-out", "d.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).starts_with("depth: t from "), "{}", stderr(&o));
    let scene = scene::load(&dir.path().join("tiny.xml")).unwrap();
    let depth = pass(&scene, &RenderRequest::default(), Pass::Depth);
    let png = image::open(dir.path().join("d.png")).unwrap().to_rgb8();
    assert!(png == depth.to_rgb8());
    let o = rayoflight(
        dir.path(),
        &["tiny.xml", "--pass", "glossy", "-out", "g.png"],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains(
            "--pass expects one of final, ambient, diffuse, specular, reflection, normal, depth, object"
        ),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_pass_kept_in_its_files_form_is_the_whole_pass_converted() {
    // What the CLI renders for a file (3, 8 or 12 bytes a pixel, made
    // tile by tile) is what the f64 pass converts to, to the last bit.
    use rayoflight::render::{PassForm, PassPixels};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden/mirror-spheres.xml");
    let scene = scene::load(&path).unwrap();
    for aa in [1, 2] {
        let request = RenderRequest {
            aa: Some(aa),
            ..RenderRequest::default()
        };
        let options = request.options(&scene);
        for p in Pass::ALL {
            let whole = pass(&scene, &request, p);
            for form in [PassForm::Picture, PassForm::Floats] {
                let (kept, _) = render::render_pass_as(
                    &scene,
                    &options,
                    p,
                    form,
                    &Cancel::never(),
                    &Progress::default(),
                )
                .unwrap()
                .unwrap();
                let what = format!("{} {form:?} aa {aa}", p.name());
                assert_eq!(kept.depth_range, whole.depth_range(), "{what}");
                match kept.pixels {
                    PassPixels::Picture(image) => assert!(image == whole.to_rgb8(), "{what}"),
                    PassPixels::Floats(image) => assert!(image == whole.to_rgb32f(), "{what}"),
                }
            }
        }
    }
}
