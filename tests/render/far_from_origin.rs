//! Robustness far from the origin: a scene moved as a whole (objects,
//! lights and camera) by 1e5 must render like the scene at the origin —
//! no acne from self-intersection of reflected rays, no holes.

use glam::DVec3;
use rayoflight::math::{Transform, TransformStep};
use rayoflight::render::{self, RenderOptions};
use rayoflight::scene::{self, Scene};
use std::path::Path;

fn moved(transform: &Transform, offset: DVec3) -> Transform {
    let mut steps = transform.steps().to_vec();
    steps.push(TransformStep::Translate(offset));
    Transform::from_steps(steps).unwrap()
}

fn translate_scene(scene: &Scene, offset: DVec3) -> Scene {
    let mut s = scene.clone();
    for o in &mut s.objects {
        let o = std::sync::Arc::make_mut(o);
        o.transform = moved(&o.transform, offset);
    }
    for l in &mut s.lights {
        l.position += offset;
    }
    s.camera.transform = moved(&s.camera.transform, offset);
    s
}

#[test]
fn a_scene_moved_by_1e5_renders_like_at_the_origin() {
    let offset = DVec3::new(1e5, -1e5, 1e5);
    for name in [
        "example-whitted-d3",
        "floor-wall",
        "mirror-spheres",
        "mirror-corridor",
        "grazing-plane",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/golden")
            .join(format!("{name}.xml"));
        let here = scene::load(&path).unwrap();
        let there = translate_scene(&here, offset);
        let a = render::render(&here, &RenderOptions::default()).unwrap();
        let b = render::render(&there, &RenderOptions::default()).unwrap();
        let difference = rayoflight::render::measure::Difference::between(&a, &b);
        let (share, max) = (difference.within1, difference.max);
        assert!(
            share >= 0.9999 && max <= 8,
            "{name}: {:.4} % within one level, max difference {max}",
            share * 100.0
        );
    }
}
