//! `auto`: the options one scene needs, and why.
//!
//! [`auto`] looks at a scene and returns a [`Plan`]: [`RenderOptions`] whose
//! image is the reference image byte for byte (every choice is exact), with
//! a [`Decision`] for each choice so that the study, the CLI and the app can
//! say what was skipped and why.
//!
//! - **Precision.** f32 would be allowed only where a bound proves every
//!   pixel equal. Reflected rays start ε = 1e-9 + 1e-12·|M| off the surface,
//!   far below f32's spacing at any useful scale, and without reflections a
//!   silhouette or an 8-bit rounding step can still fall between the f32 and
//!   the f64 hit point. No such bound exists for this renderer's scenes, so
//!   the plan stays in f64 and says by how much f32 falls short.
//! - **Acceleration.** The BVH from [`BVH_THRESHOLD`] bounded objects up
//!   (below that a scan is cheaper), per-tile culling of primary rays, black
//!   tiles without a ray.
//! - **Early stop.** Only where a whitted chain can end early: some surface
//!   reflects, every ks is below 1 (otherwise nothing bounds what the rest
//!   of a chain adds), and the depth goes past the bounce where the rest of
//!   a chain through the most reflective surfaces falls below half a
//!   level (before it, the test costs and ends nothing: the study measured
//!   the mirror corridor, ks 0.75 at depth 12, 6 % slower with it).
//! - **Zero terms.** The ambient model evaluates no light, lambert no
//!   specular term, and no reflected ray leaves a surface with ks = 0; the
//!   tracer does this for every method, the plan reports it.

use super::RenderOptions;
use super::facts::{self, ObjectFacts};
use super::prepared::{BVH_THRESHOLD, CULL_LIMIT, TILE_CANDIDATES};
use crate::scene::{Illumination, Scene};

/// One choice of the plan.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Decision {
    /// What is decided: "precision", "acceleration", "early stop", "terms".
    pub topic: &'static str,
    /// The choice, in a few words.
    pub choice: String,
    /// Why, with the scene's numbers.
    pub reason: String,
}

/// The options a scene needs and the decisions behind them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Plan {
    pub options: RenderOptions,
    pub decisions: Vec<Decision>,
}

