//! The app's model without a window (`rayoflight::session`, no egui): the
//! render worker (newest request wins, stale events dropped,
//! cancellation), the picture assembled from tiles, the file watcher
//! (atomic rename, plain write, delete and recreate, debounced), the
//! document's broken saves, the study run by the worker. Editing, undo,
//! save-back and merges are tests/app/editing.rs; the window's panel and
//! Study window, tests/app/panel.rs.

use crate::common;

use rayoflight::render::request::RenderRequest;
use rayoflight::render::{self, RenderOptions};
use rayoflight::scene::{self, Scene};
use rayoflight::session::document::{FileState, Reload, fingerprint_file};
use rayoflight::session::preview::{Preview, RenderState};
use rayoflight::session::watcher::{FileEvent, SceneWatcher};
use rayoflight::session::worker::{self, Event, Worker};
use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc;
use std::time::{Duration, Instant};

pub(crate) fn scene_text(red: f64, width: u32) -> String {
    format!(
        r#"<scene>
  <!-- a comment that save-back must keep -->
  <sphere>
    <color red="{red}" green="0.5" blue="0.25"/>
    <transformation><translate z="3"/></transformation>
  </sphere>
  <light x="0" y="-3" z="-3"/>
  <camera width="{width}" height="{width}" eyeDistance="2"/>
</scene>
"#
    )
}

pub(crate) fn parse(text: &str) -> Scene {
    scene::parse(text, Path::new("test.xml")).unwrap()
}

/// The slow two-mirror scene (tests/common).
fn mirrors(depth: u32, width: u32, height: u32) -> Scene {
    parse(&common::mirrors_text(depth, width, height))
}

/// Collects the worker's events up to the first for which `last` holds;
/// returns them and the time it took. Panics after `limit`, naming `what`.
fn events_until(
    worker: &Worker,
    limit: Duration,
    what: &str,
    last: impl Fn(&Event) -> bool,
) -> (Vec<Event>, Duration) {
    let start = Instant::now();
    let mut events = Vec::new();
    while start.elapsed() < limit {
        if let Some(e) = worker.next_event(Duration::from_millis(10)) {
            let done = last(&e);
            events.push(e);
            if done {
                return (events, start.elapsed());
            }
        }
    }
    panic!("{what} did not end within {limit:?}");
}

/// Events until the full-resolution pass of `generation` finishes.
fn until_finished(worker: &Worker, generation: u64, limit: Duration) -> (Vec<Event>, Duration) {
    events_until(
        worker,
        limit,
        &format!("generation {generation}"),
        |e| matches!(e, Event::PassFinished { generation: g, scale: 1, .. } if *g == generation),
    )
}

#[test]
fn worker_renders_the_same_image_as_the_cli_path() {
    let s = parse(&scene_text(1.0, 300));
    let worker = Worker::spawn(1, || {});
    let generation = worker.request(Arc::new(s.clone()), RenderRequest::default());
    let (events, _) = until_finished(&worker, generation, Duration::from_secs(30));
    let mut preview = Preview::default();
    for e in events {
        assert!(preview.apply(generation, e));
    }
    let expected = render::render(&s, &RenderOptions::default()).unwrap();
    assert_eq!(preview.image(), &expected);
    assert!(matches!(preview.state(), RenderState::Done { .. }));
}

#[test]
fn coarse_passes_come_first_for_large_images() {
    let s = parse(&scene_text(1.0, 600));
    let worker = Worker::spawn(1, || {});
    let generation = worker.request(Arc::new(s), RenderRequest::default());
    let (events, _) = until_finished(&worker, generation, Duration::from_secs(30));
    let scales: Vec<u32> = events
        .iter()
        .filter_map(|e| match e {
            Event::PassStarted { scale, .. } => Some(*scale),
            _ => None,
        })
        .collect();
    assert_eq!(scales, [8, 4, 1]);
}

