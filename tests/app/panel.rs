//! The window's own logic without a display (egui_kittest): an edit in
//! the panel renders the edited scene, the Study window runs the study and
//! picks the preview's method, the method while dragging, and the object
//! list of a big scene.

use egui_kittest::kittest::Queryable;
use rayoflight::gui::app::RayOfLightApp;
use rayoflight::render::{self, RenderOptions};
use rayoflight::scene;
use rayoflight::session::document::Document;
use rayoflight::session::preview::RenderState;
use rayoflight::session::settings::Persisted;
use std::time::{Duration, Instant};

use crate::background::{parse, scene_text};

/// Steps the app until its preview is finished and equals `expected`
/// (at most 20 s; `what` names the picture in the failure).
fn until_the_picture_is(
    harness: &mut egui_kittest::Harness<'_, RayOfLightApp>,
    expected: &image::RgbImage,
    what: &str,
) {
    let start = Instant::now();
    loop {
        harness.step();
        let app = harness.state();
        if matches!(app.preview().state(), RenderState::Done { .. })
            && app.preview().image() == expected
        {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{what} never showed"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn a_panel_edit_renders_the_edited_scene() {
    let app = RayOfLightApp::new(
        &egui::Context::default(),
        Document::builtin(),
        Persisted::in_memory(),
    );
    let mut harness = egui_kittest::Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .build_ui_state(|ui, app: &mut RayOfLightApp| app.draw(ui), app);
    harness.run_steps(2);
    let before = harness.state().newest_generation();
    harness.get_by_label("lambert").click();
    harness.run_steps(2);
    let app = harness.state();
    assert_eq!(
        app.document().scene().model.illumination,
        scene::Illumination::Lambert
    );
    assert!(app.document().has_unsaved_edits());
    assert!(
        app.newest_generation() > before,
        "the edit asked for a render"
    );

    // The picture becomes the lambert render, as the CLI would draw it.
    let expected = render::render(app.document().scene(), &RenderOptions::default()).unwrap();
    until_the_picture_is(&mut harness, &expected, "the edited scene");
}

#[test]
fn the_study_window_runs_the_study_and_picks_the_preview_method() {
    let app = RayOfLightApp::new(
        &egui::Context::default(),
        Document::builtin(),
        Persisted::in_memory(),
    );
    let mut harness = egui_kittest::Harness::builder()
        .with_size(egui::vec2(1400.0, 1000.0))
        .build_ui_state(|ui, app: &mut RayOfLightApp| app.draw(ui), app);
    harness.run_steps(2);
    assert_eq!(harness.state().preview_methods().preview.name, "auto");
    harness.get_by_label("View").click();
    harness.run_steps(2);
    harness.get_by_label("Study…").click();
    harness.run_steps(2);
    // auto's plan is shown with its numbers (every glyph must exist in
    // egui's font).
    harness.get_by_label("auto's plan for this scene").click();
    harness.run_steps(2);
    harness.get_by_label("Run the study").click();
    harness.run_steps(2);
    let start = Instant::now();
    while !harness.state().study_window().is_done() {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "the study did not finish: {:?}",
            harness.state().study_window().state()
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    harness.run_steps(2);
    let methods = rayoflight::render::methods();
    assert_eq!(harness.state().study_window().rows().len(), methods.len());

    // The chart's legend stands beside the chart, not over it: the
    // threshold's entry and every method's name to its right.
    let chart = harness.get_by_label("study chart").rect();
    let threshold = harness.get_by_label("fails above 1 %").rect();
    assert!(
        threshold.left() >= chart.right(),
        "legend {threshold:?} over the chart {chart:?}"
    );
    for m in &methods {
        assert!(
            harness
                .get_all_by_label(m.name)
                .any(|n| n.rect().left() >= chart.right()),
            "{} is not in the legend beside the chart {chart:?}",
            m.name
        );
    }

    // The rows offer their method for the live preview: pick draft (the
    // eleventh row; auto is "previewing", so the ninth button from the top).
    let buttons = harness.get_all_by_label("preview with it").count();
    assert_eq!(buttons, methods.len() - 1);
    let draft_row = methods.iter().position(|m| m.name == "draft").unwrap();
    let auto_row = methods.iter().position(|m| m.name == "auto").unwrap();
    let button = draft_row - usize::from(draft_row > auto_row);
    harness
        .get_all_by_label("preview with it")
        .nth(button)
        .unwrap()
        .scroll_to_me();
    harness.run_steps(3);
    harness
        .get_all_by_label("preview with it")
        .nth(button)
        .unwrap()
        .click();
    harness.run_steps(2);
    assert_eq!(harness.state().preview_methods().preview.name, "draft");
    // …and the picture becomes the draft render.
    let scene = harness.state().document().scene().clone();
    let expected = render::render(
        &scene,
        &RenderOptions {
            draft: true,
            ..RenderOptions::default()
        },
    )
    .unwrap();
    until_the_picture_is(&mut harness, &expected, "the draft preview");
}

#[test]
fn the_dragging_method_applies_only_while_dragging() {
    use rayoflight::gui::study::PreviewMethods;
    use rayoflight::render::method;
    let scene = parse(&scene_text(1.0, 32));
    let methods = PreviewMethods {
        preview: method("auto").unwrap(),
        dragging: method("f32"),
    };
    let auto = render::auto(&scene).options;
    assert_eq!(methods.request(false, 1).options(&scene), auto);
    let fast = methods.request(true, 1).options(&scene);
    assert_eq!(fast.precision, render::Precision::F32);
    // The preview's anti-aliasing applies to a method that does not
    // supersample.
    assert_eq!(methods.request(false, 3).options(&scene).aa, 3);
    let aa4 = PreviewMethods {
        preview: method("aa4").unwrap(),
        dragging: None,
    };
    assert_eq!(aa4.request(true, 1).options(&scene).aa, 4);
}

/// The object list of a scene of 100 000 spheres: only the rows on screen
/// are laid out, the search finds an object by its number and by the words
/// of its label, and a click on a row selects it.
#[test]
fn the_object_list_of_a_big_scene_lays_out_only_the_rows_on_screen() {
    use egui::accesskit::Role;
    let mut text = String::from("<scene>\n");
    for i in 1..=100_000 {
        if i == 76_543 {
            text.push_str("  <!-- Golden ball, the one to find -->\n");
        }
        text.push_str(&format!(
            "  <sphere><transformation><translate x=\"{i}\" z=\"5\"/></transformation></sphere>\n"
        ));
    }
    text.push_str("  <light x=\"0\" y=\"-3\" z=\"-3\"/>\n");
    text.push_str("  <camera width=\"16\" height=\"16\" eyeDistance=\"2\"/>\n</scene>\n");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.xml");
    std::fs::write(&path, &text).unwrap();
    let app = RayOfLightApp::new(
        &egui::Context::default(),
        Document::open(&path).unwrap(),
        Persisted::in_memory(),
    );
    let mut harness = egui_kittest::Harness::builder()
        .with_size(egui::vec2(1200.0, 800.0))
        .build_ui_state(|ui, app: &mut RayOfLightApp| app.draw(ui), app);
    harness.run_steps(2);
    // The rows laid out this frame: one accessibility node each.
    let rows = |harness: &egui_kittest::Harness<'_, RayOfLightApp>| {
        harness
            .query_all_by(|node| node.label().is_some_and(|l| l.starts_with('#')))
            .count()
    };
    let shown = rows(&harness);
    assert!(
        (5..=30).contains(&shown),
        "{shown} object rows laid out of 100 000"
    );
    harness.get_by_label("#1 sphere");
    assert!(harness.query_by_label("#100000 sphere").is_none());

    // By number (as typed, or with its '#'), then by the words of its label.
    let label = "#76543 Golden ball sphere";
    for query in ["76543", "#76543", "golden BALL"] {
        let field = harness.get_by_role(Role::TextInput);
        field.focus();
        harness.run_steps(1);
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
        harness.get_by_role(Role::TextInput).type_text(query);
        harness.run_steps(2);
        assert_eq!(rows(&harness), 1, "{query:?} finds one object");
        harness.get_by_label(label);
    }
    harness.get_by_label(label).click();
    harness.run_steps(2);
    assert_eq!(harness.state().selected_object(), Some(76_542));
    harness.get_by_label(&format!("Edit {label}"));
    assert!(harness.query_by_label("Remove object").is_some());
}

/// A newcomer's first screen says where the keys are (F1, the Help menu)
/// and what the mouse does on the picture; Help › Keys and mouse… opens
/// the list.
#[test]
fn the_first_screen_says_where_the_keys_are() {
    let mut harness = crate::util::app_on(Document::builtin());
    harness.get_by_label_contains("F1: keys and mouse");
    harness.get_by_label_contains("click an object");
    assert!(harness.query_by_label("Keys and mouse").is_none());
    harness.get_by_label("Help").click();
    harness.run_steps(2);
    harness.get_by_label_contains("Keys and mouse…").click();
    harness.run_steps(2);
    assert!(harness.query_by_label("Keys and mouse").is_some());
}
