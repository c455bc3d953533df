//! `rayoflight explain scene.xml X Y [--json]`: why a pixel has its
//! colour, as text for a person or as one JSON object for a script. The
//! tree is the library's ([`Prepared::explain_each`]); this edge only
//! words it, written out as the rays are traced: one ray's tree in memory
//! at a time, whatever the output's length (256 rays of 10 000 bounces
//! write 1.5 GB of JSON).
//!
//! Its flags, as clap reads them, are here too ([`ExplainFlags`]),
//! resolved into the [`ExplainArgs`] it runs with.

use super::edit::{self, EditArg};
use super::failure::{Failure, fail, refused};
use super::render::RenderOf;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use clap::Args;
use glam::DVec3;
use rayoflight::geometry::Ray;
use rayoflight::render::explain::{
    Bounce, Ended, PixelValue, Sample, describe_ray, draft_note, number as n, vector as v,
};
use rayoflight::render::request::RenderRequest;
use rayoflight::render::{Prepared, prepare};
use rayoflight::scene::edit::Edited;
use rayoflight::scene::{self, Scene, names};
use rayoflight::system::escape::visible as shown;
use serde_json::{Value, json};
use std::io::{self, Write};
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Traces the pixel and writes its trees out, in words or as JSON.
fn explain(args: &ExplainArgs) -> Result<(), Failure> {
    let (text, loaded) = scene::load_with_text(&args.scene).map_err(fail)?;
    let mut edited = Edited::new(loaded);
    edit::apply(&mut edited, &args.edits).map_err(refused(&args.scene))?;
    let scene = edited.scene();
    let (width, height) = (scene.camera.width, scene.camera.height);
    if args.x >= width || args.y >= height {
        return Err(Failure::Usage(UsageError::Invalid {
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
    }
    let options = args.request.options(scene);
    let prepared = prepare(scene, &options);
    let names = Names {
        scene,
        comments: names::object_labels(&text),
    };
    let mut out = io::BufWriter::with_capacity(1 << 16, io::stdout().lock());
    let pixel = (args.x, args.y);
    let written = if args.json {
        json_to(&mut out, &prepared, pixel, &names)
    } else {
        words_to(
            &mut out,
            &prepared,
            pixel,
            &names,
            &args.scene.display().to_string(),
        )
    };
    // A closed pipe (`explain … | head`) is the reader's choice; any
    // other failure to write is an error.
    match written.and_then(|()| out.flush()) {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => Err(Failure::Error(format!(
            "rayoflight: cannot write to stdout: {e}"
        ))),
        _ => Ok(()),
    }
}

/// Each ray's tree of pixel (x, y) in turn to `write`, stopping at its
/// first error; then the pixel.
fn each_sample(
    p: &Prepared,
    (x, y): (u32, u32),
    mut write: impl FnMut(usize, Sample) -> io::Result<()>,
) -> io::Result<PixelValue> {
    let mut failure = None;
    let mut k = 0;
    let pixel = p.explain_each(x, y, |sample| {
        let written = write(k, sample);
        k += 1;
        match written {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                failure = Some(e);
                ControlFlow::Break(())
            }
        }
    });
    match (failure, pixel) {
        (Some(e), _) => Err(e),
        (None, Some(pixel)) => Ok(pixel),
        (None, None) => Err(io::Error::other("the pixel is outside the image")),
    }
}

/// The panel's names of the scene's objects.
struct Names<'a> {
    scene: &'a Scene,
    comments: names::Labels,
}

impl Names<'_> {
    fn object(&self, n: usize) -> String {
        let shape = self
            .scene
            .objects
            .get(n)
            .map_or("object", |o| o.shape.name());
        // A comment may hold a line break: one line still.
        let name = names::object_name(n, shape, self.comments.get(n));
        shown(&name, false).into_owned()
    }
}

// ----- JSON -----

fn v3(v: DVec3) -> Value {
    json!([v.x, v.y, v.z])
}

fn ray_json(ray: &Ray) -> Value {
    json!({ "origin": v3(ray.origin), "direction": v3(ray.dir) })
}

