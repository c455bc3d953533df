//! Looking around with the mouse (egui_kittest, no display): a drag on the
//! picture orbits the camera, Shift+drag pans it, the wheel dollies it, each
//! an undoable edit of the camera that saves to a file the CLI renders to
//! the same picture; a click still selects; Home returns to the file's
//! camera.

use crate::common;

use std::path::Path;
use std::time::{Duration, Instant};

use egui::{Event, Modifiers, PointerButton, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::DVec3;
use rayoflight::gui::app::{Command, RayOfLightApp};
use rayoflight::render::{
    self,
    navigate::{self, Pose},
};
use rayoflight::scene;
use rayoflight::session::document::Document;
use rayoflight::session::preview::RenderState;
use rayoflight::session::settings::Persisted;

const SCENE: &str = r#"<scene>
  <!-- GREEN sphere -->
  <sphere><color red="0" green="1" blue="0"/></sphere>
  <!-- RED sphere -->
  <sphere>
    <color red="1" green="0" blue="0"/>
    <transformation><translate x="3" y="0" z="0"/></transformation>
  </sphere>
  <light x="1" y="-1" z="-5"/>
  <camera width="32" height="24" eyeDistance="2">
    <transformation>
      <translate x="0" y="0" z="-10"/>
    </transformation>
  </camera>
</scene>
"#;

/// The middle of the picture: the window is 1200×900 and the panel takes
/// the left 320 or so; the fitted picture is centred in the rest.
const MIDDLE: Pos2 = Pos2::new(780.0, 460.0);

fn app(path: &Path) -> Harness<'static, RayOfLightApp> {
    crate::util::app_on(Document::open(path).unwrap())
}

/// The app on `path` once its first full picture is on screen: a click
/// or a drag before it would land on the blank placeholder (a loaded CI
/// machine takes longer than a few frames to render even a tiny scene).
fn ready(path: &Path) -> Harness<'static, RayOfLightApp> {
    let mut harness = app(path);
    let start = Instant::now();
    while !matches!(harness.state().preview().state(), RenderState::Done { .. }) {
        assert!(start.elapsed() < Duration::from_secs(20), "no picture");
        harness.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    harness.run_steps(2);
    harness
}

fn file() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.xml");
    std::fs::write(&path, SCENE).unwrap();
    (dir, path)
}

/// Presses at `from`, moves to `to` in a few steps, releases.
fn drag(harness: &mut Harness<'_, RayOfLightApp>, from: Pos2, to: Pos2, modifiers: Modifiers) {
    harness.event(Event::PointerMoved(from));
    harness.run_steps(1);
    harness.event_modifiers(
        Event::PointerButton {
            pos: from,
            button: PointerButton::Primary,
            pressed: true,
            modifiers,
        },
        modifiers,
    );
    harness.run_steps(1);
    for k in 1..=4 {
        let p = from + (to - from) * (k as f32 / 4.0);
        harness.event_modifiers(Event::PointerMoved(p), modifiers);
        harness.run_steps(1);
    }
    harness.event_modifiers(
        Event::PointerButton {
            pos: to,
            button: PointerButton::Primary,
            pressed: false,
            modifiers,
        },
        modifiers,
    );
    harness.run_steps(2);
}

/// File › Export to path…, `out` typed into its field, Enter.
fn export_to(harness: &mut Harness<'_, RayOfLightApp>, out: &Path) {
    harness.state_mut().run(Command::ExportPath);
    harness.run_steps(2);
    // The dialog's field (the panel's search field is the other one).
    harness
        .get_all_by_role(egui::accesskit::Role::TextInput)
        .last()
        .unwrap()
        .type_text(out.to_str().unwrap());
    harness.run_steps(1);
    harness.key_press(egui::Key::Enter);
    harness.run_steps(2);
}