#[test]
fn a_newer_request_cancels_the_older_within_100_ms() {
    // Depth 10 000 between two mirrors at 3840×2160: minutes of work.
    let heavy = mirrors(10_000, 3840, 2160);
    let light = parse(&scene_text(0.3, 32));
    let worker = Worker::spawn(Worker::default_threads(), || {});
    let old = worker.request(Arc::new(heavy), RenderRequest::default());
    std::thread::sleep(Duration::from_millis(300));
    let new = worker.request(Arc::new(light.clone()), RenderRequest::default());
    // The light scene takes well under a millisecond: what is measured is
    // the time for the heavy render to notice it was cancelled.
    let (events, took) = until_finished(&worker, new, Duration::from_secs(10));
    eprintln!("newer render finished {took:?} after the request");
    assert!(
        took < Duration::from_millis(300),
        "cancel took {took:?} (promise 100 ms, 3x allowed on a noisy CI machine)"
    );
    // Stale events are dropped by the preview.
    let mut preview = Preview::default();
    let mut stale = 0;
    for e in events {
        if e.generation() == old {
            assert!(!preview.apply(new, e));
            stale += 1;
        } else {
            assert!(preview.apply(new, e));
        }
    }
    let _ = stale;
    let expected = render::render(&light, &RenderOptions::default()).unwrap();
    assert_eq!(preview.image(), &expected);
}

#[test]
fn dropping_the_worker_stops_a_long_render_promptly() {
    let worker = Worker::spawn(Worker::default_threads(), || {});
    worker.request(
        Arc::new(mirrors(10_000, 3840, 2160)),
        RenderRequest::default(),
    );
    std::thread::sleep(Duration::from_millis(200));
    let start = Instant::now();
    drop(worker);
    let took = start.elapsed();
    eprintln!("worker stopped in {took:?}");
    assert!(took < Duration::from_millis(300), "stopping took {took:?}");
}

#[test]
fn queued_requests_collapse_to_the_newest() {
    let worker = Worker::spawn(1, || {});
    let scenes: Vec<_> = (0..20)
        .map(|i| Arc::new(parse(&scene_text(f64::from(i) / 20.0, 64))))
        .collect();
    let mut last = 0;
    for s in &scenes {
        last = worker.request(s.clone(), RenderRequest::default());
    }
    let (events, _) = until_finished(&worker, last, Duration::from_secs(30));
    let finished: Vec<u64> = events
        .iter()
        .filter_map(|e| match e {
            Event::PassFinished { generation, .. } => Some(*generation),
            _ => None,
        })
        .collect();
    assert!(finished.len() < 5, "renders were queued: {finished:?}");
    assert_eq!(finished.last(), Some(&last));
}

#[test]
fn tiles_wake_the_window_at_most_once_a_frame() {
    // 1024×1024 in 32-pixel tiles: a thousand tiles a pass.
    let s = Arc::new(mirrors(3, 1024, 1024));
    let wakes = Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let counted = wakes.clone();
    let worker = Worker::spawn(Worker::default_threads(), move || {
        counted.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    });
    let start = Instant::now();
    let generation = worker.request_passes(s, Default::default(), vec![1]);
    let (events, _) = until_finished(&worker, generation, Duration::from_secs(60));
    let took = start.elapsed();
    let tiles = events
        .iter()
        .filter(|e| matches!(e, Event::Tile { .. }))
        .count();
    let passes = events.len() - tiles;
    let wakes = wakes.load(std::sync::atomic::Ordering::Relaxed);
    // Each pass event wakes it; tiles at most once a frame.
    let most = passes + (took.as_secs_f64() / worker::FRAME.as_secs_f64()).ceil() as usize + 1;
    eprintln!("{tiles} tiles, {passes} pass events in {took:?}: {wakes} wake-ups (at most {most})");
    assert!(tiles >= 1024, "{tiles}");
    assert!(
        wakes <= most,
        "{wakes} wake-ups for {tiles} tiles in {took:?}"
    );
    assert!(wakes >= passes, "every pass event wakes the window");
}

