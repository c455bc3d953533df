//! Known-answer tests: one-pixel images whose colour was worked out by hand
//! from the scene format's formulas (docs/scene-format.md, Illumination),
//! so the renderer is checked against arithmetic, not against itself.
//!
//! The setup: a 1×1 image (s = 2, the pixel centre is the screen origin), the
//! eye at (0, 0, −4), so the primary ray runs along +z through the origin.
//! A unit sphere centred at (0, 0, 5) is hit at M = (0, 0, 4) with
//! N = V = (0, 0, −1). The light at S = (0, −3, 1) gives
//! L = (0, −1, −1)/√2, cos θ = 1/√2, R = 2 cos θ N − L = (0, 1, −1)/√2 and
//! cos α = R · V = 1/√2.

use glam::DVec3;
use rayoflight::geometry::Ray;
use rayoflight::math::{Transform, TransformStep};
use rayoflight::render::{self, RenderOptions};
use rayoflight::scene::{Camera, Illumination, Light, Material, Model, Object, Scene, Shape};
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2};

fn transform(steps: Vec<TransformStep>) -> Transform {
    Transform::from_steps(steps).unwrap()
}

fn object(shape: Shape, color: DVec3, material: Material, steps: Vec<TransformStep>) -> Object {
    Object {
        shape,
        color,
        material,
        transform: transform(steps),
    }
}

/// C = (1, 0.5, 0.25), ka = 0.2, kd = 0.3, ks = 0.4, m = 3.
fn front_sphere() -> Object {
    object(
        Shape::Sphere,
        DVec3::new(1.0, 0.5, 0.25),
        Material {
            ka: 0.2,
            kd: 0.3,
            ks: 0.4,
            m: 3.0,
        },
        vec![TransformStep::Translate(DVec3::new(0.0, 0.0, 5.0))],
    )
}

/// A plane z = −10 behind the eye, C = (0.2, 0.4, 0.6), ka 0.1, kd 0.3,
/// ks 0.5, m 2. Invisible to primary rays, seen in the sphere's mirror.
fn back_plane() -> Object {
    object(
        Shape::Plane,
        DVec3::new(0.2, 0.4, 0.6),
        Material {
            ka: 0.1,
            kd: 0.3,
            ks: 0.5,
            m: 2.0,
        },
        vec![TransformStep::Translate(DVec3::new(0.0, 0.0, -10.0))],
    )
}

fn scene(objects: Vec<Object>, illumination: Illumination, depth: u32) -> Scene {
    Scene {
        objects: objects.into_iter().map(std::sync::Arc::new).collect(),
        lights: vec![Light {
            position: DVec3::new(0.0, -3.0, 1.0),
            color: DVec3::ONE,
        }],
        camera: Camera {
            width: 1,
            height: 1,
            eye_distance: 4.0,
            transform: Transform::default(),
        },
        model: Model {
            illumination,
            depth,
        },
    }
}

fn pixel(scene: &Scene) -> [u8; 3] {
    let image = render::render(scene, &RenderOptions::default()).unwrap();
    image.get_pixel(0, 0).0
}

#[test]
fn ambient_is_ka_c() {
    // I = ka C = (0.2, 0.1, 0.05) → floor(255 I + 0.5) = (51, 26, 13).
    let s = scene(vec![front_sphere()], Illumination::Ambient, 1);
    assert_eq!(pixel(&s), [51, 26, 13]);
}

#[test]
fn lambert_adds_kd_cos_theta_without_the_object_colour() {
    // I = ka C + kd/√2 = (0.41213, 0.31213, 0.26213) → (105, 80, 67).
    let expected = [0.2, 0.1, 0.05].map(|a: f64| a + 0.3 * FRAC_1_SQRT_2);
    assert_eq!(
        expected.map(|c| (c * 255.0 + 0.5).floor() as u8),
        [105, 80, 67]
    );
    let s = scene(vec![front_sphere()], Illumination::Lambert, 1);
    assert_eq!(pixel(&s), [105, 80, 67]);
}

#[test]
fn phong_adds_ks_cos_alpha_to_the_m() {
    // I = ka C + kd/√2 + ks (1/√2)³ = (0.55355, 0.45355, 0.40355) → (141, 116, 103).
    let s = scene(vec![front_sphere()], Illumination::Phong, 1);
    assert_eq!(pixel(&s), [141, 116, 103]);
}

#[test]
fn whitted_depth_0_is_phong() {
    let s = scene(vec![front_sphere(), back_plane()], Illumination::Whitted, 0);
    assert_eq!(pixel(&s), [141, 116, 103]);
}

#[test]
fn whitted_follows_depth_reflections() {
    // The mirror ray leaves (0,0,4) along −z and meets the plane at
    // (0,0,−10) with N = V = (0,0,1): L = (0,−3,11)/√130, cos θ = 11/√130
    // = 0.96476, R = 2 cos θ N − L has R_z = cos θ, so cos α = R · V = cos θ;
    // plane colour P = 0.1 C_p + 0.3 cos θ + 0.5 cos²α = (0.77481, 0.79481, 0.81481).
    // Its mirror ray goes back along +z to the sphere (colour S, the phong
    // value above), and so on:
    //   depth 1: S + 0.4 P                      = (0.86348, 0.77148, 0.72948)
    //   depth 2: S + 0.4 (P + 0.5 S)            = (0.97419, 0.86219, 0.81019)
    //   depth 3: S + 0.4 (P + 0.5 (S + 0.4 P))  = (1.03617, 0.92577, 0.87537)
    let cases = [
        (1, [220, 197, 186]),
        (2, [248, 220, 207]),
        (3, [255, 236, 223]),
    ];
    for (depth, expected) in cases {
        let s = scene(
            vec![front_sphere(), back_plane()],
            Illumination::Whitted,
            depth,
        );
        assert_eq!(pixel(&s), expected, "depth {depth}");
    }
    // Phong ignores the depth.
    let s = scene(vec![front_sphere(), back_plane()], Illumination::Phong, 3);
    assert_eq!(pixel(&s), [141, 116, 103]);
}