/// Presses and releases the primary button at `at`, without moving.
fn click(harness: &mut Harness<'_, RayOfLightApp>, at: Pos2) {
    for pressed in [true, false] {
        harness.event(Event::PointerButton {
            pos: at,
            button: PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
        harness.run_steps(1);
    }
}

fn pose(harness: &Harness<'_, RayOfLightApp>) -> Pose {
    Pose::of(&harness.state().document().scene().camera).unwrap()
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() < 1e-9
}

#[test]
fn a_drag_orbits_the_camera_by_the_expected_angle_and_undoes_exactly() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    let original = harness.state().document().scene().clone();
    drag(
        &mut harness,
        MIDDLE,
        MIDDLE + Vec2::new(100.0, 0.0),
        Modifiers::NONE,
    );
    let p = pose(&harness);
    // 100 points at 0.01 rad a point: one radian of yaw about the point
    // under the cursor (the green sphere's near side, on the axis), to
    // the gesture's precision (a sixteenth of a pixel's angle: the angle
    // is written as its shortest decimal within that).
    let camera = &harness.state().document().scene().camera;
    let precision = navigate::pixel_angle(camera) * navigate::GESTURE_PRECISION;
    let expected = DVec3::new(1f64.sin(), 0.0, 1f64.cos());
    assert!(
        p.forward().angle_between(expected) <= precision * 1.01,
        "forward {}",
        p.forward()
    );
    let doc = harness.state().document();
    assert!(doc.has_unsaved_edits());
    assert_eq!(doc.undo_label(), Some("camera view"));
    // One drag, one step: Ctrl+Z gives the camera back exactly.
    harness.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    harness.run_steps(2);
    assert_eq!(harness.state().document().scene(), &original);
    assert!(!harness.state().document().has_unsaved_edits());
}

#[test]
fn shift_drag_pans_and_the_wheel_dollies_as_one_step() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    let start = pose(&harness);
    drag(
        &mut harness,
        MIDDLE,
        MIDDLE + Vec2::new(0.0, 60.0),
        Modifiers::SHIFT,
    );
    let panned = pose(&harness);
    assert!(close(panned.forward(), start.forward()), "no turn");
    let moved = panned.position - start.position;
    assert!(
        moved.y < 0.0 && moved.x.abs() < 1e-9 && moved.z.abs() < 1e-9,
        "{moved}"
    );

    // Three wheel steps in a burst: one undo step toward the sphere.
    harness.event(Event::PointerMoved(MIDDLE));
    for _ in 0..3 {
        harness.event(Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: Vec2::new(0.0, 40.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers: Modifiers::NONE,
        });
        harness.run_steps(4);
    }
    harness.run_steps(20);
    let dollied = pose(&harness);
    assert!(dollied.position.z > panned.position.z, "moved forward");
    std::thread::sleep(Duration::from_millis(600));
    harness.run_steps(2);
    harness.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    harness.run_steps(2);
    assert!(close(pose(&harness).position, panned.position));
}

#[test]
fn a_click_without_a_drag_still_selects() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    assert!(harness.query_by_label("Remove object").is_none());
    harness.event(Event::PointerMoved(MIDDLE));
    harness.run_steps(1);
    click(&mut harness, MIDDLE);
    harness.run_steps(2);
    assert!(harness.query_by_label("Remove object").is_some());
    let camera = &harness.state().document().scene().camera;
    assert_eq!(camera, &scene::load(&path).unwrap().camera, "no move");
}

#[test]
fn the_saved_view_renders_on_the_command_line_as_on_screen_and_home_returns() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    drag(
        &mut harness,
        MIDDLE,
        MIDDLE + Vec2::new(-80.0, 30.0),
        Modifiers::NONE,
    );
    harness.key_press_modifiers(Modifiers::COMMAND, egui::Key::S);
    harness.run_steps(2);
    let start = Instant::now();
    while harness.state().is_saving() {
        assert!(start.elapsed() < Duration::from_secs(10), "the save ended");
        std::thread::sleep(Duration::from_millis(5));
        harness.run_steps(1);
    }
    let saved = scene::load(&path).unwrap();
    assert_eq!(&saved, harness.state().document().scene());
    // The file's text kept its comments; the camera's steps were replaced.
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("<!-- RED sphere -->") && text.contains("<rotate-y angle="));
    let expected = render::render(&saved, &render::auto(&saved).options).unwrap();
    let start = Instant::now();
    loop {
        harness.step();
        let app = harness.state();
        if matches!(app.preview().state(), RenderState::Done { .. })
            && app.preview().image() == &expected
        {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "the saved view never showed"
        );
        std::thread::sleep(Duration::from_millis(10));
    }

    // Home: back to the camera the file has (the saved one now); after
    // another orbit, Home undoes it as one edit.
    drag(
        &mut harness,
        MIDDLE,
        MIDDLE + Vec2::new(50.0, 0.0),
        Modifiers::NONE,
    );
    assert_ne!(&harness.state().document().scene().camera, &saved.camera);
    harness.key_press(egui::Key::Home);
    harness.run_steps(2);
    assert_eq!(&harness.state().document().scene().camera, &saved.camera);
}