#[test]
fn a_render_while_dragging_is_the_same_render_on_fewer_threads() {
    let s = parse(&scene_text(0.7, 300));
    let worker = Worker::spawn(Worker::default_threads(), || {});
    let generation = worker.request_while_dragging(Arc::new(s.clone()), Default::default(), 1);
    let (events, _) = until_finished(&worker, generation, Duration::from_secs(30));
    let mut preview = Preview::default();
    for e in events {
        assert!(preview.apply(generation, e));
    }
    assert_eq!(
        preview.image(),
        &render::render(&s, &RenderOptions::default()).unwrap()
    );
}

#[test]
fn passes_ids_and_exports_are_rendered_by_the_worker() {
    let s = Arc::new(parse(&scene_text(0.4, 96)));
    let worker = Worker::spawn(Worker::default_threads(), || {});
    let generation = worker.request(s.clone(), RenderRequest::default());
    until_finished(&worker, generation, Duration::from_secs(30));
    let (tx, rx) = mpsc::channel();
    // A pass: the library's, for the same request.
    let never = render::Cancel::new(Arc::new(std::sync::atomic::AtomicU64::new(0)), 0);
    let sent = tx.clone();
    worker.render_pass(
        s.clone(),
        Default::default(),
        render::Pass::Normal,
        never.clone(),
        move |image| {
            let _ = sent.send(("pass", Some(image), None));
        },
    );
    let (what, image, _) = rx.recv_timeout(Duration::from_secs(30)).unwrap();
    assert_eq!(what, "pass");
    let expected = render::render_pass(
        &s,
        &RenderOptions::default(),
        render::Pass::Normal,
        &render::Cancel::never(),
        &Default::default(),
    )
    .unwrap()
    .unwrap()
    .0;
    assert!(image.as_ref() == Some(&expected));
    // The object ids, in the scene it prepared.
    let sent = tx.clone();
    worker.object_ids(s.clone(), 2, move |ids| {
        let _ = sent.send(("ids", None, Some(ids)));
    });
    let (what, _, ids) = rx.recv_timeout(Duration::from_secs(30)).unwrap();
    assert_eq!(what, "ids");
    let ids = ids.unwrap();
    let expected = render::object_ids(
        &render::prepare(&s, &RenderOptions::default()),
        &s.camera,
        2,
    );
    assert_eq!((ids.width, ids.height), (48, 48));
    assert_eq!(ids.is_outline(24, 24, 0), expected.is_outline(24, 24, 0));
    assert_eq!(
        (0..48)
            .flat_map(|y| (0..48).map(move |x| (x, y)))
            .filter(|&(x, y)| ids.is_outline(x, y, 0))
            .count(),
        (0..48)
            .flat_map(|y| (0..48).map(move |x| (x, y)))
            .filter(|&(x, y)| expected.is_outline(x, y, 0))
            .count(),
    );
    // A pass asked for before a newer render never comes: that render
    // cancels it (or it is stale before it starts).
    let heavy = Arc::new(mirrors(10_000, 1920, 1080));
    let old = worker.request(heavy.clone(), RenderRequest::default());
    let sent = tx.clone();
    worker.render_pass(
        heavy.clone(),
        Default::default(),
        render::Pass::Final,
        never.clone(),
        move |image| {
            let _ = sent.send(("stale pass", Some(image), None));
        },
    );
    let new = worker.request(s.clone(), RenderRequest::default());
    assert!(new > old);
    until_finished(&worker, new, Duration::from_secs(10));
    // The export: the command line's image, beside the preview.
    let (done_tx, done_rx) = mpsc::channel();
    let progress = Arc::new(render::Progress::default());
    worker.export(
        worker::ExportJob {
            scene: (*s).clone(),
            request: Default::default(),
            pass: None,
            progress: progress.clone(),
            cancel: never,
        },
        move |rendered| {
            let _ = done_tx.send(rendered);
        },
    );
    let exported = done_rx.recv_timeout(Duration::from_secs(30)).unwrap();
    let Ok(Some(worker::Exported::Picture(picture))) = exported else {
        panic!("no picture exported");
    };
    assert_eq!(
        picture,
        render::render(&s, &RenderOptions::default()).unwrap()
    );
    assert_eq!(progress.fraction(), 1.0);
    std::thread::sleep(Duration::from_millis(200));
    assert!(rx.try_recv().is_err(), "the stale pass was cancelled");
}

