//! Render methods: a name and how it renders — the same [`RenderOptions`]
//! for every scene, or the options [`auto`](fn@super::auto) plans for each.
//! The command line's `--method`, the app's preview and the study choose
//! among [`methods`]; the study compares them all (speed against
//! accuracy). A [`RenderRequest`](crate::render::request::RenderRequest) names one
//! (none: `auto`).

use super::{Offset, Precision, RenderOptions, SphereTest};
use crate::scene::Scene;

/// A method: a name (the CSV's `method` column) and how it renders.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Method {
    pub name: &'static str,
    pub options: Options,
}

/// How a method renders: the same options for every scene, or the options
/// [`auto`](fn@super::auto) plans for each scene.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Options {
    Fixed(RenderOptions),
    Auto,
}

impl Method {
    /// The options this method renders `scene` with.
    pub fn options_for(&self, scene: &Scene) -> RenderOptions {
        match &self.options {
            Options::Fixed(options) => options.clone(),
            Options::Auto => super::auto(scene).options,
        }
    }

    /// Whether the method supersamples (and is measured against the
    /// supersampled reference).
    pub fn supersamples(&self) -> bool {
        matches!(&self.options, Options::Fixed(o) if o.aa > 1)
    }
}

/// The methods compared: `default` (the reference method, docs/study.md,
/// done plainly, every ray against every object, every chain to its
/// depth) first, then `auto`, then variations of the exact fast path
/// ([`RenderOptions::default`]), one change each.
pub fn methods() -> Vec<Method> {
    let d = RenderOptions::default;
    let method = |name, options| Method {
        name,
        options: Options::Fixed(options),
    };
    vec![
        method("default", RenderOptions::reference()),
        Method {
            name: "auto",
            options: Options::Auto,
        },
        method(
            "f32",
            RenderOptions {
                precision: Precision::F32,
                ..d()
            },
        ),
        // f32 with an offset f32 can resolve near the origin (the reference
        // offset 1e-9 + 1e-12·|M| is below f32's spacing everywhere): it
        // separates f32's failure far from the origin from its acne.
        method(
            "f32-eps-1e-3",
            RenderOptions {
                precision: Precision::F32,
                offset: Offset::Fixed(1e-3),
                ..d()
            },
        ),
        method(
            "textbook",
            RenderOptions {
                sphere: SphereTest::Textbook,
                ..d()
            },
        ),
        method(
            "fixed-eps-1e-4",
            RenderOptions {
                offset: Offset::Fixed(1e-4),
                ..d()
            },
        ),
        method(
            "no-offset",
            RenderOptions {
                offset: Offset::None,
                ..d()
            },
        ),
        method("aa2", RenderOptions { aa: 2, ..d() }),
        method("aa4", RenderOptions { aa: 4, ..d() }),
        method(
            "depth-1",
            RenderOptions {
                depth_cut: true,
                ..d()
            },
        ),
        method(
            "no-early-stop",
            RenderOptions {
                early_stop: false,
                ..d()
            },
        ),
        method("draft", RenderOptions { draft: true, ..d() }),
    ]
}

/// The method called `name`, if the study has one.
pub fn method(name: &str) -> Option<Method> {
    methods().into_iter().find(|m| m.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn methods_are_named_once_and_default_first() {
        let m = methods();
        assert_eq!(m[0].name, "default");
        assert_eq!(m[0].options, Options::Fixed(RenderOptions::reference()));
        let mut names: Vec<_> = m.iter().map(|m| m.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), m.len());
    }
}