/// Plans the cheapest exact render of `scene`.
pub fn auto(scene: &Scene) -> Plan {
    let mut decisions = Vec::new();
    let mut decide = |topic, choice: String, reason: String| {
        decisions.push(Decision {
            topic,
            choice,
            reason,
        })
    };

    // (What every object says, walked once per list of objects.)
    let facts = facts::of(&scene.objects);
    let depth = scene.model.reflection_depth();
    let max_ks = facts.max_ks;
    let reflects = depth > 0 && max_ks > 0.0;

    // Precision: f64, with the numbers that rule f32 out.
    let extent = extent(scene, &facts);
    let spacing = f32_spacing(extent);
    let reason = match spacing {
        None => format!(
            "the scene reaches {extent:.3e}, beyond f32's range (3.4e38): f32 cannot hold it"
        ),
        Some(spacing) if reflects => {
            let epsilon = 1e-9 + 1e-12 * extent;
            format!(
                "reflected rays start ε = {epsilon:.1e} off the surface; f32's spacing at the \
                 scene's extent {} is {spacing:.1e}, {:.0}× larger, so f32 cannot \
                 place them (acne)",
                number(extent),
                spacing / epsilon
            )
        }
        Some(spacing) => format!(
            "no bound proves every pixel equal: f32 moves hit points by up to {spacing:.1e} \
             (scene extent {}), and a silhouette or an 8-bit rounding step can fall \
             in between",
            number(extent)
        ),
    };
    decide("precision", "f64".into(), reason);

    // Acceleration: what prepare builds for this object count.
    let bounded = facts.bounded;
    let planes = scene.objects.len() - bounded;
    let (choice, reason) = if bounded == 0 && planes == 0 {
        (
            "nothing to trace".to_owned(),
            "no objects: every tile is black without a ray".to_owned(),
        )
    } else if bounded == 0 {
        (
            "planes only".to_owned(),
            format!("{planes} plane(s), tested one by one by every ray"),
        )
    } else if bounded < BVH_THRESHOLD {
        (
            "no BVH, tile culling".to_owned(),
            format!(
                "{bounded} sphere(s): a scan of fewer than {BVH_THRESHOLD} is cheaper than a BVH; \
                 each tile's primary rays test only the spheres in its frustum{}",
                if planes == 0 {
                    ", and a tile with none is black without a ray"
                } else {
                    ""
                }
            ),
        )
    } else if bounded <= CULL_LIMIT {
        (
            "BVH, tile culling".to_owned(),
            format!(
                "{bounded} spheres: a BVH for reflected rays; each tile's primary rays test only \
                 the spheres in its frustum"
            ),
        )
    } else {
        (
            "BVH, tile candidates".to_owned(),
            format!(
                "{bounded} spheres: a BVH; a tile whose frustum reaches at most \
                 {TILE_CANDIDATES} of them tests just those"
            ),
        )
    };
    decide("acceleration", choice, reason);

    // Early stop: only where it can fire.
    let (early_stop, reason) = if scene.model.illumination != Illumination::Whitted {
        (false, "no reflected rays in this model".to_owned())
    } else if depth == 0 {
        (false, "whitted with depth 0: no reflected rays".to_owned())
    } else if max_ks == 0.0 {
        (false, "no material reflects (every ks = 0)".to_owned())
    } else if max_ks >= 1.0 {
        (
            false,
            format!(
                "a material has ks = {max_ks}: nothing bounds what the rest of a chain adds, \
                 so the test could never end one"
            ),
        )
    } else {
        // A chain can end once the most the rest can add (weight ≤ ks^k,
        // then Σ ks^j ≤ 1/(1 − ks), each hit ≤ the brightest local colour)
        // is below half a level; chains through the most reflective
        // surfaces get there at bounce k. Before that the test only costs.
        let brightest = facts.max_local_color(scene).max_element();
        let k = first_stoppable_bounce(max_ks, brightest);
        if k < depth {
            (
                true,
                format!(
                    "largest ks = {max_ks}: from bounce {k} on, the rest of a chain adds \
                     less than half a level (ks^k/(1 − ks) × {} × 255 < 0.5), and the depth is \
                     {depth}: chains end there, or earlier",
                    number(brightest)
                ),
            )
        } else {
            (
                false,
                format!(
                    "largest ks = {max_ks}: the rest of a chain can add half a level or more \
                     until bounce {k}, and the depth is {depth}: the test would only cost"
                ),
            )
        }
    };
    decide(
        "early stop",
        if early_stop { "on" } else { "off" }.into(),
        reason,
    );

    let reason = match scene.model.illumination {
        Illumination::Ambient => "ambient: no light is evaluated (ka C only)".to_owned(),
        Illumination::Lambert => "lambert: no specular term, no reflected rays".to_owned(),
        Illumination::Phong => "phong: no reflected rays".to_owned(),
        Illumination::Whitted => {
            let mirrors = facts.mirrors;
            format!(
                "whitted: reflected rays leave the {mirrors} of {} objects with ks > 0, none the others",
                scene.objects.len()
            )
        }
    };
    decide("terms", "skip what is zero".into(), reason);

    Plan {
        options: RenderOptions {
            early_stop,
            accelerate: true,
            ..RenderOptions::default()
        },
        decisions,
    }
}

/// The largest coordinate magnitude in the scene: the camera's eye, the
/// lights, the spheres' bounding boxes and the planes' anchor points.
fn extent(scene: &Scene, facts: &ObjectFacts) -> f64 {
    let camera = &scene.camera;
    let eye = camera
        .transform
        .to_world()
        .transform_point3(glam::DVec3::new(0.0, 0.0, -camera.eye_distance))
        .abs()
        .max_element();
    let lights = scene
        .lights
        .iter()
        .map(|l| l.position.abs().max_element())
        .fold(0.0, f64::max);
    let objects = facts.reach;
    eye.max(lights).max(objects)
}

/// The first bounce k ≥ 1 at which ks^k/(1 − ks) × brightest × 255 is
/// at most half a level (0 < ks < 1), saturating at `u32::MAX`.
fn first_stoppable_bounce(ks: f64, brightest: f64) -> u32 {
    let target = 0.5 * (1.0 - ks) / (255.0 * brightest);
    if target >= ks || !target.is_finite() {
        return 1;
    }
    let k = (target.ln() / ks.ln()).ceil();
    if k >= f64::from(u32::MAX) {
        u32::MAX
    } else {
        (k as u32).max(1)
    }
}

/// A magnitude as people write it: 20, 0.5, 1.0e7.
fn number(x: f64) -> String {
    if (1e-3..1e5).contains(&x) {
        format!("{}", (x * 1e3).round() / 1e3)
    } else {
        format!("{x:.1e}")
    }
}