/// Waits for the next watcher event.
fn next(rx: &mpsc::Receiver<FileEvent>) -> FileEvent {
    rx.recv_timeout(Duration::from_secs(5))
        .expect("the watcher reported within 5 s")
}

fn assert_loaded_red(event: FileEvent, red: f64) {
    match event {
        FileEvent::Loaded(read) => assert_eq!(read.scene.objects[0].color.x, red),
        other => panic!("expected a loaded scene, got {other:?}"),
    }
}

/// Nothing more arrives for a while (debounced, and nothing spurious).
fn quiet(rx: &mpsc::Receiver<FileEvent>) {
    if let Ok(e) = rx.recv_timeout(Duration::from_millis(400)) {
        panic!("unexpected event {e:?}");
    }
}

/// A temporary scene file (red 0.1) under a watcher whose events arrive on
/// the returned channel; the watcher is running when this returns.
fn watched_scene() -> (
    tempfile::TempDir,
    std::path::PathBuf,
    mpsc::Receiver<FileEvent>,
    SceneWatcher,
) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.xml");
    std::fs::write(&path, scene_text(0.1, 8)).unwrap();
    let (tx, rx) = mpsc::channel();
    let watcher = SceneWatcher::new(&path, fingerprint_file(&path).ok(), move |e| {
        let _ = tx.send(e);
    })
    .unwrap();
    std::thread::sleep(Duration::from_millis(100));
    (dir, path, rx, watcher)
}

#[test]
fn watcher_sees_renames_writes_deletes_and_recreates() {
    let (dir, path, rx, _watcher) = watched_scene();

    // Atomic rename, as vim, VS Code and sed -i save.
    let tmp = dir.path().join(".scene.xml.swp");
    std::fs::write(&tmp, scene_text(0.2, 8)).unwrap();
    std::fs::rename(&tmp, &path).unwrap();
    assert_loaded_red(next(&rx), 0.2);
    quiet(&rx);

    // A plain write in several quick chunks: one event, after the last.
    let text = scene_text(0.3, 8);
    let (a, b) = text.split_at(text.len() / 2);
    std::fs::write(&path, a).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(&path)
        .unwrap();
    std::io::Write::write_all(&mut f, b.as_bytes()).unwrap();
    drop(f);
    assert_loaded_red(next(&rx), 0.3);
    quiet(&rx);

    // Deleted, then created again.
    std::fs::remove_file(&path).unwrap();
    assert!(matches!(next(&rx), FileEvent::Missing));
    std::fs::write(&path, scene_text(0.4, 8)).unwrap();
    assert_loaded_red(next(&rx), 0.4);

    // A broken save reports the error with its position.
    std::fs::write(
        &path,
        "<scene>\n  <sphere><material ka=\"-1\"/></sphere>\n</scene>\n",
    )
    .unwrap();
    match next(&rx) {
        FileEvent::Broken(e) => {
            let message = e.to_string();
            assert!(message.contains("scene.xml:2:21:"), "{message}");
        }
        other => panic!("expected an error, got {other:?}"),
    }

    // Other files in the directory are ignored.
    std::fs::write(dir.path().join("other.xml"), "x").unwrap();
    quiet(&rx);
}

#[test]
fn a_broken_save_keeps_the_last_good_scene_and_shows_the_error() {
    let (_dir, path, mut doc) = common::document_on(&scene_text(0.1, 8));
    let good = doc.scene().clone();
    let error = scene::load(&path).err();
    assert!(error.is_none());
    std::fs::write(&path, "<scene><camera width=\"0\"").unwrap();
    let error = scene::load(&path).unwrap_err();
    assert_eq!(doc.file_broken(&error), Reload::Broken);
    assert_eq!(doc.scene(), &good);
    assert!(
        doc.error()
            .unwrap()
            .starts_with(&format!("{}:1:", path.display()))
    );
    // The next good save clears it.
    let text = scene_text(0.7, 8);
    assert_eq!(
        doc.file_loaded(text.clone(), parse(&text)),
        Reload::Replaced
    );
    assert!(doc.error().is_none());
    assert_eq!(doc.scene().objects[0].color.x, 0.7);
    // The same content again is not a change.
    assert_eq!(
        doc.file_loaded(text.clone(), parse(&text)),
        Reload::Unchanged
    );
    doc.file_missing();
    assert_eq!(doc.state(), &FileState::Missing);
}