#[test]
fn esc_cancels_at_once_and_the_status_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mirrors.xml");
    std::fs::write(&path, common::mirrors_text(10_000, 1920, 1080)).unwrap();
    let mut harness = app(&path);
    let start = Instant::now();
    while !matches!(
        harness.state().preview().state(),
        RenderState::Rendering { .. }
    ) {
        assert!(start.elapsed() < Duration::from_secs(20), "never rendered");
        harness.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    harness.key_press(egui::Key::Escape);
    harness.run_steps(2);
    assert_eq!(harness.state().preview().state(), &RenderState::Cancelled);
    harness
        .get_by_label("cancelled (Esc): the picture may be of an older scene — F5 renders again");
    // Tiles still in flight do not bring "rendering" back.
    std::thread::sleep(Duration::from_millis(200));
    harness.run_steps(3);
    assert_eq!(harness.state().preview().state(), &RenderState::Cancelled);
}

/// Steps the app until a label containing `text` shows, for up to `limit`.
fn wait_for_label(harness: &mut Harness<'_, RayOfLightApp>, text: &str, limit: Duration) {
    let start = Instant::now();
    while harness.query_all_by_label_contains(text).next().is_none() {
        assert!(
            start.elapsed() < limit,
            "no label with {text:?} in {limit:?}"
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn an_export_shows_its_progress_and_time_left_and_can_be_cancelled() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mirrors.xml");
    // Tens of seconds of work: long enough to see progress, then cancel.
    std::fs::write(&path, common::mirrors_text(10_000, 640, 360)).unwrap();
    let out = dir.path().join("out.png");
    let mut harness = app(&path);
    export_to(&mut harness, &out);
    wait_for_label(&mut harness, "exporting out.png", Duration::from_secs(5));
    // After a second with tiles done: a percentage and the time left.
    wait_for_label(&mut harness, "s left", Duration::from_secs(60));
    harness.get_by_label("Cancel").click();
    wait_for_label(&mut harness, "export of", Duration::from_secs(10));
    assert!(
        harness
            .query_all_by_label_contains("cancelled")
            .next()
            .is_some()
    );
    assert!(
        harness
            .query_all_by_label_contains("exporting out.png")
            .next()
            .is_none()
    );
    assert!(!out.exists(), "a cancelled export writes nothing");
}

#[test]
fn dragging_a_light_marker_moves_the_light_in_the_view_plane() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    let start = harness.state().document().scene().lights[0].position;
    // Markers are placed on the picture, which takes its size from the
    // first render: wait for it (a busy machine may be slower than the
    // three frames `app` runs).
    let began = Instant::now();
    let marker = loop {
        if let Some(marker) = harness.state().light_marker(0) {
            break marker;
        }
        assert!(
            began.elapsed() < Duration::from_secs(10),
            "the light is never in view"
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(5));
    };
    drag(
        &mut harness,
        marker,
        marker + Vec2::new(40.0, 0.0),
        Modifiers::NONE,
    );
    let moved = harness.state().document().scene().lights[0].position;
    // The camera looks along +z, unturned: right is +x.
    assert!(moved.x > start.x + 0.1, "{start} -> {moved}");
    assert!((moved.y - start.y).abs() < 1e-9 && (moved.z - start.z).abs() < 1e-9);
    let camera = &harness.state().document().scene().camera;
    assert_eq!(
        camera,
        &scene::load(&path).unwrap().camera,
        "the camera stays"
    );
    let doc = harness.state().document();
    assert_eq!(doc.undo_label(), Some("position of light 1"));
    harness.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    harness.run_steps(2);
    assert_eq!(harness.state().document().scene().lights[0].position, start);
}

#[test]
fn the_selected_object_is_outlined() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    assert_eq!(harness.state().outline_pixels(), None);
    // The middle of the picture is the green sphere.
    harness.state_mut().pick(16.0, 12.0);
    let start = Instant::now();
    while harness.state().outline_pixels().is_none() {
        assert!(start.elapsed() < Duration::from_secs(10), "no outline");
        harness.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    // The sphere's rim: some pixels, far fewer than the picture has.
    let pixels = harness.state().outline_pixels().unwrap();
    assert!((4..32 * 24 / 2).contains(&pixels), "{pixels}");
    // The same outline the core's id buffer gives.
    let scene = harness.state().document().scene().clone();
    let ids = render::object_ids(
        &render::prepare(&scene, &Default::default()),
        &scene.camera,
        1,
    );
    let expected = (0..ids.height)
        .flat_map(|y| (0..ids.width).map(move |x| (x, y)))
        .filter(|&(x, y)| ids.is_outline(x, y, 0))
        .count();
    assert_eq!(pixels, expected);
}

#[test]
fn g_moves_the_selected_object_in_the_view_plane_and_esc_puts_it_back() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    let original = harness.state().document().scene().clone();
    harness.state_mut().pick(16.0, 12.0);
    harness.event(Event::PointerMoved(MIDDLE));
    harness.run_steps(2);

    // G, a move to the right, Esc: nothing changed, nothing to undo.
    harness.key_press(egui::Key::G);
    harness.run_steps(1);
    harness.event(Event::PointerMoved(MIDDLE + Vec2::new(60.0, 0.0)));
    harness.run_steps(2);
    assert_ne!(harness.state().document().scene(), &original, "it follows");
    harness.key_press(egui::Key::Escape);
    harness.run_steps(2);
    assert_eq!(harness.state().document().scene(), &original);
    assert!(!harness.state().document().has_unsaved_edits());

    // G, a move, a click: placed, one undo step.
    harness.event(Event::PointerMoved(MIDDLE));
    harness.run_steps(1);
    harness.key_press(egui::Key::G);
    harness.run_steps(1);
    let to = MIDDLE + Vec2::new(60.0, 0.0);
    harness.event(Event::PointerMoved(to));
    harness.run_steps(2);
    click(&mut harness, to);
    harness.run_steps(2);
    let doc = harness.state().document();
    let moved = doc.scene().objects[0].transform.to_world().translation;
    assert!(
        moved.x > 0.1 && moved.y.abs() < 1e-9 && moved.z.abs() < 1e-9,
        "{moved}"
    );
    assert_eq!(doc.undo_label(), Some("move #1 sphere"));
    harness.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    harness.run_steps(2);
    assert_eq!(harness.state().document().scene(), &original);
}

