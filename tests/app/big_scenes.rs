//! A big scene costs the app what it costs the command line, not a copy
//! more per place that holds it: the objects of the
//! file's scene, the edited one, the one being rendered and the one read
//! back after a save are shared where they are the same; a scene is
//! prepared once however often the camera moves; a save scans only the
//! objects it changes; a large text held packed saves as the same text
//! held whole. Each is checked here by what is shared, not by
//! memory or time, so the tests stay small and exact — but one: the
//! memory a save leaves behind in the allocator, which only memory shows
//! (`src/cli/allocator.rs`).

use crate::common;

use rayoflight::render::request::RenderRequest;
use rayoflight::scene::edit::{Edit, Field, Value};
use rayoflight::scene::{self, Scene, Shape};
use rayoflight::session::document::{Document, FileRead, Reload, SaveStep};
use rayoflight::session::watcher::{FileEvent, SceneWatcher};
use rayoflight::session::worker::{Event, Worker};
use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;

/// `n` small spheres in a row, each with a colour and two steps, a light,
/// a 24×24 camera.
fn spheres_text(n: usize) -> String {
    let mut text = String::from("<scene>\n");
    for i in 0..n {
        text.push_str(&format!(
            "  <!-- ball {i} -->\n  <sphere>\n    <color red=\"0.5\" green=\"{}\" blue=\"0.25\"/>\n    \
             <transformation><scale factor=\"0.1\"/><translate x=\"{}\" z=\"5\"/></transformation>\n  </sphere>\n",
            (i % 100) as f64 / 100.0,
            i as f64 * 0.01 - 5.0,
        ));
    }
    text.push_str("  <light x=\"0\" y=\"-3\" z=\"-3\"/>\n");
    text.push_str("  <camera width=\"24\" height=\"24\" eyeDistance=\"2\"/>\n</scene>\n");
    text
}

fn set(path: &str, value: f64) -> Edit {
    Edit::Set(Field::parse(path).unwrap(), Value::Number(value))
}

/// Which objects of `a` and `b` (of one length) are not one shared object.
fn unshared(a: &Scene, b: &Scene) -> Vec<usize> {
    assert_eq!(a.objects.len(), b.objects.len());
    (0..a.objects.len())
        .filter(|&i| !Arc::ptr_eq(&a.objects[i], &b.objects[i]))
        .collect()
}

#[test]
fn the_edited_scene_shares_every_object_but_the_one_edited() {
    let (_dir, _path, mut doc) = common::document_on(&spheres_text(1000));
    assert!(unshared(doc.file_scene(), doc.scene()).is_empty());
    // Until an edit, even the list of objects is one.
    assert!(doc.file_scene().objects.same_list(&doc.scene().objects));
    // Paths count from 1: object[700] is index 699.
    doc.apply(set("object[700].material.ka", 0.5)).unwrap();
    assert_eq!(unshared(doc.file_scene(), doc.scene()), vec![699]);
    // A copy of the scene (what a render request sends) shares them all,
    // and their list: a million objects' is 8 MB a copy.
    let sent = doc.scene().clone();
    assert!(unshared(&sent, doc.scene()).is_empty());
    assert!(sent.objects.same_list(&doc.scene().objects));
    // Undone, the one copied object is equal again: nothing unsaved.
    doc.undo();
    assert!(!doc.has_unsaved_edits());
    assert_eq!(unshared(doc.file_scene(), doc.scene()), vec![699]);
}

#[test]
fn a_save_is_read_back_sharing_the_objects_on_screen() {
    let (_dir, path, mut doc) = common::document_on(&spheres_text(1000));
    let (rx, watcher) = watched(&path, &doc);
    doc.apply(set("object[4].color.red", 0.75)).unwrap();
    watcher.share(&doc.scene().objects);
    doc.save().unwrap();
    let back = next_loaded(&rx);
    assert!(unshared(&back.scene, doc.scene()).is_empty());
    assert_eq!(doc.file_read(*back), Reload::Unchanged);
    // What the file holds now is what was saved: every object shared.
    assert!(unshared(doc.file_scene(), doc.scene()).is_empty());
}

