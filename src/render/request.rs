//! One render request, resolved in one place. The command line's flags,
//! the bench, the study and the app each say what they want — a method
//! (none: `auto`), an anti-aliasing, a thread count — and
//! [`RenderRequest::options`] turns it into the [`RenderOptions`] for a
//! scene, with one precedence:
//!
//! 1. the method's options for the scene: `auto` plans them per scene
//!    (exact, the reference image), another method fixes them;
//! 2. an anti-aliasing the user asked for (`--aa N`, View › Anti-aliasing
//!    above 1×1) replaces the method's; none asked, the method's stays
//!    (`aa4` renders 4×4);
//! 3. the thread count (none: rayon's pool, one thread per core), and the
//!    region of the image to render (none: all of it).

use crate::render::region::Region;
use crate::render::{self, Method, RenderOptions};
use crate::scene::Scene;

/// What a front end asks to render with.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RenderRequest {
    /// A render method ([`render::methods`]); `None`: `auto`.
    pub method: Option<Method>,
    /// Anti-aliasing the user asked for (N×N rays a pixel); `None`: the
    /// method's.
    pub aa: Option<u32>,
    /// Render threads; `None`: one per core.
    pub threads: Option<usize>,
    /// The rectangle of the image to render (`--region`); `None`: all.
    pub region: Option<Region>,
}

impl RenderRequest {
    /// The options to render `scene` with (see the module's precedence).
    pub fn options(&self, scene: &Scene) -> RenderOptions {
        let planned = match &self.method {
            Some(method) => method.options_for(scene),
            None => render::auto(scene).options,
        };
        RenderOptions {
            aa: self.aa.unwrap_or(planned.aa),
            threads: self.threads,
            region: self.region,
            ..planned
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_users_anti_aliasing_wins_over_the_methods() {
        let scene = crate::scene::parse(crate::EXAMPLE_SCENE, std::path::Path::new("e.xml"))
            .expect("the example loads");
        let aa4 = render::method("aa4");
        let request = |method: Option<Method>, aa| RenderRequest {
            method,
            aa,
            threads: Some(3),
            region: None,
        };
        assert_eq!(request(aa4.clone(), None).options(&scene).aa, 4);
        assert_eq!(request(aa4, Some(2)).options(&scene).aa, 2);
        let auto = request(None, None).options(&scene);
        assert_eq!(
            auto,
            RenderOptions {
                threads: Some(3),
                ..render::auto(&scene).options
            }
        );
        assert_eq!(request(None, Some(3)).options(&scene).aa, 3);
    }
}