#[test]
fn the_app_starts_from_its_saved_settings() {
    let (_dir, path) = file();
    let mut persisted = Persisted::in_memory();
    persisted.settings.aa = 3;
    persisted.settings.study_runs = 7;
    let app = RayOfLightApp::new(
        &egui::Context::default(),
        Document::open(&path).unwrap(),
        persisted,
    );
    let settings = app.settings();
    assert_eq!((settings.aa, settings.study_runs), (3, 7));
    assert_eq!(app.study_window().runs, 7);
    // The file open now is the one to reopen next time.
    let saved = settings.last_file.expect("the open file is remembered");
    assert_eq!(saved, std::path::absolute(&path).unwrap());
}

#[test]
fn without_a_file_the_app_reopens_the_last_one_if_it_is_still_there() {
    let (dir, path) = file();
    let mut settings = Persisted::in_memory().settings;
    fn first(s: &rayoflight::session::settings::Settings) -> Document {
        rayoflight::gui::first_document(None, s).unwrap()
    }
    assert!(
        first(&settings).path().is_none(),
        "a fresh machine: built-in"
    );
    settings.last_file = Some(path.clone());
    assert_eq!(first(&settings).path(), Some(path.as_path()));
    // Given a file, that one.
    let other = dir.path().join("other.xml");
    std::fs::write(&other, SCENE).unwrap();
    let given = rayoflight::gui::first_document(Some(&other), &settings).unwrap();
    assert_eq!(given.path(), Some(other.as_path()));
    // Gone (or a folder now): the built-in example.
    std::fs::remove_file(&path).unwrap();
    assert!(first(&settings).path().is_none());
    std::fs::create_dir(&path).unwrap();
    assert!(first(&settings).path().is_none());
}