/// The app's own save of a large file is not read back by the watcher
/// (the document knows those bytes: a million objects would be read and
/// parsed again for nothing); another program's change to it still is.
#[test]
fn a_large_file_the_app_saved_is_not_read_back() {
    let text = spheres_text(30_000);
    assert!(text.len() as u64 >= rayoflight::session::BACKGROUND_BYTES);
    let (_dir, path, mut doc) = common::document_on(&text);
    let (rx, watcher) = watched(&path, &doc);
    doc.apply(set("object[4].color.red", 0.75)).unwrap();
    let job = doc.save_job().unwrap().announcing(watcher.own_writes());
    let outcome = job.run();
    assert_eq!(
        doc.save_done(job, outcome).unwrap(),
        SaveStep::Done(Reload::Unchanged)
    );
    assert!(!doc.has_unsaved_edits());
    // Past the debounce and a poll or two: nothing read, nothing said.
    if let Ok(event) = rx.recv_timeout(Duration::from_secs(3)) {
        panic!("the app's own save was read back: {event:?}");
    }
    // Another program's bytes are read.
    let saved = std::fs::read_to_string(&path).unwrap();
    let theirs = saved.replacen("blue=\"0.25\"", "blue=\"0.5\"", 1);
    std::fs::write(&path, &theirs).unwrap();
    assert_eq!(next_change(&rx, &mut doc), Reload::Replaced);
    // And so are the app's saved bytes when another program writes them
    // back: the document last read other ones.
    std::thread::sleep(Duration::from_millis(300));
    std::fs::write(&path, &saved).unwrap();
    assert_eq!(next_change(&rx, &mut doc), Reload::Replaced);
}

/// What the next read of the file that `doc` does not hold yet did to
/// it: a write can be seen as two changes, its second read giving bytes
/// the document already took (on a loaded machine, once in many runs).
fn next_change(rx: &mpsc::Receiver<FileEvent>, doc: &mut Document) -> Reload {
    loop {
        match doc.file_read(*next_loaded(rx)) {
            Reload::Unchanged => continue,
            other => return other,
        }
    }
}

/// A watcher on `path`, which `doc` read, and the events it sends, once
/// it has settled.
fn watched(path: &Path, doc: &Document) -> (mpsc::Receiver<FileEvent>, SceneWatcher) {
    let (tx, rx) = mpsc::channel();
    let watcher = SceneWatcher::new(path, doc.disk_fingerprint(), move |e| {
        let _ = tx.send(e);
    })
    .unwrap();
    std::thread::sleep(Duration::from_millis(100));
    (rx, watcher)
}

/// The next file the watcher read and loaded.
fn next_loaded(rx: &mpsc::Receiver<FileEvent>) -> Box<FileRead> {
    loop {
        match rx
            .recv_timeout(Duration::from_secs(10))
            .expect("the change is seen")
        {
            FileEvent::Loaded(read) => return read,
            FileEvent::Broken(e) => panic!("{e}"),
            FileEvent::Missing | FileEvent::Reading => {}
        }
    }
}

#[test]
fn a_large_text_held_packed_saves_as_a_text_held_whole() {
    use rayoflight::scene::edit::{Item, NewElement};
    use rayoflight::scene::source::PACK_BYTES;
    let text = spheres_text(95_000);
    assert!(text.len() >= PACK_BYTES, "{}", text.len());
    let (_dir, path, mut doc) = common::document_on(&text);
    assert!(doc.holds_packed_text());
    // The labels the comments above the objects give, as of a whole text.
    let labels = scene::names::object_labels(&text);
    for n in [0, 1, 47_000, 94_999] {
        let shape = doc.scene().objects[n].shape.name();
        let expected = scene::names::object_name(n, shape, labels.get(n));
        assert_eq!(doc.object_label(n), expected);
    }
    assert_eq!(doc.object_label(47_000), "#47001 ball 47000 sphere");
    // Values, an object removed, one added, a light moved: what the same
    // edits save into the text held whole.
    let mut whole = rayoflight::scene::edit::Edited::new(doc.file_scene().clone());
    for k in 0..4 {
        let edit = match k {
            0 => set("object[40000].color.red", 0.75),
            1 => Edit::Remove(Item::Object(12)),
            2 => Edit::add(doc.scene(), NewElement::Object(Shape::Sphere)),
            _ => set("light[1].x", 2.5),
        };
        doc.apply(edit.clone()).unwrap();
        whole.apply(&edit).unwrap();
    }
    let expected = scene::splice::save(&text, &path, &whole).unwrap();
    doc.save().unwrap();
    let saved = std::fs::read_to_string(&path).unwrap();
    assert!(saved == expected, "the packed text's save differs");
    assert_eq!(&scene::parse(&saved, &path).unwrap(), doc.scene());
    // Everything undone and saved: the file byte for byte.
    while doc.undo().is_some() {}
    doc.save().unwrap();
    assert!(std::fs::read_to_string(&path).unwrap() == text, "undone");
}