/// Writes `value` as compact JSON (serde_json's numbers and escapes).
fn put(out: &mut impl Write, value: &Value) -> io::Result<()> {
    serde_json::to_writer(&mut *out, value).map_err(io::Error::from)
}

/// The explanation as one JSON object on one line, written as the rays
/// are traced: `x`, `y`, `traced`, `model`, `rgb8`, `rgb`, then the first ray's
/// `hits` and `ended`, then, with more rays than one, every ray's tree in
/// `samples`. The pixel's value comes first, so it is traced once
/// beforehand without recording.
fn json_to(
    out: &mut impl Write,
    p: &Prepared,
    (x, y): (u32, u32),
    names: &Names,
) -> io::Result<()> {
    let pixel = p
        .explained_pixel(x, y)
        .ok_or_else(|| io::Error::other("the pixel is outside the image"))?;
    out.write_all(b"{\"x\":")?;
    put(out, &json!(x))?;
    out.write_all(b",\"y\":")?;
    put(out, &json!(y))?;
    // The pixel whose rays were traced: (x, y), or a draft's block corner.
    out.write_all(b",\"traced\":")?;
    put(out, &json!([pixel.traced.0, pixel.traced.1]))?;
    out.write_all(b",\"model\":")?;
    put(out, &json!(p.illumination().name()))?;
    out.write_all(b",\"rgb8\":")?;
    put(out, &json!(pixel.rgb8))?;
    out.write_all(b",\"rgb\":")?;
    put(out, &v3(pixel.rgb))?;
    let many = pixel.samples > 1;
    each_sample(p, (x, y), |k, sample| {
        if k == 0 {
            // One ray per pixel: its tree at the top. More: each ray's
            // tree in "samples", the first one's also at the top.
            out.write_all(b",\"hits\":")?;
            hits_to(out, &sample, names)?;
            out.write_all(b",\"ended\":")?;
            put(out, &ended_json(sample.ended))?;
            if many {
                out.write_all(b",\"samples\":[")?;
            }
        } else {
            out.write_all(b",")?;
        }
        if many {
            sample_to(out, &sample, names)?;
        }
        Ok(())
    })?;
    if many {
        out.write_all(b"]")?;
    }
    out.write_all(b"}\n")
}

/// One ray's tree: `at`, `rgb`, `hits`, `ended`.
fn sample_to(out: &mut impl Write, s: &Sample, names: &Names) -> io::Result<()> {
    out.write_all(b"{\"at\":")?;
    put(out, &json!([s.at.0, s.at.1]))?;
    out.write_all(b",\"rgb\":")?;
    put(out, &v3(s.color))?;
    out.write_all(b",\"hits\":")?;
    hits_to(out, s, names)?;
    out.write_all(b",\"ended\":")?;
    put(out, &ended_json(s.ended))?;
    out.write_all(b"}")
}

/// The hits of a ray's chain, a bounce at a time, and the ray that
/// missed, if one did.
fn hits_to(out: &mut impl Write, s: &Sample, names: &Names) -> io::Result<()> {
    out.write_all(b"[")?;
    for (k, b) in s.bounces.iter().enumerate() {
        if k > 0 {
            out.write_all(b",")?;
        }
        put(out, &bounce_json(b, names))?;
    }
    if let Some(ray) = &s.missed {
        if !s.bounces.is_empty() {
            out.write_all(b",")?;
        }
        put(
            out,
            &json!({
                "object": null, "label": null, "t": null, "point": null, "normal": null,
                "ray": ray_json(ray),
            }),
        )?;
    }
    out.write_all(b"]")
}