/// Polls frames until `done` holds (20 s at most).
fn until(
    harness: &mut Harness<'_, RayOfLightApp>,
    what: &str,
    done: impl Fn(&RayOfLightApp) -> bool,
) {
    let start = Instant::now();
    while !done(harness.state()) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{what} never came"
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    harness.run_steps(2);
}

#[test]
fn e_then_a_click_explains_the_pixel_as_rendered_and_a_term_selects_its_field() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    // E arms the explain (Esc takes it back); the click explains
    // instead of selecting.
    let armed = |h: &Harness<'_, RayOfLightApp>| {
        h.query_by_label_contains("click a pixel to explain")
            .is_some()
    };
    harness.key_press(egui::Key::E);
    harness.run_steps(1);
    assert!(armed(&harness));
    harness.key_press(egui::Key::Escape);
    harness.run_steps(1);
    assert!(!armed(&harness));
    harness.key_press(egui::Key::E);
    harness.run_steps(1);
    assert!(
        harness
            .query_by_label_contains("click a pixel to explain")
            .is_some()
    );
    harness.event(Event::PointerMoved(MIDDLE));
    harness.run_steps(1);
    click(&mut harness, MIDDLE);
    harness.run_steps(2);
    // The worker traces it; the window goes on meanwhile.
    until(&mut harness, "the pixel explained", |app| {
        !app.is_explaining() && app.explanation().is_some()
    });
    // Asked directly, the explain is the worker's until a frame takes its
    // answer: the UI thread traces nothing.
    let (x, y) = {
        let e = harness.state().explanation().unwrap();
        (e.x, e.y)
    };
    harness.state_mut().explain_pixel(x, y);
    assert!(harness.state().is_explaining());
    until(&mut harness, "the pixel explained again", |app| {
        !app.is_explaining()
    });
    let app = harness.state();
    let e = app.explanation().expect("the pixel is explained").clone();
    assert_eq!(
        app.selected_object(),
        None,
        "the click explained, not picked"
    );
    // The explained value is the pixel on screen and the CLI's.
    let image = render::render(app.document().scene(), &render::RenderOptions::default()).unwrap();
    assert_eq!(e.rgb8, image.get_pixel(e.x, e.y).0);
    assert_eq!(e.rgb8, app.preview().image().get_pixel(e.x, e.y).0);
    let [r, g, b] = e.rgb8;
    let title = format!("Pixel ({}, {}): ({r}, {g}, {b})", e.x, e.y);
    assert!(harness.query_by_label(&title).is_some(), "{title}");
    let hit = &e.samples[0].bounces[0];
    assert!(
        harness
            .query_by_label_contains(&format!("at t = {}", render::explain::number(hit.t)))
            .is_some()
    );
    // The middle pixel shows the green sphere, named as in the panel.
    // (The object list's row, and the window's link.)
    assert_eq!(harness.query_all_by_label("#1 GREEN sphere").count(), 2);
    // A click on the diffuse term selects the object and marks its kd.
    harness.get_by_label("diffuse  Σ I·kd·cos θ").click();
    harness.run_steps(3);
    assert_eq!(harness.state().selected_object(), Some(hit.object));
    assert!(harness.query_by_label("Remove object").is_some());
    assert_eq!(
        harness.state().marked_field(),
        Some(scene::edit::Field::Material {
            object: hit.object,
            coef: scene::edit::Coef::Kd
        })
    );
    // Alt+click explains directly, without E.
    let alt_click = |harness: &mut Harness<'_, RayOfLightApp>, at: Pos2| {
        harness.event(Event::PointerMoved(at));
        harness.run_steps(1);
        for pressed in [true, false] {
            harness.event_modifiers(
                Event::PointerButton {
                    pos: at,
                    button: PointerButton::Primary,
                    pressed,
                    modifiers: Modifiers::ALT,
                },
                Modifiers::ALT,
            );
            harness.run_steps(1);
        }
        until(harness, "the pixel explained", |app| !app.is_explaining());
    };
    alt_click(&mut harness, MIDDLE + Vec2::new(40.0, 0.0));
    let elsewhere = harness.state().explanation().unwrap().clone();
    assert!(elsewhere.x > e.x, "{} then {}", e.x, elsewhere.x);
    assert_eq!(elsewhere.rgb8, image.get_pixel(elsewhere.x, elsewhere.y).0);
    alt_click(&mut harness, MIDDLE);
    let again = harness.state().explanation().unwrap().clone();
    assert_eq!((again.x, again.y, again.rgb8), (e.x, e.y, e.rgb8));
    // Another program saves the scene: once its picture is done, the
    // pixel is explained again with the new numbers.
    std::fs::write(
        &path,
        SCENE.replace(r#"green="1" blue="0""#, r#"green="0.5" blue="1""#),
    )
    .unwrap();
    until(&mut harness, "the pixel explained again", |app| {
        app.explanation().is_some_and(|now| now.rgb8 != again.rgb8)
    });
    let now = harness.state().explanation().unwrap();
    let edited = render::render(
        harness.state().document().scene(),
        &render::RenderOptions::default(),
    )
    .unwrap();
    assert_eq!((now.x, now.y), (again.x, again.y));
    assert_eq!(now.rgb8, edited.get_pixel(now.x, now.y).0);
}

