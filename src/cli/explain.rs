//! `rayoflight explain scene.xml X Y [--json]`: why a pixel has its
//! colour, as text for a person or as one JSON object for a script. The
//! tree is the library's ([`Prepared::explain`]); this edge only words it.

use super::args::ExplainArgs;
use super::{Failure, edit, fail, print_line, refused};
use glam::DVec3;
use rayoflight::geometry::Ray;
use rayoflight::render::explain::{Bounce, Ended, Sample, describe_ray, number as n, vector as v};
use rayoflight::render::{Explanation, prepare};
use rayoflight::scene::edit::Edited;
use rayoflight::scene::{self, Scene, splice};
use serde_json::{Value, json};

pub fn run(args: &ExplainArgs) -> Result<(), Failure> {
    let (text, loaded) = scene::load_with_text(&args.scene).map_err(fail)?;
    let mut edited = Edited::new(loaded);
    edit::apply(&mut edited, &args.edits).map_err(refused(&args.scene))?;
    let scene = edited.scene();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let options = args.request.options(scene);
    let Some(explained) = prepare(scene, &options).explain(args.x, args.y) else {
        return Err(Failure::Usage(super::UsageError::Invalid {
            message: format!(
                "pixel ({}, {}) is outside the {width}×{height} image of {} \
                 (X from 0 to {}, Y from 0 to {})",
                args.x,
                args.y,
                args.scene.display(),
                width.saturating_sub(1),
                height.saturating_sub(1)
            ),
            command: Some("explain"),
        }));
    };
    let names = Names {
        scene,
        comments: splice::object_labels(&text),
    };
    if args.json {
        let value = to_json(&explained, &names);
        print_line(&value.to_string())?;
    } else {
        print_line(&words(
            &explained,
            &names,
            &args.scene.display().to_string(),
        ))?;
    }
    Ok(())
}

/// The panel's names of the scene's objects.
struct Names<'a> {
    scene: &'a Scene,
    comments: Vec<Option<String>>,
}

impl Names<'_> {
    fn object(&self, n: usize) -> String {
        let shape = self
            .scene
            .objects
            .get(n)
            .map_or("object", |o| o.shape.name());
        let words = self.comments.get(n).and_then(|w| w.as_deref());
        splice::object_name(n, shape, words)
    }
}

// ----- JSON -----

fn v3(v: DVec3) -> Value {
    json!([v.x, v.y, v.z])
}

fn ray_json(ray: &Ray) -> Value {
    json!({ "origin": v3(ray.origin), "direction": v3(ray.dir) })
}

fn to_json(e: &Explanation, names: &Names) -> Value {
    let samples: Vec<Value> = e.samples.iter().map(|s| sample_json(s, names)).collect();
    let mut top = json!({
        "x": e.x,
        "y": e.y,
        "traced": [e.traced.0, e.traced.1],
        "model": e.illumination.name(),
        "rgb8": e.rgb8,
        "rgb": v3(e.rgb),
    });
    // One ray per pixel: its tree at the top. More: each ray's tree in
    // "samples", the first one's also at the top.
    if let (Some(Value::Object(first)), Value::Object(out)) = (samples.first(), &mut top) {
        for key in ["hits", "ended"] {
            if let Some(v) = first.get(key) {
                out.insert(key.to_owned(), v.clone());
            }
        }
        if samples.len() > 1 {
            out.insert("samples".to_owned(), Value::Array(samples));
        }
    }
    top
}

fn sample_json(s: &Sample, names: &Names) -> Value {
    let mut hits: Vec<Value> = s.bounces.iter().map(|b| bounce_json(b, names)).collect();
    if let Some(ray) = &s.missed {
        hits.push(json!({
            "object": null, "label": null, "t": null, "point": null, "normal": null,
            "ray": ray_json(ray),
        }));
    }
    let ended = match s.ended {
        Ended::EarlyStop { bound } => json!({ "reason": "early stop", "bound": v3(bound) }),
        other => json!({ "reason": reason(other) }),
    };
    json!({
        "at": [s.at.0, s.at.1],
        "rgb": v3(s.color),
        "hits": hits,
        "ended": ended,
    })
}

fn bounce_json(b: &Bounce, names: &Names) -> Value {
    let lights: Vec<Value> = b
        .lights
        .iter()
        .map(|l| {
            json!({
                "light": l.light + 1,
                "cos_theta": l.cos_theta,
                "cos_alpha": l.cos_alpha,
                "diffuse": v3(l.diffuse),
                "specular": v3(l.specular),
            })
        })
        .collect();
    json!({
        "object": b.object + 1,
        "label": names.object(b.object),
        "ray": ray_json(&b.ray),
        "t": b.t,
        "point": v3(b.point),
        "normal": v3(b.normal),
        "lights": lights,
        "ks": b.ks,
        "weight": b.weight,
        "terms": {
            "ambient": v3(b.terms.ambient),
            "diffuse": v3(b.terms.diffuse),
            "specular": v3(b.terms.specular),
            "reflection": v3(b.reflection),
        },
        "color": v3(b.color),
    })
}

fn reason(ended: Ended) -> &'static str {
    match ended {
        Ended::Missed => "missed",
        Ended::Depth => "depth",
        Ended::NoMirror => "ks = 0",
        Ended::EarlyStop { .. } => "early stop",
    }
}

// ----- words -----

fn words(e: &Explanation, names: &Names, scene: &str) -> String {
    let [r, g, b] = e.rgb8;
    let mut out = format!(
        "pixel ({}, {}) of {scene}: {} model\n",
        e.x,
        e.y,
        e.illumination.name()
    );
    if let Some(note) = e.draft_note() {
        out += &format!("{note}\n");
    }
    for (k, s) in e.samples.iter().enumerate() {
        if e.samples.len() > 1 {
            out += &format!(
                "\nsample {} of {} at ({}, {}):\n",
                k + 1,
                e.samples.len(),
                n(s.at.0),
                n(s.at.1)
            );
        }
        sample_words(&mut out, s, names);
    }
    if e.samples.len() > 1 {
        out += &format!(
            "\nmean of the {} samples {} (each clamped to [0, 1] first)\n",
            e.samples.len(),
            v(e.rgb)
        );
    } else {
        out += &format!("\nunclamped sum {}\n", v(e.rgb));
    }
    out += &format!("8-bit value  ({r}, {g}, {b})");
    out
}

fn sample_words(out: &mut String, s: &Sample, names: &Names) {
    for (k, b) in s.bounces.iter().enumerate() {
        *out += &format!("\n{}\n", describe_ray(k, &b.ray));
        *out += &format!("  hits {} at t = {}\n", names.object(b.object), n(b.t));
        *out += &format!("  M = {}  N = {}\n", v(b.point), v(b.normal));
        for l in &b.lights {
            *out += &format!("  {}\n", l.describe());
        }
        *out += &format!("  ambient     ka·C            {}\n", v(b.terms.ambient));
        *out += &format!("  diffuse     Σ I·kd·cos θ    {}\n", v(b.terms.diffuse));
        *out += &format!("  specular    Σ I·ks·cos^m α  {}\n", v(b.terms.specular));
        *out += &format!(
            "  reflection  ks·Ir           {}  (ks = {})\n",
            v(b.reflection),
            n(b.ks)
        );
        *out += &format!("  colour                      {}\n", v(b.color));
    }
    if let Some(ray) = &s.missed {
        let ray = describe_ray(s.bounces.len(), ray);
        *out += &format!("\n{ray}\n  hits nothing: black\n");
    }
    *out += &format!("chain ended: {}\n", s.ended.describe());
}