#[test]
fn parsing_again_shares_the_objects_that_did_not_change() {
    let text = spheres_text(50);
    let first = scene::parse(&text, Path::new("a.xml")).unwrap();
    let changed = text.replacen("green=\"0.3\"", "green=\"0.35\"", 1);
    let again = scene::parse_sharing(&changed, Path::new("a.xml"), &first.objects).unwrap();
    assert_eq!(unshared(&first, &again), vec![30]);
    assert_eq!(again, scene::parse(&changed, Path::new("a.xml")).unwrap());
}

/// Renders `scene` in the worker and waits for its last pass.
fn render(worker: &Worker, scene: &Scene) {
    let generation = worker.request(Arc::new(scene.clone()), RenderRequest::default());
    loop {
        match worker.next_event(Duration::from_secs(20)) {
            Some(Event::PassFinished {
                generation: g,
                scale: 1,
                ..
            }) if g == generation => return,
            Some(Event::Failed { message, .. }) => panic!("{message}"),
            Some(_) => {}
            None => panic!("the render did not finish"),
        }
    }
}

#[test]
fn moving_the_camera_does_not_prepare_the_scene_again() {
    let worker = Worker::spawn(1, || {});
    let scene = scene::parse(&spheres_text(200), Path::new("a.xml")).unwrap();
    render(&worker, &scene);
    let first = worker.prepared(&scene).expect("the scene just rendered");

    // Another camera: the same prepared scene, for the render and for
    // picking.
    let mut moved = scene.clone();
    moved.camera.eye_distance = 3.0;
    assert!(worker.prepared(&moved).unwrap().same_world(&first));
    render(&worker, &moved);
    let after = worker.prepared(&moved).unwrap();
    assert!(after.same_world(&first));
    assert_eq!(after.camera().ray(12.0, 12.0), {
        let fresh =
            rayoflight::render::prepare(&moved, &rayoflight::render::RenderOptions::default());
        fresh.camera().ray(12.0, 12.0)
    });

    // Another object value: prepared again, and not offered for picks
    // until then.
    let mut edited = moved.clone();
    Arc::make_mut(&mut edited.objects[5]).material.kd = 0.1;
    assert!(worker.prepared(&edited).is_none());
    render(&worker, &edited);
    assert!(!worker.prepared(&edited).unwrap().same_world(&first));
}

/// A stage of `rayoflight bench --app-document` and the memory it printed.
#[derive(Debug)]
struct Stage {
    name: String,
    /// The process's peak so far, and its resident memory then, in kB.
    peak_kb: f64,
    resident_kb: f64,
}

/// `rayoflight bench --app-document path` with `args`, its allocator as
/// the program sets it (not as this shell might), and the stages it
/// printed.
fn app_document(path: &Path, args: &[&str]) -> Vec<Stage> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .args(["bench", "--app-document"])
        .arg(path)
        .args(args)
        .env_remove("MALLOC_MMAP_THRESHOLD_")
        .env_remove("MALLOC_TRIM_THRESHOLD_")
        .env_remove("MALLOC_ARENA_MAX")
        .env_remove("GLIBC_TUNABLES")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let (l, resident) = l.rsplit_once(' ').unwrap();
            let (name, peak) = l.rsplit_once(' ').unwrap();
            Stage {
                name: name.to_owned(),
                peak_kb: peak.parse().unwrap(),
                resident_kb: resident.parse().unwrap(),
            }
        })
        .collect()
}

/// The bench's measure of the app without its window (`bench
/// --app-document`, a child of the big section): it opens the file,
/// renders, edits one value, journals and saves it, and says its peak
/// memory after each stage; the file ends up with that one value changed.
#[test]
fn the_bench_measures_the_app_through_a_picture_an_edit_and_a_save() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("spheres.xml");
    let text = spheres_text(2000);
    std::fs::write(&path, &text).unwrap();
    let stages = app_document(&path, &["--threads", "1"]);
    let names: Vec<&str> = stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        ["after the picture", "after an edit", "after a save"]
    );
    // Peaks only rise, and a process holding 2000 objects is over 1 MB.
    assert!(
        stages.windows(2).all(|w| w[0].peak_kb <= w[1].peak_kb),
        "{stages:?}"
    );
    assert!(stages[0].peak_kb > 1000.0, "{stages:?}");
    assert!(
        stages.iter().all(|s| s.resident_kb <= s.peak_kb),
        "{stages:?}"
    );
    // Saved: the first object's ka and nothing else, as the command
    // line's edit (the same edit engine) writes it.
    let copy = dir.path().join("copy.xml");
    std::fs::write(&copy, &text).unwrap();
    let edit = std::process::Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .args(["edit", "--set", "object[1].material.ka=0.25"])
        .arg(&copy)
        .status()
        .unwrap();
    assert!(edit.success());
    let saved = std::fs::read_to_string(&path).unwrap();
    assert_ne!(saved, text);
    assert_eq!(saved, std::fs::read_to_string(&copy).unwrap());
}

