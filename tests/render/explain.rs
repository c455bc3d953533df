//! `rayoflight explain`: for every golden scene and 200 pixels each, the
//! explained 8-bit value is the pixel of the CLI's render, and each
//! bounce's terms add up to its colour (the camera ray's to the pixel's
//! unclamped sum) to the last bit. Also: anti-aliasing, --set, a pixel
//! outside the image, the text form.

use crate::common;

use crate::common::{Rng, rayoflight, stderr, stdout};
use serde_json::Value;
use std::path::Path;

/// `explain --json` of pixel (x, y), parsed.
fn explain(dir: &Path, scene: &Path, x: u32, y: u32, extra: &[&str]) -> Value {
    let (x, y) = (x.to_string(), y.to_string());
    let mut args = vec!["explain", scene.to_str().unwrap(), &x, &y, "--json"];
    args.extend_from_slice(extra);
    let o = rayoflight(dir, &args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).expect("one JSON object")
}

fn render(dir: &Path, scene: &Path, extra: &[&str]) -> image::RgbImage {
    let out = dir.join("render.png");
    let mut args = vec![
        "--no-gui",
        scene.to_str().unwrap(),
        "-out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = rayoflight(dir, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    image::open(&out).unwrap().to_rgb8()
}

fn v3(v: &Value) -> [f64; 3] {
    let a = v.as_array().expect("three numbers");
    assert_eq!(a.len(), 3);
    [0, 1, 2].map(|i| a[i].as_f64().expect("a number"))
}

/// ((a + d) + s) + r per channel, in the renderer's order.
fn sum_of_terms(terms: &Value) -> [f64; 3] {
    let [a, d, s, r] = ["ambient", "diffuse", "specular", "reflection"].map(|k| v3(&terms[k]));
    [0, 1, 2].map(|c| ((a[c] + d[c]) + s[c]) + r[c])
}

/// The 8-bit rounding (docs/scene-format.md, Illumination): clamp to
/// [0, 1], floor(c·255 + 0.5).
fn to_8bit(c: f64) -> u8 {
    if c > 0.0 {
        (c.min(1.0) * 255.0 + 0.5).floor() as u8
    } else {
        0
    }
}

fn bits(v: [f64; 3]) -> [u64; 3] {
    v.map(f64::to_bits)
}

/// Checks one explained pixel against the render's pixel and itself.
fn check(e: &Value, pixel: [u8; 3], what: &str) {
    let rgb8: Vec<u64> = e["rgb8"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .collect();
    assert_eq!(
        rgb8,
        pixel.map(u64::from),
        "{what}: rgb8 is not the rendered pixel"
    );
    let hits = e["hits"].as_array().expect("hits");
    for (k, hit) in hits.iter().enumerate() {
        if hit["object"].is_null() {
            assert_eq!(k, hits.len() - 1, "{what}: only the last ray misses");
            assert!(hit["t"].is_null() && hit["point"].is_null());
            continue;
        }
        assert!(
            hit["object"].as_u64().unwrap() >= 1,
            "{what}: objects are 1-based"
        );
        assert!(hit["t"].as_f64().unwrap() > 0.0);
        let n = v3(&hit["normal"]);
        // Unit length (f32's precision for the f32 method).
        assert!((n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0).abs() < 1e-6);
        assert_eq!(
            bits(sum_of_terms(&hit["terms"])),
            bits(v3(&hit["color"])),
            "{what}: bounce {k}'s terms do not add up to its colour"
        );
    }
    // The camera ray's colour is its ray's sum: the pixel's with one ray,
    // the first sample's with more.
    let sum = match e.get("samples") {
        Some(samples) => &samples[0]["rgb"],
        None => &e["rgb"],
    };
    match hits.first() {
        Some(first) if !first["object"].is_null() => assert_eq!(
            bits(v3(&first["color"])),
            bits(v3(sum)),
            "{what}: the camera ray's terms do not add up to the pixel"
        ),
        _ => assert_eq!(v3(sum), [0.0; 3], "{what}: a miss is black"),
    }
}

#[test]
fn every_golden_scene_explains_200_pixels_as_rendered() {
    let scenes = common::golden_scenes();
    assert!(scenes.len() >= 19, "the golden scenes are there");
    let dir = tempfile::tempdir().unwrap();
    let mut hits_seen = 0;
    let mut chains_seen = 0;
    for scene in &scenes {
        let image = render(dir.path(), scene, &[]);
        let (w, h) = image.dimensions();
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ u64::from(w * 31 + h));
        let mut pixels: Vec<(u32, u32)> = vec![(0, 0), (w - 1, h - 1), (w / 2, h / 2)];
        while pixels.len() < 200 {
            pixels.push((rng.below(w as usize) as u32, rng.below(h as usize) as u32));
        }
        // Two at a time: the CI machine has two cores.
        std::thread::scope(|s| {
            let halves = pixels.split_at(pixels.len() / 2);
            let results: Vec<_> = [halves.0, halves.1]
                .into_iter()
                .map(|part| {
                    let (dir, image) = (dir.path(), &image);
                    s.spawn(move || {
                        let mut seen = (0, 0);
                        for &(x, y) in part {
                            let e = explain(dir, scene, x, y, &[]);
                            let what = format!("{} ({x}, {y})", scene.display());
                            check(&e, image.get_pixel(x, y).0, &what);
                            let hits = e["hits"].as_array().unwrap();
                            let hit = |h: &Value| !h["object"].is_null();
                            seen.0 += usize::from(hits.first().is_some_and(hit));
                            seen.1 += usize::from(hits.iter().filter(|h| hit(h)).count() > 1);
                        }
                        seen
                    })
                })
                .collect();
            for r in results {
                let (h, c) = r.join().unwrap();
                hits_seen += h;
                chains_seen += c;
            }
        });
    }
    // The sample is not all sky: most pixels hit, many reflect.
    assert!(hits_seen > scenes.len() * 60, "{hits_seen} hits");
    assert!(chains_seen > 500, "{chains_seen} reflection chains");
}

#[test]
fn supersampled_and_edited_pixels_explain_their_render() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden/mirror-spheres.xml");
    for extra in [
        &["--aa", "3"][..],
        &["--set", "object[1].material.ks=0.9"][..],
        &["--method", "f32"][..],
    ] {
        let image = render(dir.path(), &scene, extra);
        let mut rng = Rng(7);
        for _ in 0..20 {
            let (x, y) = (rng.below(200) as u32, rng.below(200) as u32);
            let e = explain(dir.path(), &scene, x, y, extra);
            check(
                &e,
                image.get_pixel(x, y).0,
                &format!("{extra:?} ({x}, {y})"),
            );
            if extra[0] == "--aa" {
                let samples = e["samples"].as_array().expect("each ray's tree");
                assert_eq!(samples.len(), 9);
                for s in samples {
                    for hit in s["hits"].as_array().unwrap() {
                        if !hit["object"].is_null() {
                            let (sum, color) = (sum_of_terms(&hit["terms"]), v3(&hit["color"]));
                            assert_eq!(bits(sum), bits(color));
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn the_early_stop_is_explained_with_its_bound() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden/mirror-corridor.xml");
    // Deep enough for auto's early stop (ks 0.75: past bounce 28).
    let deep = ["--set", "model.depth=60"];
    let image = render(dir.path(), &scene, &deep);
    let (w, h) = image.dimensions();
    let mut reasons = std::collections::BTreeSet::new();
    for y in (0..h).step_by(13) {
        for x in (0..w).step_by(17) {
            let e = explain(dir.path(), &scene, x, y, &deep);
            check(&e, image.get_pixel(x, y).0, &format!("({x}, {y})"));
            let reason = e["ended"]["reason"].as_str().unwrap().to_owned();
            if reason == "early stop" {
                // What the rest could add leaves every 8-bit value as is.
                let (bound, rgb) = (v3(&e["ended"]["bound"]), v3(&e["rgb"]));
                for c in 0..3 {
                    assert!(bound[c] > 0.0);
                    assert_eq!(to_8bit(rgb[c]), to_8bit(rgb[c] + bound[c]));
                }
            }
            reasons.insert(reason);
        }
    }
    assert!(reasons.contains("early stop"), "{reasons:?}");
}

#[test]
fn a_pixel_outside_the_image_is_a_usage_error_and_text_is_readable() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.xml"), common::TINY).unwrap();
    let o = rayoflight(dir.path(), &["explain", "tiny.xml", "16", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("pixel (16, 0) is outside the 16×12 image of tiny.xml"),
        "{}",
        stderr(&o)
    );
    let o = rayoflight(dir.path(), &["explain", "tiny.xml", "x", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("<X> expects a pixel number"),
        "{}",
        stderr(&o)
    );
    let o = rayoflight(dir.path(), &["explain", "tiny.xml", "8", "6"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for words in [
        "camera ray from (0, 0, -2)",
        "hits #1 sphere at t = ",
        "ambient     ka·C",
        "diffuse     Σ I·kd·cos θ",
        "specular    Σ I·ks·cos^m α",
        "reflection  ks·Ir",
        "light 1: cos θ = ",
        "8-bit value  (",
    ] {
        assert!(text.contains(words), "{words:?} in\n{text}");
    }
}

#[test]
fn the_trees_one_at_a_time_are_the_explanations_trees() {
    use rayoflight::render::prepare;
    use rayoflight::render::request::RenderRequest;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden/mirror-spheres.xml");
    let scene = rayoflight::scene::load(&path).unwrap();
    for aa in [1, 3] {
        let request = RenderRequest {
            aa: Some(aa),
            ..RenderRequest::default()
        };
        let prepared = prepare(&scene, &request.options(&scene));
        for (x, y) in [(0, 0), (100, 100), (150, 60)] {
            let whole = prepared.explain(x, y).unwrap();
            let mut each = Vec::new();
            let pixel = prepared
                .explain_each(x, y, |s| {
                    each.push(s);
                    std::ops::ControlFlow::Continue(())
                })
                .unwrap();
            assert_eq!(each, whole.samples);
            assert_eq!((pixel.rgb, pixel.rgb8), (whole.rgb, whole.rgb8));
            assert_eq!(pixel.samples, (aa * aa) as usize);
            assert_eq!(prepared.explained_pixel(x, y), Some(pixel));
            // A visitor that stops: no pixel, and no more trees.
            let mut seen = 0;
            let stopped = prepared.explain_each(x, y, |_| {
                seen += 1;
                std::ops::ControlFlow::Break(())
            });
            assert_eq!((stopped, seen), (None, 1));
        }
    }
    assert_eq!(prepared_outside(&scene), None);
}

fn prepared_outside(
    scene: &rayoflight::scene::Scene,
) -> Option<rayoflight::render::explain::PixelValue> {
    let prepared = rayoflight::render::prepare(scene, &Default::default());
    prepared.explained_pixel(scene.camera.width, 0)
}

/// A draft traces one ray per 2×2 block (its top-left pixel, even x and
/// y) and copies it to the other three: explaining any pixel of a draft
/// explains that ray, says so, and gives the draft render's colour.
#[test]
fn a_draft_pixel_explains_the_ray_the_draft_traced() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("tiny.xml");
    std::fs::write(&scene, common::TINY).unwrap();
    for extra in [
        &["--method", "draft"][..],
        &["--method", "draft", "--aa", "2"],
    ] {
        let image = render(dir.path(), &scene, extra);
        let (w, h) = image.dimensions();
        for y in 0..h {
            for x in 0..w {
                let e = explain(dir.path(), &scene, x, y, extra);
                check(
                    &e,
                    image.get_pixel(x, y).0,
                    &format!("{extra:?} ({x}, {y})"),
                );
                let traced: Vec<u64> = e["traced"]
                    .as_array()
                    .expect("the pixel traced")
                    .iter()
                    .map(|c| c.as_u64().unwrap())
                    .collect();
                assert_eq!(traced, [u64::from(x & !1), u64::from(y & !1)]);
            }
        }
    }
    let o = rayoflight(
        dir.path(),
        &["explain", "tiny.xml", "7", "5", "--method", "draft"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("draft: pixel (7, 5) shows the ray of (6, 4)"),
        "{}",
        stdout(&o)
    );
    // A traced pixel's explanation says nothing of the kind.
    let o = rayoflight(
        dir.path(),
        &["explain", "tiny.xml", "6", "4", "--method", "draft"],
    );
    assert!(!stdout(&o).contains("shows the ray of"), "{}", stdout(&o));
}