/// The distance between consecutive f32 values at `x` (at least the
/// spacing at 1), or `None` beyond f32's range.
fn f32_spacing(x: f64) -> Option<f64> {
    let x = x.max(1.0);
    if x >= f64::from(f32::MAX) {
        return None;
    }
    let single = x as f32;
    Some(f64::from(f32::from_bits(single.to_bits() + 1) - single))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene;
    use std::path::Path;

    fn plan(text: &str) -> Plan {
        auto(&scene::parse(text, Path::new("t.xml")).unwrap())
    }

    fn choice<'a>(plan: &'a Plan, topic: &str) -> &'a str {
        &plan
            .decisions
            .iter()
            .find(|d| d.topic == topic)
            .unwrap()
            .choice
    }

    const SPHERE: &str = r#"<sphere><material ka="0.2" kd="0.5" ks="KS" m="10"/></sphere>"#;

    fn scene_with(model: &str, ks: &str, spheres: usize) -> String {
        let objects = SPHERE.replace("KS", ks).repeat(spheres);
        format!(
            r#"<scene>{objects}<light x="1" y="-4" z="-2"/><camera width="8" height="8" eyeDistance="1"/>{model}</scene>"#
        )
    }

    #[test]
    fn early_stop_only_where_a_chain_can_end_early() {
        let whitted = |depth| format!(r#"<model type="whitted" depth="{depth}"/>"#);
        // ks 0.3, brightest local colour 1: 0.3^k / 0.7 × 255 < 0.5 from
        // k = 6 on.
        assert_eq!(first_stoppable_bounce(0.3, 1.0), 6);
        assert!(!plan(&scene_with(&whitted(6), "0.3", 1)).options.early_stop);
        assert!(plan(&scene_with(&whitted(7), "0.3", 1)).options.early_stop);
        // ks 0.9 needs 82 bounces at brightness 1 (86 at this scene's 1.6).
        assert_eq!(first_stoppable_bounce(0.9, 1.0), 82);
        assert!(!plan(&scene_with(&whitted(80), "0.9", 1)).options.early_stop);
        assert!(
            plan(&scene_with(&whitted(10_000), "0.9", 1))
                .options
                .early_stop
        );
        // Nothing to stop.
        assert!(!plan(&scene_with(&whitted(100), "0", 1)).options.early_stop);
        assert!(!plan(&scene_with(&whitted(100), "1", 1)).options.early_stop);
        assert!(!plan(&scene_with(&whitted(0), "0.3", 1)).options.early_stop);
        let phong = r#"<model type="phong"/>"#;
        assert!(!plan(&scene_with(phong, "0.3", 1)).options.early_stop);
    }

    #[test]
    fn bvh_only_when_the_count_pays() {
        let phong = r#"<model type="phong"/>"#;
        let few = plan(&scene_with(phong, "0.3", BVH_THRESHOLD - 1));
        assert_eq!(choice(&few, "acceleration"), "no BVH, tile culling");
        let many = plan(&scene_with(phong, "0.3", BVH_THRESHOLD));
        assert_eq!(choice(&many, "acceleration"), "BVH, tile culling");
        let lots = plan(&scene_with(phong, "0.3", CULL_LIMIT + 1));
        assert_eq!(choice(&lots, "acceleration"), "BVH, tile candidates");
    }

    #[test]
    fn precision_stays_f64_and_says_by_how_much_f32_falls_short() {
        let p = plan(&scene_with(
            r#"<model type="whitted" depth="2"/>"#,
            "0.3",
            1,
        ));
        assert_eq!(p.options.precision, super::super::Precision::F64);
        let d = &p.decisions[0];
        assert_eq!((d.topic, d.choice.as_str()), ("precision", "f64"));
        // The light at y = -4 is the farthest point: f32's spacing at 4 is
        // 2^-21 ≈ 4.8e-7, against ε = 1e-9 + 4e-12.
        assert!(d.reason.contains("extent 4 is 4.8e-7"), "{}", d.reason);
        assert!(d.reason.contains("ε = 1.0e-9"), "{}", d.reason);
    }

    #[test]
    fn f32_spacing_is_one_ulp() {
        assert_eq!(f32_spacing(1.0), Some(f64::from(f32::EPSILON)));
        assert_eq!(f32_spacing(1e7), Some(1.0));
        assert_eq!(f32_spacing(1e39), None);
    }
}