#[test]
fn view_pass_shows_a_pass_and_the_inspector_its_values() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    harness
        .state_mut()
        .run(Command::ShowPass(render::Pass::Diffuse));
    until(&mut harness, "the diffuse pass", |app| {
        app.pass_shown().1.is_some()
    });
    let scene = harness.state().document().scene().clone();
    let options = render::RenderOptions::default();
    let (expected, _) = render::render_pass(
        &scene,
        &options,
        render::Pass::Diffuse,
        &render::Cancel::never(),
        &render::Progress::default(),
    )
    .unwrap()
    .unwrap();
    assert!(harness.state().pass_shown().1 == Some(&expected));
    harness.event(Event::PointerMoved(MIDDLE));
    harness.run_steps(2);
    assert!(harness.query_by_label_contains(") diffuse (").is_some());
    // Exported: the pass shown, its floats in an EXR.
    let out = path.with_file_name("diffuse.exr");
    export_to(&mut harness, &out);
    wait_for_label(&mut harness, "exported ", Duration::from_secs(20));
    let exr = image::open(&out).unwrap().to_rgb32f();
    let floats: Vec<f32> = expected
        .values
        .iter()
        .map(|&v| render::f32_keeping_level(v))
        .collect();
    assert!(exr.as_raw() == &floats);
    // Depth: its range in the status bar.
    harness
        .state_mut()
        .run(Command::ShowPass(render::Pass::Depth));
    until(&mut harness, "the depth pass", |app| {
        app.pass_shown().1.is_some()
    });
    assert!(harness.query_by_label_contains("depth pass: t ").is_some());
    harness.event(Event::PointerMoved(MIDDLE));
    harness.run_steps(2);
    assert!(harness.query_by_label_contains(") t = ").is_some());
    // Back to the picture.
    harness
        .state_mut()
        .run(Command::ShowPass(render::Pass::Final));
    harness.run_steps(2);
    assert_eq!(harness.state().pass_shown(), (render::Pass::Final, None));
}