/// A save of a large scene, on a thread of its own as the app saves,
/// leaves nothing behind: the allocator gives back the blocks the save
/// freed instead of its thread's arena keeping them for a next time that
/// does not come (`src/system/allocator.rs`). 200 000 spheres (43 MB): the save
/// left 6.4–7.0 MB resident with glibc's own threshold; with the threshold
/// fixed, 0.8–1.9 MB, and 5–6 MB one run in three (a few live bytes above
/// the freed blocks keep them); given back as the save ends, resident
/// memory is 0.8–7.5 MB lower after the save than before it (30 runs,
/// half of them beside two busy cores).
#[test]
fn a_save_of_a_large_scene_leaves_little_behind() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("spheres.xml");
    let mut text = String::from("<scene>\n");
    for i in 0..200_000 {
        text.push_str(&format!(
            "  <sphere><color red=\"0.{:03}\" green=\"0.5\" blue=\"0.25\"/>\
             <material ka=\"0.2\" kd=\"0.6\" ks=\"0.4\" m=\"30\"/>\
             <transformation><scale factor=\"0.2\"/>\
             <translate x=\"{:.4}\" y=\"0.8\" z=\"{:.4}\"/></transformation></sphere>\n",
            i % 1000,
            (i % 997) as f64 * 3.7 - 1800.0,
            (i / 997) as f64 * 17.3,
        ));
    }
    text.push_str("  <light x=\"-10\" y=\"-20\" z=\"-10\"/>\n");
    text.push_str("  <camera width=\"32\" height=\"24\" eyeDistance=\"2\"/>\n</scene>\n");
    std::fs::write(&path, &text).unwrap();
    let stages = app_document(&path, &[]);
    let resident = |name: &str| stages.iter().find(|s| s.name == name).unwrap().resident_kb;
    let kept = resident("after a save") - resident("after an edit");
    assert!(kept < 500.0, "the save left {kept} kB behind: {stages:?}");
}

/// Edits journaled before a crash, restored onto the file they were made
/// on, need no base: the document takes them as it is, one undo step (a
/// million objects' base was read and parsed again, and the app peaked at
/// 3.3× the file). Onto a file changed since, the base is read and the
/// edits merged with the change.
#[test]
fn restored_edits_read_their_base_only_when_the_file_changed() {
    let text = spheres_text(50);
    let (_dir, path, mut doc) = common::document_on(&text);
    let base_fingerprint = doc.file_fingerprint();
    let edits = [set("object[2].color.red", 0.75)];
    let red = |doc: &Document, n: usize| {
        Field::parse(&format!("object[{n}].color.red"))
            .unwrap()
            .get(doc.scene())
            .unwrap()
    };
    let read = std::cell::Cell::new(0);
    let base = || {
        read.set(read.get() + 1);
        Ok(text.clone())
    };
    assert_eq!(
        doc.restore(base_fingerprint, base, &edits),
        Ok(Reload::Unchanged)
    );
    assert_eq!(read.get(), 0, "the file is the base: not read");
    assert_eq!(red(&doc, 2), Value::Number(0.75));
    assert!(doc.has_unsaved_edits());
    assert_eq!(doc.undo().as_deref(), Some("restore 1 unsaved edit"));
    assert!(!doc.has_unsaved_edits());

    // Another program changed the file meanwhile.
    let theirs = text.replacen("green=\"0.1\"", "green=\"0.15\"", 1);
    assert_ne!(theirs, text);
    std::fs::write(&path, &theirs).unwrap();
    let mut doc = Document::open(&path).unwrap();
    let base = || {
        read.set(read.get() + 1);
        Ok(text.clone())
    };
    assert_eq!(
        doc.restore(base_fingerprint, base, &edits),
        Ok(Reload::Merged)
    );
    assert_eq!(read.get(), 1);
    assert_eq!(red(&doc, 2), Value::Number(0.75));
    let green = Field::parse("object[11].color.green").unwrap();
    assert_eq!(green.get(doc.scene()).unwrap(), Value::Number(0.15));
}