#[test]
fn a_miss_is_black() {
    let s = scene(vec![back_plane()], Illumination::Whitted, 2);
    assert_eq!(pixel(&s), [0, 0, 0]);
}

#[test]
fn transform_steps_apply_in_document_order() {
    // translate x=3 then rotate-y by −π/2 moves the centre to (0, 0, 3),
    // on the camera axis: hit at z = 2, t = 4 + 2 = 6.
    // rotate-y first leaves the origin in place, then translate x=3: off axis.
    let on_axis = vec![
        TransformStep::Translate(DVec3::new(3.0, 0.0, 0.0)),
        TransformStep::RotateY(-FRAC_PI_2),
    ];
    let off_axis = vec![
        TransformStep::RotateY(-FRAC_PI_2),
        TransformStep::Translate(DVec3::new(3.0, 0.0, 0.0)),
    ];
    let white = Material::default();
    let hit = |steps| {
        let s = scene(
            vec![object(Shape::Sphere, DVec3::ONE, white, steps)],
            Illumination::Ambient,
            1,
        );
        let prepared = render::prepare(&s, &RenderOptions::default());
        prepared.nearest_hit(&prepared.camera().ray(0.5, 0.5))
    };
    let t = hit(on_axis).expect("on-axis sphere is hit").t;
    assert!((t - 6.0).abs() < 1e-12, "t = {t}");
    assert_eq!(hit(off_axis), None);
}

#[test]
fn nearest_hit_compares_world_distances() {
    // A sphere scaled by 10 at z = 30 (front face z = 20) and a unit sphere
    // at z = 25 (front face z = 24): the big one is nearer in the world,
    // though its object-space parameter would be smaller for the other.
    let big = object(
        Shape::Sphere,
        DVec3::new(1.0, 0.0, 0.0),
        Material::default(),
        vec![
            TransformStep::UniformScale(10.0),
            TransformStep::Translate(DVec3::new(0.0, 0.0, 30.0)),
        ],
    );
    let small = object(
        Shape::Sphere,
        DVec3::new(0.0, 1.0, 0.0),
        Material::default(),
        vec![TransformStep::Translate(DVec3::new(0.0, 0.0, 25.0))],
    );
    let s = scene(vec![small, big], Illumination::Ambient, 1);
    let prepared = render::prepare(&s, &RenderOptions::default());
    let hit = prepared
        .nearest_hit(&prepared.camera().ray(0.5, 0.5))
        .unwrap();
    assert_eq!(hit.object, 1);
    assert!((hit.t - 24.0).abs() < 1e-12);
}

#[test]
fn normals_under_non_uniform_scale_use_the_inverse_transpose() {
    // An ellipsoid x²/4 + y² + z² = 1 turned by 0.5 rad about y and moved to
    // z = 5, lit by a light straight along the ray's way back. With lambert,
    // ka = 0, kd = 1 and a white light, the pixel is cos θ = N · L, where N
    // is the world gradient of the ellipsoid: worked out here in world space
    // with no help from the renderer's matrices.
    let a = 0.5_f64;
    let steps = vec![
        TransformStep::Scale(DVec3::new(2.0, 1.0, 1.0)),
        TransformStep::RotateY(a),
        TransformStep::Translate(DVec3::new(0.0, 0.0, 5.0)),
    ];
    let material = Material {
        ka: 0.0,
        kd: 1.0,
        ks: 0.0,
        m: 1.0,
    };
    let mut s = scene(
        vec![object(Shape::Sphere, DVec3::ONE, material, steps)],
        Illumination::Lambert,
        1,
    );
    s.lights[0].position = DVec3::new(0.0, 0.0, -100.0);

    // The axis point (0, 0, 5 + w) in the ellipsoid's frame (translation and
    // rotation undone): rotate-y maps (z, x) → (z cos a − x sin a,
    // z sin a + x cos a), so its inverse takes (x, z) = (0, w) to
    // x' = −w sin a, z' = w cos a. On the surface (x'/2)² + z'² = 1, and the
    // near side has w < 0.
    let (sin, cos) = a.sin_cos();
    let w = -1.0 / (sin * sin / 4.0 + cos * cos).sqrt();
    let (xl, zl) = (-w * sin, w * cos);
    // Gradient in the local frame (x'/4, 0, z'), rotated back to the world.
    let (gx, gz) = (xl / 4.0, zl);
    let n = DVec3::new(gx * cos + gz * sin, 0.0, -gx * sin + gz * cos).normalize();
    let m = DVec3::new(0.0, 0.0, 5.0 + w);
    let l = (s.lights[0].position - m).normalize();
    let cos_theta = n.dot(l).abs();
    let expected = (cos_theta * 255.0 + 0.5).floor() as u8;
    assert!(
        expected < 250,
        "the test needs a tilted normal, got {cos_theta}"
    );

    let prepared = render::prepare(&s, &RenderOptions::default());
    let hit = prepared
        .nearest_hit(&Ray::new(DVec3::new(0.0, 0.0, -4.0), DVec3::Z))
        .unwrap();
    assert!((hit.t - (9.0 + w)).abs() < 1e-12, "t = {}", hit.t);
    assert_eq!(pixel(&s), [expected; 3]);
}