/// What a gesture writes is the shortest decimal within a
/// fraction of a pixel, with no identity steps: many orbits there and
/// back, a light dragged, and the file holds short numbers only.
#[test]
fn gestures_write_no_float_noise() {
    let (_dir, path) = file();
    let mut harness = ready(&path);
    for k in 0..6 {
        let dx = if k % 2 == 0 { 37.0 } else { -29.0 };
        drag(
            &mut harness,
            MIDDLE,
            MIDDLE + Vec2::new(dx, 11.0 - 2.0 * k as f32),
            Modifiers::NONE,
        );
    }
    let marker = harness
        .state()
        .light_marker(0)
        .expect("the light is in view");
    drag(
        &mut harness,
        marker,
        marker + Vec2::new(23.0, 7.0),
        Modifiers::NONE,
    );
    harness.key_press_modifiers(Modifiers::COMMAND, egui::Key::S);
    harness.run_steps(2);
    let start = Instant::now();
    while harness.state().is_saving() {
        assert!(start.elapsed() < Duration::from_secs(10), "the save ended");
        std::thread::sleep(Duration::from_millis(5));
        harness.run_steps(1);
    }
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(
        &scene::load(&path).unwrap(),
        harness.state().document().scene(),
        "the file renders what is shown"
    );
    assert!(
        !text.contains("<scale") && !text.contains("rotate-z"),
        "{text}"
    );
    // Every number in the file is short: no 0.9999999999999991.
    for value in text.split('"').skip(1).step_by(2) {
        if value.parse::<f64>().is_ok() {
            assert!(value.len() <= 8, "{value} in\n{text}");
        }
    }
    assert!(
        text.contains("<rotate-y") && text.contains("<light x="),
        "{text}"
    );
}

/// A light's marker and G need only the camera's
/// projection, so they work with a non-uniformly scaled (or sheared)
/// camera, which orbit, pan and dolly refuse with a message.
#[test]
fn a_light_and_an_object_follow_the_mouse_under_a_stretched_camera() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("stretched.xml");
    let text = SCENE.replace(
        r#"<translate x="0" y="0" z="-10"/>"#,
        r#"<scale x="1.5" y="1" z="1"/><translate x="0" y="0" z="-10"/>"#,
    );
    std::fs::write(&path, &text).unwrap();
    let mut harness = ready(&path);
    assert!(Pose::of(&harness.state().document().scene().camera).is_err());
    // Orbiting says why it cannot.
    drag(
        &mut harness,
        MIDDLE,
        MIDDLE + Vec2::new(40.0, 0.0),
        Modifiers::NONE,
    );
    assert!(!harness.state().document().has_unsaved_edits());
    assert!(harness.query_by_label_contains("shear").is_some());

    let start = harness.state().document().scene().lights[0].position;
    let marker = harness
        .state()
        .light_marker(0)
        .expect("the light is in view");
    drag(
        &mut harness,
        marker,
        marker + Vec2::new(40.0, 0.0),
        Modifiers::NONE,
    );
    let moved = harness.state().document().scene().lights[0].position;
    assert!(moved.x > start.x + 0.1, "{start} -> {moved}");
    assert!((moved.y - start.y).abs() < 1e-9 && (moved.z - start.z).abs() < 1e-9);
    // Where the marker is now: under the pointer, to a pixel.
    let now = harness.state().light_marker(0).unwrap();
    assert!(
        (now - (marker + Vec2::new(40.0, 0.0))).length() < 3.0,
        "{now:?}"
    );

    // The light's drag changed the scene: the pick waits for the worker
    // to prepare it again, and G needs the selection.
    harness.state_mut().pick(16.0, 12.0);
    until(&mut harness, "the pick", |app| !app.waits_for_the_worker());
    harness.event(Event::PointerMoved(MIDDLE));
    harness.run_steps(1);
    harness.key_press(egui::Key::G);
    harness.run_steps(1);
    let to = MIDDLE + Vec2::new(60.0, 0.0);
    harness.event(Event::PointerMoved(to));
    harness.run_steps(2);
    click(&mut harness, to);
    harness.run_steps(2);
    let doc = harness.state().document();
    let moved = doc.scene().objects[0].transform.to_world().translation;
    assert!(
        moved.x > 0.1 && moved.y.abs() < 1e-9 && moved.z.abs() < 1e-9,
        "{moved}"
    );
}