#[test]
fn watcher_survives_a_rename_away_and_a_directory_in_place() {
    let (dir, path, rx, _watcher) = watched_scene();

    // Renamed away: missing.
    std::fs::rename(&path, dir.path().join("elsewhere.xml")).unwrap();
    assert!(matches!(next(&rx), FileEvent::Missing));

    // A directory where the file was: an error that says so.
    std::fs::create_dir(&path).unwrap();
    match next(&rx) {
        FileEvent::Broken(e) => assert!(e.to_string().contains("directory"), "{e}"),
        other => panic!("expected an error, got {other:?}"),
    }

    // A good file again: back to normal (a Missing may come first, between
    // the directory's removal and the new file).
    std::fs::remove_dir(&path).unwrap();
    std::fs::write(&path, scene_text(0.6, 8)).unwrap();
    loop {
        match next(&rx) {
            FileEvent::Missing => continue,
            event => {
                assert_loaded_red(event, 0.6);
                break;
            }
        }
    }
}

/// Events of `generation` until its study ends (finished or stopped).
fn until_study_ends(worker: &Worker, generation: u64, limit: Duration) -> (Vec<Event>, Duration) {
    events_until(worker, limit, &format!("study {generation}"), |e| {
        e.generation() == generation
            && matches!(e, Event::StudyFinished { .. } | Event::StudyStopped { .. })
    })
}

#[test]
fn the_worker_runs_the_study_row_by_row() {
    let scene = rayoflight::study::StudyScene {
        name: "small".into(),
        scene: parse(&scene_text(1.0, 64)),
    };
    let worker = Worker::spawn(1, || {});
    let generation = worker.study(scene, 1, Default::default());
    let (events, _) = until_study_ends(&worker, generation, Duration::from_secs(60));
    let methods = rayoflight::render::methods();
    assert!(matches!(events[0], Event::StudyStarted { total, .. } if total == methods.len()));
    let rows: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Event::StudyRow { row, failure, .. } => Some((row, failure)),
            _ => None,
        })
        .collect();
    assert_eq!(rows.len(), methods.len());
    for ((row, failure), method) in rows.iter().zip(&methods) {
        assert_eq!(row.method, method.name);
        assert_eq!(row.failed, failure.is_some(), "{}", row.method);
    }
    for exact in ["default", "auto"] {
        let row = rows.iter().find(|(r, _)| r.method == exact).unwrap().0;
        assert_eq!((row.max_diff, row.within1), (0, 1.0), "{exact}");
    }
    assert!(
        matches!(events.last(), Some(Event::StudyFinished { .. })),
        "{:?}",
        events.last()
    );
}

#[test]
fn a_study_is_cancelled_within_100_ms() {
    // The plain reference of a depth-10 000 mirror pair at 3840×2160:
    // minutes of work.
    let scene = rayoflight::study::StudyScene {
        name: "heavy".into(),
        scene: mirrors(10_000, 3840, 2160),
    };
    let worker = Worker::spawn(Worker::default_threads(), || {});
    let generation = worker.study(scene, 1, Default::default());
    std::thread::sleep(Duration::from_millis(300));
    let asked = Instant::now();
    worker.cancel();
    let (events, _) = until_study_ends(&worker, generation, Duration::from_secs(10));
    let took = asked.elapsed();
    eprintln!("the study stopped {took:?} after the cancel");
    assert!(
        took < Duration::from_millis(300),
        "cancel took {took:?} (promise 100 ms, 3x allowed on a noisy CI machine)"
    );
    assert!(
        matches!(events.last(), Some(Event::StudyStopped { message, .. }) if message == "cancelled")
    );
}
