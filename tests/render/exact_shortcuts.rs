//! The work the renderer skips must never show: the per-tile frustum culling
//! of primary rays, the black tiles, the BVH, the early end of whitted
//! chains and the options `auto` plans all give exactly the image of the
//! plain path (every pixel through `Prepared::pixel`, alone in its packet
//! of rays where a tile fills every lane, every ray against
//! every object, every chain to its full depth).

use rayoflight::render::{self, RenderOptions};
use rayoflight::scene::{self, Scene};
use std::path::Path;

fn load(relative: &str) -> Scene {
    scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)).unwrap()
}

/// Every pixel through the un-culled path, without BVH or early stop.
fn plain(scene: &Scene) -> image::RgbImage {
    let prepared = render::prepare(scene, &RenderOptions::reference());
    image::RgbImage::from_fn(prepared.width(), prepared.height(), |i, j| {
        image::Rgb(prepared.pixel(i, j))
    })
}

fn scenes() -> Vec<(String, Scene)> {
    let mut list = Vec::new();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .collect();
    names.sort();
    for path in names {
        list.push((path.display().to_string(), scene::load(&path).unwrap()));
    }
    // The bench scenes, shrunk to keep the test quick.
    for name in ["mirrors", "room", "spheres-2000", "example-2000"] {
        let mut s = load(&format!("scenes/bench/{name}.xml"));
        s.camera.width /= 8;
        s.camera.height /= 8;
        list.push((name.to_owned(), s));
    }
    list
}

#[test]
fn shortcuts_never_change_a_pixel() {
    for (name, scene) in scenes() {
        let reference = plain(&scene);
        let auto = render::auto(&scene).options;
        for (method, options) in [("default", RenderOptions::default()), ("auto", auto)] {
            let fast = render::render(&scene, &options).unwrap();
            let differing = fast
                .pixels()
                .zip(reference.pixels())
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differing, 0, "{name}, {method}: {differing} pixels differ");
        }
    }
}

#[test]
fn deep_mirror_chains_stop_early_with_the_same_image() {
    // Depth 10 000 between two facing mirrors of ks 0.5: the chain's rest
    // falls below half a level after a few dozen bounces.
    let text = r#"<scene>
  <plane><color red="0.8" green="0.9" blue="1"/><material ka="0.05" kd="0.2" ks="0.5" m="8"/><transformation><translate z="5"/></transformation></plane>
  <plane><color red="1" green="0.9" blue="0.8"/><material ka="0.05" kd="0.2" ks="0.5" m="8"/><transformation><translate z="-5"/></transformation></plane>
  <sphere><material ka="0.3" kd="0.5" ks="0.5" m="20"/><transformation><translate x="0.5" z="2"/></transformation></sphere>
  <light x="0" y="-3" z="0"/>
  <camera width="40" height="30" eyeDistance="1"/>
  <model type="whitted" depth="10000"/>
</scene>"#;
    let scene = scene::parse(text, Path::new("mirrors.xml")).unwrap();
    let start = std::time::Instant::now();
    let fast = render::render(&scene, &RenderOptions::default()).unwrap();
    let fast_time = start.elapsed();
    let start = std::time::Instant::now();
    let reference = plain(&scene);
    let plain_time = start.elapsed();
    assert_eq!(fast, reference);
    eprintln!("early stop {fast_time:?}, full chains {plain_time:?}");
}

#[test]
fn coincident_objects_resolve_to_the_first_listed_with_every_shortcut() {
    // Forty spheres in the same place, each its own colour, and thirty
    // more elsewhere: too many to cull one by one, and more than a tile's
    // candidate list holds, so primary rays go through the BVH. Ties go to
    // the object listed first, whichever path finds them.
    let mut objects = String::new();
    for k in 0..40 {
        let red = f64::from(k) / 39.0;
        objects.push_str(&format!(
            r#"<sphere><color red="{red}" green="0.5" blue="0.2"/><transformation><translate z="4"/></transformation></sphere>"#
        ));
    }
    for k in 0..30 {
        objects.push_str(&format!(
            r#"<sphere><transformation><scale factor="0.2"/><translate x="{}" y="-2" z="6"/></transformation></sphere>"#,
            f64::from(k) / 3.0 - 5.0
        ));
    }
    let text = format!(
        r#"<scene>{objects}<light x="0" y="-4" z="0"/><camera width="48" height="36" eyeDistance="2"/><model type="whitted" depth="2"/></scene>"#
    );
    let scene = scene::parse(&text, Path::new("coincident.xml")).unwrap();
    let reference = plain(&scene);
    for options in [RenderOptions::default(), render::auto(&scene).options] {
        let fast = render::render(&scene, &options).unwrap();
        assert!(fast == reference, "{options:?}");
    }
}
