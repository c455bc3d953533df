//! Render passes: on every golden scene, ambient + diffuse + specular +
//! reflection = final to the last bit of the renderer's f64 sum, and final
//! rounded to 8 bits is the image; the EXR files hold those values, each
//! rounded once to f32, and their final rounds to the PNG render; the
//! geometric passes agree with the pick (object), are unit (normal) and
//! positive (depth).

mod common;

use common::{rayoflight, stderr};
use rayoflight::render::{self, Cancel, Pass, PassImage, Progress, object_ids, prepare};
use rayoflight::request::RenderRequest;
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

#[test]
fn the_terms_add_up_to_final_bit_for_bit_and_final_is_the_image() {
    let request = RenderRequest::default();
    let mut reflecting = 0;
    for path in common::golden_scenes() {
        let scene = scene::load(&path).unwrap();
        let name = path.display();
        let [a, d, s, r] = TERMS.map(|p| pass(&scene, &request, p));
        let last = pass(&scene, &request, Pass::Final);
        for (i, &f) in last.values.iter().enumerate() {
            let sum = ((a.values[i] + d.values[i]) + s.values[i]) + r.values[i];
            assert_eq!(sum.to_bits(), f.to_bits(), "{name}: texel {i}: {sum} ≠ {f}");
        }
        reflecting += usize::from(r.values.iter().any(|&v| v > 0.0));
        let image = render::render(&scene, &request.options(&scene)).unwrap();
        assert!(last.to_rgb8() == image, "{name}: final is not the image");
    }
    assert!(reflecting >= 5, "{reflecting} golden scenes reflect");
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
fn exr_passes_hold_the_renderers_values_and_final_rounds_to_the_png() {
    let dir = tempfile::tempdir().unwrap();
    let request = RenderRequest::default();
    // Values whose nearest f32 lies across an 8-bit boundary.
    let mut adjusted = 0;
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
        for p in TERMS.into_iter().chain([Pass::Final]) {
            let file = dir.path().join(format!("{}.exr", p.name()));
            run(&["--pass", p.name(), "-out", file.to_str().unwrap()]);
            let exr = read_exr(&file);
            let ours = pass(&scene, &request, p);
            assert_eq!(exr.dimensions(), (ours.width, ours.height));
            for (i, (&f, &v)) in exr.as_raw().iter().zip(&ours.values).enumerate() {
                // The nearest f32, or its neighbour where the nearest
                // would round to another 8-bit level.
                let nearest = v as f32;
                if f != nearest {
                    assert_eq!(
                        render::to_8bit(f64::from(f)),
                        render::to_8bit(v),
                        "{name}: {i}"
                    );
                    assert_ne!(render::to_8bit(f64::from(nearest)), render::to_8bit(v));
                    assert!(f == nearest.next_up() || f == nearest.next_down());
                    adjusted += 1;
                }
                assert_eq!(f.to_bits(), render::f32_keeping_level(v).to_bits());
            }
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
    // coloured-lights has one (0.476470577951 just below 121.5/255).
    assert!((1..100).contains(&adjusted), "{adjusted}");
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