fn ended_json(ended: Ended) -> Value {
    match ended {
        Ended::EarlyStop { bound } => json!({ "reason": "early stop", "bound": v3(bound) }),
        other => json!({ "reason": reason(other) }),
    }
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

/// The explanation in words, a ray's tree at a time.
fn words_to(
    out: &mut impl Write,
    p: &Prepared,
    (x, y): (u32, u32),
    names: &Names,
    scene: &str,
) -> io::Result<()> {
    // The scene's name and its comments come from outside: escaped, a
    // line break in them too (it would start a line of its own).
    let head = format!(
        "pixel ({x}, {y}) of {}: {} model\n",
        shown(scene, false),
        p.illumination().name()
    );
    out.write_all(shown(&head, true).as_bytes())?;
    let count = p.samples_per_pixel();
    if let Some(note) = draft_note((x, y), p.traced_for(x, y), count) {
        writeln!(out, "{note}")?;
    }
    let pixel = each_sample(p, (x, y), |k, s| {
        let mut text = String::new();
        if count > 1 {
            text += &format!(
                "\nsample {} of {count} at ({}, {}):\n",
                k + 1,
                n(s.at.0),
                n(s.at.1)
            );
        }
        sample_words(&mut text, &s, names);
        out.write_all(shown(&text, true).as_bytes())
    })?;
    if count > 1 {
        writeln!(
            out,
            "\nmean of the {count} samples {} (each clamped to [0, 1] first)",
            v(pixel.rgb)
        )?;
    } else {
        writeln!(out, "\nunclamped sum {}", v(pixel.rgb))?;
    }
    let [r, g, b] = pixel.rgb8;
    writeln!(out, "8-bit value  ({r}, {g}, {b})")
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

// ----- the command line -----

/// `rayoflight explain`: which pixel of which render.
#[derive(Debug, Clone, PartialEq)]
pub struct ExplainArgs {
    pub scene: PathBuf,
    pub x: u32,
    pub y: u32,
    pub json: bool,
    /// The render's method and anti-aliasing (threads do not matter).
    pub request: RenderRequest,
    /// `--set`: values changed in memory first, in order.
    pub edits: Vec<EditArg>,
}

/// Why a pixel has its colour: its ray tree, term by term.
///
/// For each bounce: the ray, the object hit (its number as in the
/// app's panel), t, the hit point M and normal N, for each light
/// cos θ and cos α, and the terms ka·C, Σ I·kd·cos θ, Σ I·ks·cos^m α
/// and ks·Ir; then where the chain ended (a miss, the depth, ks = 0,
/// or the early stop and its bound), the unclamped sum and the 8-bit
/// value, which is the pixel of `rayoflight scene.xml` with the same
/// --set, --aa and --method.
#[derive(Args, Debug)]
#[command(
    override_usage = "rayoflight explain scene.xml X Y [--json] [--set PATH=VALUE]… \
                      [--aa N] [--method NAME]"
)]
pub(super) struct ExplainFlags {
    /// The scene file.
    scene: PathBuf,
    /// The pixel's column, 0 at the left.
    #[arg(value_name = "X", value_parser = pixel, allow_negative_numbers = true)]
    x: u32,
    /// The pixel's row, 0 at the top.
    #[arg(value_name = "Y", value_parser = pixel, allow_negative_numbers = true)]
    y: u32,
    /// Print one JSON object: "rgb8", "rgb", "hits" (each with "object",
    /// 1-based or null for a miss, "t", "point", "normal", "terms").
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    render: RenderOf,
}

impl Subcommand for ExplainFlags {
    type Args = ExplainArgs;

    /// The pixel asked about, the render's edits read against the scene's
    /// path.
    fn resolve(self, _: &clap::ArgMatches) -> Result<ExplainArgs, UsageError> {
        let (request, edits) = self.render.resolve(&self.scene)?;
        Ok(ExplainArgs {
            scene: self.scene,
            x: self.x,
            y: self.y,
            json: self.json,
            request,
            edits,
        })
    }

    fn prints(_: &ExplainArgs) -> bool {
        true
    }

    fn run(args: ExplainArgs, _: fn() -> clap::Command) -> Result<(), Failure> {
        explain(&args)
    }
}

fn pixel(text: &str) -> Result<u32, String> {
    text.parse()
        .map_err(|_| "expects a pixel number: 0, 1, 2, … from the image's top left".to_owned())
}
