//! What the app's tests share: the app in a test harness (no display,
//! egui_kittest), stepping it until something holds, and small readers.

use std::path::Path;
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use rayoflight::gui::app::RayOfLightApp;
use rayoflight::scene::edit::{Coef, Field};
use rayoflight::scene::{self, Scene};
use rayoflight::session::document::Document;
use rayoflight::session::settings::Persisted;

/// The app on `doc` with the settings `persisted`, in a 1200×900 window,
/// its first frames drawn.
pub fn app_keeping(doc: Document, persisted: Persisted) -> Harness<'static, RayOfLightApp> {
    let app = RayOfLightApp::new(&egui::Context::default(), doc, persisted);
    let mut harness = Harness::builder()
        .with_size(egui::vec2(1200.0, 900.0))
        .build_ui_state(|ui, app: &mut RayOfLightApp| app.draw(ui), app);
    harness.run_steps(3);
    harness
}

/// The app on `doc` with settings in memory only (no journal, nothing
/// written to the user's home).
pub fn app_on(doc: Document) -> Harness<'static, RayOfLightApp> {
    app_keeping(doc, Persisted::in_memory())
}

/// Steps the app until `done` holds; how long it took (at most `limit`,
/// or the test fails naming `what`).
pub fn step_until(
    harness: &mut Harness<'_, RayOfLightApp>,
    limit: Duration,
    what: &str,
    done: impl Fn(&RayOfLightApp) -> bool,
) -> Duration {
    let start = Instant::now();
    while !done(harness.state()) {
        assert!(start.elapsed() < limit, "{what} within {limit:?}");
        harness.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    start.elapsed()
}

pub fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

pub fn parse(text: &str) -> Scene {
    scene::parse(text, Path::new("t.xml")).unwrap()
}

/// The path of object `object`'s ka.
pub fn ka(object: usize) -> Field {
    Field::Material {
        object,
        coef: Coef::Ka,
    }
}
