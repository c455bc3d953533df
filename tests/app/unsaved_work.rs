//! Nothing the user wrote is lost or altered: undoing a reload
//! gives back the text before it byte for byte, and unsaved edits follow
//! their element by its identity when another program inserts, removes or
//! moves elements around it. Each defect found by hand first, then a
//! property test that interleaves another program's changes with the
//! app's edits and saves.

use crate::common;
use crate::util::{app_keeping, app_on, ka, parse, read, step_until};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use rayoflight::gui::app::RayOfLightApp;
use rayoflight::math::TransformStep;
use rayoflight::scene;
use rayoflight::scene::edit::{Coef, Edit, Field, Item, Value};
use rayoflight::scene::merge::Choice;
use rayoflight::session::document::{Document, Reload, SaveError};
use rayoflight::session::preview::RenderState;
use rayoflight::session::settings::Persisted;
use rayoflight::session::watcher::{FileEvent, SceneWatcher};

/// The example scene (`scenes/example.xml`) with comments above and inside
/// the light, and a number spelled `-2.0e0`.
const EXAMPLE: &str = r#"<?xml version="1.0"?>
<scene>
<!-- big green ball -->
<sphere>
 <color red="0.2" green="0.8" blue="0.2"/>
 <material ka="0.3" kd="0.3" ks="0.3" m="20"/>
 <transformation>
  <translate x="2" y="0" z="-2"/>
 </transformation>
</sphere>
<!-- small red ball -->
<sphere>
 <color red="1.0" green="0.2" blue="0.0"/>
 <material ka="0.4" kd="0.5" ks="0.3" m="1"/>
 <transformation>
  <translate x="-2" y="0" z="-2"/>
 </transformation>
</sphere>
<!-- the only light -->
<light x="1" y="-4" z="-2.0e0">
 <!-- white, full strength -->
 <color red="1.0" green="1.0" blue="1.0"/>
</light>
<camera width="60" height="60" eyeDistance="4">
  <transformation>
   <translate x="0" y="0" z="-20"/>
 </transformation>
</camera>
<model type="whitted" depth="2"/>
</scene>
"#;

/// Another program writes `text`; the watcher hands it to the document.
fn they_write(doc: &mut Document, path: &Path, text: &str) -> Reload {
    std::fs::write(path, text).unwrap();
    doc.file_loaded(text.to_owned(), parse(text))
}

#[test]
fn undoing_a_reload_gives_back_the_text_byte_for_byte() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut doc = Document::open(&path).unwrap();
    // sed -i 's/light x="1"/light x="5"/'
    let theirs = EXAMPLE.replace(r#"light x="1""#, r#"light x="5""#);
    assert_eq!(they_write(&mut doc, &path, &theirs), Reload::Replaced);
    assert_eq!(doc.scene().lights[0].position.x, 5.0);
    assert_eq!(doc.undo().as_deref(), Some("reload from disk"));
    assert!(doc.has_unsaved_edits());
    doc.save().unwrap();
    assert_eq!(read(&path), EXAMPLE, "Ctrl+Z, Ctrl+S: the text before");
    // Redo brings the other program's text back, and saves it as it was.
    assert_eq!(doc.redo().as_deref(), Some("reload from disk"));
    doc.save().unwrap();
    assert_eq!(read(&path), theirs);
}

#[test]
fn undoing_another_programs_removals_restores_their_text_in_place() {
    let red = "<!-- small red ball -->\n<sphere>\n <color red=\"1.0\" green=\"0.2\" blue=\"0.0\"/>\n <material ka=\"0.4\" kd=\"0.5\" ks=\"0.3\" m=\"1\"/>\n <transformation>\n  <translate x=\"-2\" y=\"0\" z=\"-2\"/>\n </transformation>\n</sphere>\n";
    let light = "<!-- the only light -->\n<light x=\"1\" y=\"-4\" z=\"-2.0e0\">\n <!-- white, full strength -->\n <color red=\"1.0\" green=\"1.0\" blue=\"1.0\"/>\n</light>\n";
    assert!(EXAMPLE.contains(red) && EXAMPLE.contains(light));
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut doc = Document::open(&path).unwrap();
    let without_red = EXAMPLE.replace(red, "");
    assert_eq!(they_write(&mut doc, &path, &without_red), Reload::Replaced);
    let without_both = without_red.replace(light, "");
    assert_eq!(they_write(&mut doc, &path, &without_both), Reload::Replaced);
    assert_eq!(doc.undo().as_deref(), Some("reload from disk"));
    doc.save().unwrap();
    assert_eq!(read(&path), without_red, "the light back where it was");
    assert_eq!(doc.undo().as_deref(), Some("reload from disk"));
    doc.save().unwrap();
    assert_eq!(read(&path), EXAMPLE, "the sphere back with its comment");
}

#[test]
fn undoing_a_merge_and_a_revert_gives_back_their_texts() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut doc = Document::open(&path).unwrap();
    doc.apply(Edit::Set(ka(1), Value::Number(0.9))).unwrap();
    let theirs = EXAMPLE.replace("<!-- the only light -->", "<!-- the key light -->");
    assert_eq!(they_write(&mut doc, &path, &theirs), Reload::Merged);
    assert!(doc.has_unsaved_edits());
    // Undo the merge, then the edit: the text first read, unsaved against
    // the other program's.
    assert_eq!(doc.undo().as_deref(), Some("merge with the file's changes"));
    assert_eq!(doc.scene().objects[1].material.ka, 0.9);
    assert!(doc.undo().is_some());
    assert!(doc.has_unsaved_edits(), "the file holds the other text");
    doc.save().unwrap();
    assert_eq!(read(&path), EXAMPLE);

    // Revert, then undo it: the edits come back on the same text.
    doc.apply(Edit::Set(ka(0), Value::Number(0.7))).unwrap();
    doc.revert();
    assert!(!doc.has_unsaved_edits());
    assert_eq!(doc.undo().as_deref(), Some("revert edits"));
    assert_eq!(doc.scene().objects[0].material.ka, 0.7);
    doc.save().unwrap();
    assert_eq!(read(&path), EXAMPLE.replace(r#"ka="0.3""#, r#"ka="0.7""#));
}

#[test]
fn an_edit_stays_on_its_object_when_another_program_inserts_above() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut doc = Document::open(&path).unwrap();
    assert_eq!(doc.object_label(0), "#1 big green ball sphere");
    doc.apply(Edit::Set(ka(0), Value::Number(0.9))).unwrap();
    let new = "<!-- a newcomer -->\n<sphere/>\n";
    let theirs = EXAMPLE.replacen(
        "<!-- big green ball -->",
        &format!("{new}<!-- big green ball -->"),
        1,
    );
    assert_eq!(they_write(&mut doc, &path, &theirs), Reload::Merged);
    assert_eq!(doc.object_label(1), "#2 big green ball sphere");
    doc.save().unwrap();
    let expected = theirs.replacen(r#"ka="0.3""#, r#"ka="0.9""#, 1);
    assert_eq!(read(&path), expected, "ka on the green ball, nothing else");
}

#[test]
fn an_edit_on_an_object_another_program_removed_is_a_conflict() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut doc = Document::open(&path).unwrap();
    doc.apply(Edit::Set(ka(0), Value::Number(0.9))).unwrap();
    let green_end = EXAMPLE.find("<!-- small red ball -->").unwrap();
    let green_start = EXAMPLE.find("<!-- big green ball -->").unwrap();
    let theirs = format!("{}{}", &EXAMPLE[..green_start], &EXAMPLE[green_end..]);
    assert_eq!(they_write(&mut doc, &path, &theirs), Reload::Conflict);
    let conflicts = doc.conflict().unwrap().conflicts();
    assert_eq!(conflicts.len(), 1);
    assert!(conflicts[0].theirs.contains("gone"), "{:?}", conflicts[0]);
    assert!(!conflicts[0].can_keep_yours);
    // "Keep all of mine" cannot put it anywhere: the file is theirs.
    doc.resolve(&[Choice::Mine]).unwrap();
    doc.save().unwrap();
    assert_eq!(
        read(&path),
        theirs,
        "no edit landed on the plane or the red ball"
    );
}

#[test]
fn edits_follow_their_light_and_object_across_a_reordering() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut doc = Document::open(&path).unwrap();
    doc.apply(Edit::Set(ka(1), Value::Number(0.25))).unwrap();
    // Another program puts the red ball first.
    let green = &EXAMPLE[EXAMPLE.find("<!-- big green ball -->").unwrap()
        ..EXAMPLE.find("<!-- small red ball -->").unwrap()];
    let theirs = EXAMPLE.replace(green, "").replace(
        "<!-- the only light -->",
        &format!("{green}<!-- the only light -->"),
    );
    assert_eq!(they_write(&mut doc, &path, &theirs), Reload::Merged);
    doc.save().unwrap();
    let saved = parse(&read(&path));
    assert_eq!(
        saved.objects[0].material.ka, 0.25,
        "the red ball, now first"
    );
    assert_eq!(saved.objects[1].material.ka, 0.3, "the green one untouched");
}

// ----- the property: random changes from both sides -----

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A ball's marker: its x, which only its own block in the text sets.
fn marker(object: &scene::Object) -> i64 {
    match object.transform.steps().first() {
        Some(TransformStep::Translate(t)) => t.x as i64,
        other => panic!("no marker: {other:?}"),
    }
}

fn block(id: i64, red: f64) -> String {
    format!(
        "  <!-- ball {id} -->\n  <sphere>\n    <color red=\"{red}\" green=\"0.5\" blue=\"0.5\"/>\n    <material ka=\"0.1\" kd=\"0.5\"/>\n    <transformation><translate x=\"{id}\" z=\"9\"/></transformation>\n  </sphere>\n"
    )
}

/// The text's ball blocks (each sphere, from the start of its line or of
/// the comment line above it to the end of its end tag's line) and what
/// lies before and after them.
fn blocks(text: &str) -> (String, Vec<String>, String) {
    let mut starts = Vec::new();
    let mut end = None;
    let mut from = 0;
    while let Some(k) = text[from..].find("<sphere") {
        let at = from + k;
        let mut start = text[..at].rfind('\n').map_or(0, |n| n + 1);
        let above = text[..start.saturating_sub(1)]
            .rfind('\n')
            .map_or(0, |n| n + 1);
        if text[above..start].trim_start().starts_with("<!-- ball") {
            start = above;
        }
        starts.push(start);
        let close = at + text[at..].find("</sphere>").expect("spheres have children");
        let line_end = close
            + text[close..]
                .find('\n')
                .map_or(text.len() - close, |n| n + 1);
        end = Some(line_end);
        from = line_end;
    }
    let Some(end) = end else {
        let at = text.find("  <light").unwrap();
        return (text[..at].to_owned(), Vec::new(), text[at..].to_owned());
    };
    let list = starts
        .iter()
        .zip(starts.iter().skip(1).chain(std::iter::once(&end)))
        .map(|(a, b)| text[*a..*b].to_owned())
        .collect();
    (text[..starts[0]].to_owned(), list, text[end..].to_owned())
}

/// The marker of a ball's block.
fn block_marker(block: &str) -> i64 {
    let at = block.find("translate x=\"").unwrap() + "translate x=\"".len();
    let end = at + block[at..].find('"').unwrap();
    block[at..end].parse::<f64>().unwrap() as i64
}

/// Settles a conflict as a user would: their edit where it can still be
/// kept, the file's version where its element is gone.
fn settle(doc: &mut Document) {
    while let Some(pending) = doc.conflict() {
        let choices: Vec<Choice> = pending
            .conflicts()
            .iter()
            .map(rayoflight::scene::merge::Conflict::mine_if_possible)
            .collect();
        doc.resolve(&choices).unwrap();
    }
}

#[test]
fn random_changes_from_both_sides_keep_every_edit_on_its_element_and_undo_to_the_original() {
    let seed = std::env::var("RAYOFLIGHT_EDIT_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x0025_5eed_u64);
    let mut rng = Rng(seed);
    for round in 0..40 {
        eprintln!("-- round {round}");
        let context = format!("round {round}, seed {seed:#x}");
        let mut next_id = 1;
        let mut text = String::from("<scene>\n");
        for _ in 0..4 {
            text.push_str(&block(next_id, 0.5));
            next_id += 1;
        }
        text.push_str("  <light x=\"0\" y=\"-4\" z=\"-4\"/>\n  <camera width=\"8\" height=\"8\" eyeDistance=\"1\"/>\n</scene>\n");
        let original = text.clone();
        let (_dir, path) = common::scene_file("scene.xml", &text);
        let mut doc = Document::open(&path).unwrap();
        // What each ball's ka must be: the app's last edit of it, or as
        // written; a ball either side removed is gone.
        let mut truth: BTreeMap<i64, f64> = (1..next_id).map(|id| (id, 0.1)).collect();
        for _ in 0..30 {
            match rng.below(10) {
                // The app edits a ball's ka, or removes a ball.
                0..=4 => {
                    let objects = &doc.scene().objects;
                    if objects.is_empty() {
                        continue;
                    }
                    let n = rng.below(objects.len());
                    let id = marker(&objects[n]);
                    if rng.below(6) == 0 {
                        doc.apply(Edit::Remove(Item::Object(n))).unwrap();
                        eprintln!("app removes {id}");
                        truth.remove(&id);
                    } else {
                        let v = (rng.below(1000) as f64) / 1000.0;
                        doc.apply(Edit::Set(ka(n), Value::Number(v))).unwrap();
                        eprintln!("app sets ka of {id} to {v}");
                        truth.insert(id, v);
                    }
                }
                5 => match doc.save() {
                    Ok(_) | Err(SaveError::Conflict) => settle(&mut doc),
                    Err(e) => panic!("{context}: {e}"),
                },
                // The app undoes its last edit. (Undoing a reload or a
                // merge here would make the user's side move elements back,
                // which a merge replays as a removal and an insertion, as
                // diff3 does: a ball the other program removes then comes
                // back. The end of each round undoes those too.)
                6 if doc
                    .undo_label()
                    .is_some_and(|l| !l.contains("reload") && !l.contains("merge")) =>
                {
                    eprintln!("app undoes {:?}", doc.undo());
                    // Start the truth again from the scene on screen.
                    truth = doc
                        .scene()
                        .objects
                        .iter()
                        .map(|o| (marker(o), o.material.ka))
                        .collect();
                }
                6 => {}
                // Another program inserts, removes, moves or recolours a
                // ball, keeping every other byte.
                _ => {
                    let disk = read(&path);
                    let (before, mut list, after) = blocks(&disk);
                    let op = rng.below(4);
                    if op == 0 || list.is_empty() {
                        let at = rng.below(list.len() + 1);
                        list.insert(at, block(next_id, 0.5));
                        truth.insert(next_id, 0.1);
                        next_id += 1;
                    } else if op == 1 {
                        let b = list.remove(rng.below(list.len()));
                        truth.remove(&block_marker(&b));
                    } else if op == 2 {
                        let b = list.remove(rng.below(list.len()));
                        let at = rng.below(list.len() + 1);
                        list.insert(at, b);
                    } else {
                        let k = rng.below(list.len());
                        let red = format!("red=\"0.{}\"", 1 + rng.below(9));
                        let start = list[k].find("red=\"").unwrap();
                        let end = start + list[k][start + 5..].find('"').unwrap() + 6;
                        list[k].replace_range(start..end, &red);
                    }
                    let new = format!("{before}{}{after}", list.concat());
                    eprintln!(
                        "they write (op {op}): {:?}",
                        they_write(&mut doc, &path, &new)
                    );
                    settle(&mut doc);
                }
            }
            let on_screen: BTreeMap<i64, f64> = doc
                .scene()
                .objects
                .iter()
                .map(|o| (marker(o), o.material.ka))
                .collect();
            assert_eq!(on_screen, truth, "{context}: every edit on its own ball");
        }
        match doc.save() {
            Ok(_) | Err(SaveError::Conflict) => settle(&mut doc),
            Err(e) => panic!("{context}: {e}"),
        }
        let saved: BTreeMap<i64, f64> = parse(&read(&path))
            .objects
            .iter()
            .map(|o| (marker(o), o.material.ka))
            .collect();
        assert_eq!(
            saved, truth,
            "{context}: the file holds every edit on its ball"
        );
        while doc.undo().is_some() {}
        doc.save().unwrap_or_else(|e| panic!("{context}: {e}"));
        assert_eq!(read(&path), original, "{context}: undoing everything");
    }
}

// ----- the file on disk -----

fn watch(path: &Path, doc: &Document) -> (mpsc::Receiver<FileEvent>, SceneWatcher) {
    let (tx, rx) = mpsc::channel();
    let watcher = SceneWatcher::new(path, doc.disk_fingerprint(), move |e| {
        let _ = tx.send(e);
    })
    .unwrap();
    (rx, watcher)
}

fn replace_atomically(path: &Path, text: &str) {
    let tmp = path.with_extension("part");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

#[test]
fn a_file_fixed_before_the_watch_starts_is_shown() {
    // Broken at launch, fixed (renamed into place) before the watcher
    // starts: no event and no later stamp tells; the watcher must start
    // from the bytes the document read.
    let (_dir, path) = common::scene_file("scene.xml", "<scene>\n  <sphere>\n");
    let doc = Document::open(&path).unwrap();
    assert!(doc.is_placeholder() && doc.error().is_some());
    replace_atomically(&path, EXAMPLE);
    let (rx, _watcher) = watch(&path, &doc);
    match rx.recv_timeout(Duration::from_secs(5)) {
        Ok(FileEvent::Loaded(read)) => assert_eq!(read.text, EXAMPLE),
        other => panic!("the fixed file is reported: {other:?}"),
    }

    // A good file replaced by another between the read and the watch.
    let doc = Document::open(&path).unwrap();
    let theirs = EXAMPLE.replace("depth=\"2\"", "depth=\"3\"");
    replace_atomically(&path, &theirs);
    let (rx, _watcher) = watch(&path, &doc);
    match rx.recv_timeout(Duration::from_secs(5)) {
        Ok(FileEvent::Loaded(read)) => assert_eq!(read.text, theirs),
        other => panic!("the new file is reported: {other:?}"),
    }
    // The file as the document read it: nothing to report.
    let doc = Document::open(&path).unwrap();
    let (rx, _watcher) = watch(&path, &doc);
    assert!(
        rx.recv_timeout(Duration::from_millis(800)).is_err(),
        "no report of what the document has"
    );
}

#[test]
fn saving_over_a_fifo_refuses_at_once_and_the_good_file_comes_back() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut doc = Document::open(&path).unwrap();
    doc.apply(Edit::Set(ka(0), Value::Number(0.9))).unwrap();
    std::fs::remove_file(&path).unwrap();
    let made = std::process::Command::new("mkfifo")
        .arg(&path)
        .status()
        .unwrap();
    assert!(made.success());
    let job = doc.save_job().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(job.run());
    });
    let outcome = rx
        .recv_timeout(Duration::from_secs(5))
        .expect("the save does not hang on the FIFO");
    let Err(e) = doc.save_done(doc.save_job().unwrap(), outcome) else {
        panic!("a FIFO is not written");
    };
    assert!(e.to_string().contains("is a FIFO"), "{e}");
    // The good file put back: the edit merges onto it and saves.
    std::fs::remove_file(&path).unwrap();
    let theirs = EXAMPLE.replace("depth=\"2\"", "depth=\"3\"");
    std::fs::write(&path, &theirs).unwrap();
    assert!(doc.has_unsaved_edits());
    doc.save().unwrap();
    assert_eq!(
        read(&path),
        theirs.replacen(r#"ka="0.3""#, r#"ka="0.9""#, 1)
    );
}

#[test]
fn rayoflight_stats_0_is_off() {
    use rayoflight::gui::app::stats_wanted;
    use std::ffi::OsStr;
    for off in [
        None,
        Some(""),
        Some("0"),
        Some("false"),
        Some("no"),
        Some("OFF"),
    ] {
        assert!(!stats_wanted(off.map(OsStr::new)), "{off:?}");
    }
    for on in ["1", "yes", "true", "on"] {
        assert!(stats_wanted(Some(OsStr::new(on))), "{on}");
    }
}

// ----- unsaved work outlives the process (item 3) -----

fn app_with_journal(doc: Document, journal: &Path) -> Harness<'static, RayOfLightApp> {
    let persisted = Persisted {
        journal: Some(journal.to_owned()),
        ..Persisted::in_memory()
    };
    app_keeping(doc, persisted)
}

/// Runs frames until `folder` holds `n` journal entries: an edit reaches
/// the journal within [`JOURNALED_WITHIN`]. The time it took.
fn until_entries(harness: &mut Harness<'_, RayOfLightApp>, folder: &Path, n: usize) -> Duration {
    step_until(harness, JOURNALED_WITHIN, "the journal", |_| {
        journal_entries(folder).len() == n
    })
}

/// How soon an edit is in the journal (the app writes it after a short
/// pause in the typing).
const JOURNALED_WITHIN: Duration = Duration::from_millis(1500);

/// Clicks the illumination model `model` in the panel (one edit), then
/// runs frames until the window's journal in `folder` holds it: what a
/// user has done before a crash. The time the journal took.
fn choose_model(harness: &mut Harness<'_, RayOfLightApp>, model: &str, folder: &Path) -> Duration {
    harness.get_by_label(model).click();
    harness.run_steps(1);
    until_entries(harness, folder, 1)
}

fn journal_entries(folder: &Path) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(folder)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    found.retain(|p| p.extension().is_some_and(|e| e == "json"));
    found
}

/// The app on `path` with its journal in `folder`: the illumination set
/// to lambert, the edit journaled, then the process dies (nothing runs at
/// exit).
fn crash_with_an_edit_journaled(path: &Path, folder: &Path) {
    let mut harness = app_with_journal(Document::open(path).unwrap(), folder);
    choose_model(&mut harness, "lambert", folder);
    crash(harness);
}

/// The app ends as a crash ends it: nothing of its own runs at exit (no
/// question, no save, no removal of its journal); what the system does
/// for any process that ends happens — its lock on its journal goes.
/// (Dropping the app stops its threads and waits for them.)
fn crash(harness: Harness<'static, RayOfLightApp>) {
    drop(harness);
}

fn status_says(harness: &Harness<'_, RayOfLightApp>, words: &str) -> bool {
    harness.query_by_label_contains(words).is_some()
}

/// A journal folder that another user owns, or that
/// others may write in, is not used: edits planted there are never
/// restored (so never saved into the scene by Ctrl+S), and the status
/// says why. The same folder made the user's own again gives them back.
#[cfg(unix)]
#[test]
fn a_journal_folder_others_may_write_is_not_used() {
    use std::os::unix::fs::PermissionsExt;
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let state = dir.path().join("state");
    let folder = Persisted::in_homes(None, Some(&state)).journal.unwrap();
    assert_eq!(folder, state.join("rayoflight/journal"));
    // A journal written as the app writes one: the edit it holds is what
    // another user would plant.
    crash_with_an_edit_journaled(&path, &folder);
    let set_mode =
        |m: u32| std::fs::set_permissions(&folder, std::fs::Permissions::from_mode(m)).unwrap();
    set_mode(0o777);
    let root = common::is_root();
    if root {
        std::os::unix::fs::chown(&folder, Some(65534), Some(65534)).unwrap();
    }
    let persisted = Persisted::in_homes(None, Some(&state));
    assert_eq!(persisted.journal, None);
    let why = match root {
        true => format!(
            "unsaved edits journal off: {}: not used: it is another user's (uid 65534), not yours",
            folder.display()
        ),
        false => format!(
            "unsaved edits journal off: {}: not used: others may write in it (mode 777)",
            folder.display()
        ),
    };
    assert_eq!(persisted.refused, std::slice::from_ref(&why));
    let harness = app_keeping(Document::open(&path).unwrap(), persisted);
    assert!(!harness.state().document().has_unsaved_edits());
    assert!(status_says(&harness, &why), "the status says why");
    assert!(!status_says(&harness, "restored"));
    drop(harness);

    // The user's own again: the journal is used.
    if root {
        std::os::unix::fs::chown(&folder, Some(0), Some(0)).unwrap();
    }
    set_mode(0o700);
    let persisted = Persisted::in_homes(None, Some(&state));
    assert!(persisted.refused.is_empty(), "{:?}", persisted.refused);
    let harness = app_keeping(Document::open(&path).unwrap(), persisted);
    assert!(harness.state().document().has_unsaved_edits());
    assert_eq!(read(&path), EXAMPLE);
}

#[test]
fn unsaved_edits_are_journaled_and_restored_after_a_crash() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("state/rayoflight/journal");
    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(
        journal_entries(&folder).is_empty(),
        "nothing unsaved, no journal"
    );
    let took = choose_model(&mut harness, "lambert", &folder);
    eprintln!("edit to journal: {took:?}");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&folder), 0o700);
        for f in std::fs::read_dir(&folder).unwrap().flatten() {
            assert_eq!(mode(&f.path()), 0o600, "{}", f.path().display());
        }
    }
    // The process dies: nothing runs at exit.
    crash(harness);
    assert_eq!(read(&path), EXAMPLE, "the file is never written unasked");

    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    let doc = harness.state().document();
    assert!(doc.has_unsaved_edits());
    assert_eq!(doc.scene().model.illumination, scene::Illumination::Lambert);
    assert!(
        status_says(&harness, "restored 1 unsaved edit from"),
        "the status says so"
    );
    assert!(status_says(&harness, "Ctrl+S saves, Ctrl+Z undoes"));
    // Ctrl+S writes only the edit, and the journal goes.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    step_until(&mut harness, Duration::from_secs(10), "the save", |app| {
        !app.is_saving() && !app.document().has_unsaved_edits()
    });
    assert_eq!(
        read(&path),
        EXAMPLE.replace(r#"type="whitted""#, r#"type="lambert""#)
    );
    step_until(
        &mut harness,
        Duration::from_secs(2),
        "the journal removed",
        |_| journal_entries(&folder).is_empty(),
    );

    // An edit undone: nothing unsaved, no journal.
    choose_model(&mut harness, "phong", &folder);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    step_until(
        &mut harness,
        Duration::from_secs(2),
        "the journal removed",
        |_| journal_entries(&folder).is_empty(),
    );
}

#[test]
fn restored_edits_merge_with_a_file_changed_meanwhile() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    crash_with_an_edit_journaled(&path, &folder);
    // Another program inserts a sphere and moves the light meanwhile.
    let theirs = EXAMPLE
        .replace(r#"light x="1""#, r#"light x="7""#)
        .replacen(
            "<!-- big green ball -->",
            "<sphere/>\n<!-- big green ball -->",
            1,
        );
    std::fs::write(&path, &theirs).unwrap();

    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(status_says(&harness, "merged with the file's changes"));
    let s = harness.state().document().scene().clone();
    assert_eq!(s.model.illumination, scene::Illumination::Lambert);
    assert_eq!(s.lights[0].position.x, 7.0);
    assert_eq!(s.objects.len(), 3);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    step_until(&mut harness, Duration::from_secs(10), "the save", |app| {
        !app.is_saving() && !app.document().has_unsaved_edits()
    });
    assert_eq!(
        read(&path),
        theirs.replace(r#"type="whitted""#, r#"type="lambert""#)
    );

    // A conflict: both changed the model.
    choose_model(&mut harness, "phong", &folder);
    crash(harness);
    let ambient = read(&path).replace(r#"type="lambert""#, r#"type="ambient""#);
    std::fs::write(&path, &ambient).unwrap();
    let harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    let doc = harness.state().document();
    assert!(doc.conflict().is_some(), "the usual question");
    assert!(status_says(&harness, "choose what to keep"));
    assert_eq!(read(&path), ambient, "nothing written before the answer");
}

#[test]
fn a_damaged_journal_is_set_aside_with_a_notice() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    crash_with_an_edit_journaled(&path, &folder);
    // Cut short, as by a full disk.
    let entry = journal_entries(&folder).remove(0);
    let text = std::fs::read_to_string(&entry).unwrap();
    std::fs::write(&entry, &text[..text.len() - 20]).unwrap();
    let harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(!harness.state().document().has_unsaved_edits());
    assert!(status_says(&harness, "is damaged"));
    assert!(journal_entries(&folder).is_empty());
    assert!(
        std::fs::read_dir(&folder)
            .unwrap()
            .flatten()
            .any(|f| f.file_name().to_string_lossy().ends_with(".json.damaged")),
        "kept aside, not lost"
    );
    // Another file of the same name elsewhere never gets it.
    let (_other_dir, other) = common::scene_file("scene.xml", EXAMPLE);
    let harness = app_with_journal(Document::open(&other).unwrap(), &folder);
    assert!(!harness.state().document().has_unsaved_edits());
}

#[test]
fn a_camera_brought_back_to_the_files_leaves_its_text_alone() {
    let text = EXAMPLE.replace(
        r#"<translate x="0" y="0" z="-20"/>"#,
        r#"<translate y="-3" z="-8"/>"#,
    );
    let (_dir, path) = common::scene_file("scene.xml", &text);
    let mut doc = Document::open(&path).unwrap();
    let home = doc.scene().camera.transform.steps().to_vec();
    // An orbit, then Home, then another value.
    let orbit = vec![
        TransformStep::RotateY(0.5),
        TransformStep::Translate(glam::DVec3::new(-4.0, -3.0, -7.0)),
    ];
    doc.apply(Edit::Transform(
        rayoflight::scene::edit::Owner::Camera,
        orbit,
    ))
    .unwrap();
    doc.apply(Edit::Transform(
        rayoflight::scene::edit::Owner::Camera,
        home,
    ))
    .unwrap();
    doc.apply(Edit::Set(ka(1), Value::Number(0.25))).unwrap();
    doc.save().unwrap();
    assert_eq!(
        read(&path),
        text.replacen(r#"ka="0.4""#, r#"ka="0.25""#, 1),
        "only ka changed"
    );
}

/// A scene of `n` small spheres in a grid, seen by a small camera.
fn many_spheres(n: usize) -> String {
    let side = (n as f64).sqrt().ceil() as usize;
    let mut text = String::from("<scene>\n");
    for i in 0..n {
        let (x, y) = ((i % side) as f64, (i / side) as f64);
        text.push_str(&format!(
            "<sphere><transformation><scale factor=\"0.3\"/><translate x=\"{}\" y=\"{}\" z=\"{}\"/></transformation></sphere>\n",
            x - side as f64 / 2.0,
            y - side as f64 / 2.0,
            side as f64
        ));
    }
    text.push_str("<light x=\"0\" y=\"-5\" z=\"-5\"/>\n<camera width=\"64\" height=\"48\" eyeDistance=\"1\"/>\n<model type=\"phong\"/>\n</scene>\n");
    text
}

fn until_done(harness: &mut Harness<'_, RayOfLightApp>, limit: Duration) {
    step_until(harness, limit, "the picture", |app| {
        matches!(app.preview().state(), RenderState::Done { .. })
    });
}

#[test]
fn esc_before_the_first_pixels_says_cancelled_and_f5_renders_again() {
    let (_dir, path) = common::scene_file("scene.xml", &many_spheres(200_000));
    let mut harness = app_on(Document::open(&path).unwrap());
    until_done(&mut harness, Duration::from_secs(60));
    let before = harness.state().preview().image().clone();
    // An edit, and Esc while the scene is being prepared again: no pixel
    // of the new scene has come yet.
    harness.get_by_label("lambert").click();
    harness.run_steps(1);
    assert_eq!(harness.state().preview().state(), &RenderState::Waiting);
    harness.key_press(egui::Key::Escape);
    harness.run_steps(2);
    assert_eq!(harness.state().preview().state(), &RenderState::Cancelled);
    assert!(status_says(&harness, "cancelled (Esc)"));
    assert!(status_says(&harness, "F5 renders again"));
    // Nothing renders by itself, and nothing says "done".
    std::thread::sleep(Duration::from_millis(1500));
    harness.run_steps(3);
    assert_eq!(harness.state().preview().state(), &RenderState::Cancelled);
    assert_eq!(harness.state().preview().image(), &before);
    // F5: the scene on screen, as the CLI renders it.
    harness.key_press(egui::Key::F5);
    harness.run_steps(1);
    until_done(&mut harness, Duration::from_secs(60));
    let scene = harness.state().document().scene().clone();
    let expected =
        rayoflight::render::render(&scene, &rayoflight::render::auto(&scene).options).unwrap();
    assert_eq!(harness.state().preview().image(), &expected);
}

#[test]
fn a_pick_waiting_for_a_cancelled_render_is_dropped_with_a_notice() {
    let (_dir, path) = common::scene_file("scene.xml", &many_spheres(200_000));
    let mut harness = app_on(Document::open(&path).unwrap());
    until_done(&mut harness, Duration::from_secs(60));
    // An edit, a pick while the scene is prepared again (it waits for
    // the worker), then Esc before the worker has prepared it: no render
    // will, so the pick must not wait (and repaint) for ever. A sphere
    // more: the hierarchy of 200 000 is built again (a change of the
    // model alone is prepared within the frame, before the pick).
    harness.get_by_label("+ sphere").click();
    harness.run_steps(1);
    assert_eq!(harness.state().preview().state(), &RenderState::Waiting);
    harness.state_mut().pick(32.0, 24.0);
    harness.run_steps(1);
    assert!(harness.state().waits_for_the_worker());
    harness.key_press(egui::Key::Escape);
    harness.run_steps(2);
    assert_eq!(harness.state().preview().state(), &RenderState::Cancelled);
    assert!(!harness.state().waits_for_the_worker(), "dropped");
    assert!(status_says(&harness, "nothing picked"));
    // F5 renders again, and a pick is made in the new picture.
    harness.key_press(egui::Key::F5);
    harness.run_steps(1);
    until_done(&mut harness, Duration::from_secs(60));
    harness.state_mut().pick(32.0, 24.0);
    harness.run_steps(1);
    assert!(!harness.state().waits_for_the_worker());
}

#[test]
fn esc_closes_the_help_and_o_hides_the_overlays() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut harness = app_on(Document::open(&path).unwrap());
    until_done(&mut harness, Duration::from_secs(30));
    harness.key_press(egui::Key::F1);
    harness.run_steps(2);
    assert!(harness.query_by_label("Keys and mouse").is_some());
    harness.key_press(egui::Key::Escape);
    harness.run_steps(2);
    assert!(
        harness.query_by_label("Keys and mouse").is_none(),
        "Esc closed it"
    );
    assert!(harness.state().light_marker(0).is_some(), "a marker drawn");
    harness.key_press(egui::Key::O);
    harness.run_steps(2);
    assert!(!harness.state().overlays_shown());
    assert!(harness.state().light_marker(0).is_none(), "no marker");
    harness.key_press(egui::Key::O);
    harness.run_steps(2);
    assert!(harness.state().light_marker(0).is_some());
}

#[test]
fn a_large_file_opens_beside_the_window_and_esc_stops_waiting() {
    let text = many_spheres(60_000);
    assert!(text.len() as u64 >= rayoflight::session::BACKGROUND_BYTES);
    let (_dir, path) = common::scene_file("scene.xml", &text);
    let mut harness = app_on(Document::empty());
    // Esc while it loads: the window stops waiting; the late result is
    // dropped.
    harness
        .state_mut()
        .run(rayoflight::gui::app::Command::OpenFile(path.clone()));
    harness.run_steps(1);
    assert!(harness.state().is_loading(), "the window did not wait");
    assert!(harness.state().document().path().is_none());
    assert!(status_says(&harness, "Esc stops"));
    harness.key_press(egui::Key::Escape);
    harness.run_steps(2);
    assert!(!harness.state().is_loading());
    assert!(status_says(&harness, "stopped opening"));
    std::thread::sleep(Duration::from_secs(3));
    harness.run_steps(3);
    assert!(harness.state().document().path().is_none(), "dropped");
    // Again, waited for: the scene comes.
    harness
        .state_mut()
        .run(rayoflight::gui::app::Command::OpenFile(path.clone()));
    harness.run_steps(1);
    assert!(harness.state().is_loading());
    step_until(
        &mut harness,
        Duration::from_secs(30),
        "the file opened",
        |app| !app.is_loading(),
    );
    let doc = harness.state().document();
    assert_eq!(doc.path(), Some(path.as_path()));
    assert_eq!(doc.scene().objects.len(), 60_000);
}

#[test]
fn the_status_says_reading_while_a_large_changed_file_is_read() {
    let text = many_spheres(60_000);
    let (_dir, path) = common::scene_file("scene.xml", &text);
    let doc = Document::open(&path).unwrap();
    let (rx, _watcher) = watch(&path, &doc);
    let theirs = text.replace("<model type=\"phong\"/>", "<model type=\"lambert\"/>");
    replace_atomically(&path, &theirs);
    match rx.recv_timeout(Duration::from_secs(10)) {
        Ok(FileEvent::Reading) => {}
        other => panic!("reading first: {other:?}"),
    }
    // A second notification of the same replacement (a loaded machine
    // sees the rename and the attribute change apart) says "reading"
    // again; then comes what it read.
    loop {
        match rx.recv_timeout(Duration::from_secs(20)) {
            Ok(FileEvent::Reading) => {}
            Ok(FileEvent::Loaded(read)) => break assert_eq!(read.text, theirs),
            other => panic!("then what it read: {other:?}"),
        }
    }
}

#[test]
fn a_load_says_how_far_it_has_got() {
    let (_dir, path) = common::scene_file("scene.xml", &many_spheres(60_000));
    let progress = std::sync::Arc::new(scene::LoadProgress::default());
    let seen = std::thread::scope(|s| {
        let loader = s.spawn(|| scene::load_counting(&path, &[], Some(&progress)));
        let mut seen = Vec::new();
        while !loader.is_finished() {
            seen.push(progress.fraction());
            std::thread::sleep(Duration::from_millis(2));
        }
        assert_eq!(loader.join().unwrap().unwrap().scene.objects.len(), 60_000);
        seen
    });
    assert!(seen.windows(2).all(|w| w[0] <= w[1]), "it only goes up");
    assert!(
        seen.iter().any(|f| *f > 0.0 && *f < 1.0),
        "something between: {seen:?}"
    );
    assert_eq!(progress.fraction(), 1.0);
}

#[test]
fn the_app_says_reading_while_a_large_changed_file_is_read() {
    let text = many_spheres(60_000);
    let (_dir, path) = common::scene_file("scene.xml", &text);
    let mut harness = app_on(Document::open(&path).unwrap());
    until_done(&mut harness, Duration::from_secs(60));
    let theirs = text.replace("<model type=\"phong\"/>", "<model type=\"lambert\"/>");
    replace_atomically(&path, &theirs);
    let start = Instant::now();
    while !status_says(&harness, "reading it") {
        assert!(start.elapsed() < Duration::from_secs(10), "reading shown");
        harness.step();
        std::thread::sleep(Duration::from_millis(2));
    }
    step_until(
        &mut harness,
        Duration::from_secs(20),
        "the new file",
        |app| app.document().scene().model.illumination == scene::Illumination::Lambert,
    );
    harness.run_steps(2);
    assert!(!status_says(&harness, "reading it"));
    assert!(status_says(&harness, "watching, saved"));
}

#[test]
fn an_idle_window_says_idle_not_a_stale_frame_rate() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut harness = app_on(Document::open(&path).unwrap());
    until_done(&mut harness, Duration::from_secs(30));
    for _ in 0..10 {
        harness.step();
    }
    assert!(status_says(&harness, " fps"), "frames drawn: a rate");
    // No frame for over a second, then the one the app asked for.
    std::thread::sleep(Duration::from_millis(1200));
    harness.step();
    assert!(!status_says(&harness, " fps"), "no stale rate");
    assert!(harness.query_by_label("idle").is_some());
}

#[test]
fn discarding_the_edits_removes_their_journal() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    choose_model(&mut harness, "lambert", &folder);
    // Open the built-in example, and answer "Discard edits".
    harness
        .state_mut()
        .run(rayoflight::gui::app::Command::OpenBuiltin);
    harness.run_steps(2);
    harness.get_by_label("Discard edits").click();
    harness.run_steps(2);
    step_until(
        &mut harness,
        Duration::from_secs(2),
        "the journal removed",
        |_| journal_entries(&folder).is_empty(),
    );
    assert_eq!(read(&path), EXAMPLE);
    // Nothing comes back on the next start.
    let harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(!harness.state().document().has_unsaved_edits());
}

/// The selection stays on the object the user selected when another
/// program changes the file: a sphere inserted above it moves it down the
/// list, and the selection (and the panel's editor, and so the next edit)
/// goes with it; an object the other program removed is no longer
/// selected, rather than its neighbour. (The selection was a number: after
/// an insertion above, it named another object, and a panel edit went to
/// that one.) Unsaved edits merged onto the change keep it too.
#[test]
fn the_selection_follows_its_object_through_another_programs_change() {
    let sphere = |name: &str, z: f64| {
        format!(
            "  <!-- {name} -->\n  <sphere><transformation><translate z=\"{z}\"/></transformation></sphere>\n"
        )
    };
    let tail = "  <light x=\"0\" y=\"-3\" z=\"-3\"/>\n  <camera width=\"16\" height=\"12\" eyeDistance=\"2\"/>\n</scene>\n";
    let text = format!(
        "<scene>\n{}{}{}{tail}",
        sphere("RED", 3.0),
        sphere("GREEN", 4.0),
        sphere("BLUE", 5.0)
    );
    let (_dir, path) = common::scene_file("scene.xml", &text);
    let mut harness = app_on(Document::open(&path).unwrap());
    until_done(&mut harness, Duration::from_secs(30));
    harness.get_by_label("#2 GREEN sphere").click();
    harness.run_steps(2);
    assert_eq!(harness.state().selected_object(), Some(1));
    assert!(harness.query_by_label("Edit #2 GREEN sphere").is_some());

    // Another program writes `text`; the app has taken it once its scene
    // holds `objects` objects.
    let theirs_with = |harness: &mut Harness<'_, RayOfLightApp>, text: &str, objects: usize| {
        replace_atomically(&path, text);
        step_until(
            harness,
            Duration::from_secs(10),
            "the file's change",
            |app| app.document().scene().objects.len() == objects,
        );
        harness.run_steps(2);
    };

    // Another program puts a sphere first.
    let theirs = text.replacen("<scene>\n", &format!("<scene>\n{}", sphere("NEW", 6.0)), 1);
    theirs_with(&mut harness, &theirs, 4);
    assert_eq!(
        harness.state().selected_object(),
        Some(2),
        "GREEN is #3 now"
    );
    assert!(harness.query_by_label("Edit #3 GREEN sphere").is_some());

    // An unsaved edit of GREEN, then another program inserts again: the
    // edit is merged onto the file's change, the selection still GREEN.
    harness.get_by_label("lambert").click();
    harness.run_steps(2);
    let theirs = theirs.replacen(
        "<scene>\n",
        &format!("<scene>\n{}", sphere("NEWER", 7.0)),
        1,
    );
    theirs_with(&mut harness, &theirs, 5);
    assert_eq!(
        harness.state().selected_object(),
        Some(3),
        "GREEN is #4 now"
    );

    // GREEN removed by the other program: nothing selected.
    theirs_with(
        &mut harness,
        &theirs.replacen(&sphere("GREEN", 4.0), "", 1),
        4,
    );
    assert_eq!(harness.state().selected_object(), None);
}

// ----- one journal per window, found by the file's identity -----

/// Selects the object labelled `object` in the list, then types `value`
/// over the panel's field that shows `old`, as a user does (the field
/// focused, its text selected, the new text typed, Enter).
fn type_value(harness: &mut Harness<'_, RayOfLightApp>, object: &str, old: f64, value: &str) {
    harness.get_by_label(object).click();
    harness.run_steps(2);
    let field =
        harness.get_by(move |node| node.numeric_value().is_some_and(|v| (v - old).abs() < 1e-9));
    field.focus();
    harness.run_steps(2);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    harness.run_steps(1);
    harness.get_by(|node| node.is_focused()).type_text(value);
    harness.run_steps(1);
    harness.key_press(egui::Key::Enter);
    harness.run_steps(2);
}

fn material(doc: &Document, object: usize, coef: Coef) -> f64 {
    let field = Field::Material { object, coef };
    match field.get(doc.scene()).unwrap() {
        Value::Number(v) => v,
        other => panic!("{other:?}"),
    }
}

/// Two windows on one file each keep their own
/// entry; both killed, the next start restores both windows' edits (the
/// one journal file held only the last window's: A's edit was lost).
#[test]
fn two_windows_on_one_file_both_keep_their_edits_through_a_crash() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    let mut a = app_with_journal(Document::open(&path).unwrap(), &folder);
    let mut b = app_with_journal(Document::open(&path).unwrap(), &folder);
    type_value(&mut a, "#2 small red ball sphere", 0.4, "0.61");
    assert_eq!(material(a.state().document(), 1, Coef::Ka), 0.61);
    until_entries(&mut a, &folder, 1);
    type_value(&mut b, "#2 small red ball sphere", 0.5, "0.71");
    assert_eq!(material(b.state().document(), 1, Coef::Kd), 0.71);
    until_entries(&mut b, &folder, 2);
    a.run_steps(2);
    assert_eq!(journal_entries(&folder).len(), 2, "one entry each");

    // A third window while both live takes nothing, and says why.
    let c = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(!c.state().document().has_unsaved_edits());
    assert!(status_says(
        &c,
        "another RayOfLight window has unsaved edits"
    ));
    drop(c);

    crash(a);
    crash(b);
    assert_eq!(read(&path), EXAMPLE);
    let mut d = app_with_journal(Document::open(&path).unwrap(), &folder);
    step_until(&mut d, Duration::from_secs(3), "both restored", |app| {
        material(app.document(), 1, Coef::Kd) == 0.71
    });
    let doc = d.state().document();
    assert_eq!(material(doc, 1, Coef::Ka), 0.61);
    assert!(status_says(&d, "restored 1 unsaved edit from"));
    assert!(status_says(&d, "restored 1 unsaved edit of another window"));
    // Both in one entry, this window's, and the dead windows' gone.
    until_entries(&mut d, &folder, 1);
    d.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    step_until(&mut d, Duration::from_secs(10), "the save", |app| {
        !app.is_saving() && !app.document().has_unsaved_edits()
    });
    assert_eq!(
        read(&path),
        EXAMPLE.replace(
            r#"<material ka="0.4" kd="0.5""#,
            r#"<material ka="0.61" kd="0.71""#
        )
    );
    until_entries(&mut d, &folder, 0);
}

/// A window opened on a file another window is
/// editing never takes that window's edits, and undoing its own removes
/// only its own entry; the first window's edit outlives its crash.
#[test]
fn a_window_never_takes_the_journal_of_a_window_still_open() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    let mut a = app_with_journal(Document::open(&path).unwrap(), &folder);
    type_value(&mut a, "#2 small red ball sphere", 0.4, "0.61");
    until_entries(&mut a, &folder, 1);
    let mut b = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(
        !b.state().document().has_unsaved_edits(),
        "A's edit stays A's"
    );
    b.get_by_label("lambert").click();
    b.run_steps(1);
    until_entries(&mut b, &folder, 2);
    b.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    until_entries(&mut b, &folder, 1);
    drop(b);
    crash(a);
    let harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    let doc = harness.state().document();
    assert_eq!(material(doc, 1, Coef::Ka), 0.61);
    assert_eq!(doc.scene().model.illumination, scene::Illumination::Whitted);
}

/// Two dead windows that set one value differently:
/// the restart asks, as for any conflict, and writes nothing until then;
/// the entries go once it is settled.
#[test]
fn two_dead_windows_that_changed_one_value_are_asked_about() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    let mut a = app_with_journal(Document::open(&path).unwrap(), &folder);
    let mut b = app_with_journal(Document::open(&path).unwrap(), &folder);
    a.get_by_label("lambert").click();
    a.run_steps(1);
    until_entries(&mut a, &folder, 1);
    b.get_by_label("phong").click();
    b.run_steps(1);
    until_entries(&mut b, &folder, 2);
    crash(a);
    crash(b);
    let mut c = app_with_journal(Document::open(&path).unwrap(), &folder);
    step_until(&mut c, Duration::from_secs(3), "the question", |app| {
        app.document().conflict().is_some()
    });
    c.run_steps(2);
    assert!(
        c.query_by_label("Two windows edited the same values")
            .is_some()
    );
    let doc = c.state().document();
    assert_eq!(doc.scene().model.illumination, scene::Illumination::Lambert);
    assert_eq!(
        journal_entries(&folder).len(),
        2,
        "nothing goes before the answer"
    );
    c.get_by_label("Keep all of the other window's").click();
    c.run_steps(2);
    assert!(c.state().document().conflict().is_none());
    assert_eq!(
        c.state().document().scene().model.illumination,
        scene::Illumination::Phong
    );
    until_entries(&mut c, &folder, 1);
    assert_eq!(read(&path), EXAMPLE);
}

/// The journal knows the file, not the path string: an
/// edit made through a link comes back at the real path; a file moved
/// since comes back at its new path; an unrelated file put at the old
/// path is not merged with them but asked about.
#[cfg(unix)]
#[test]
fn unsaved_edits_follow_their_file_through_links_and_moves() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    let link = dir.path().join("link.xml");
    std::os::unix::fs::symlink(&path, &link).unwrap();
    crash_with_an_edit_journaled(&link, &folder);
    let harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert_eq!(
        harness.state().document().scene().model.illumination,
        scene::Illumination::Lambert,
        "made through the link, found at the real path"
    );
    crash(harness);

    // Moved, then opened where it went.
    std::fs::create_dir(dir.path().join("moved")).unwrap();
    let moved = dir.path().join("moved/scene.xml");
    std::fs::rename(&path, &moved).unwrap();
    let harness = app_with_journal(Document::open(&moved).unwrap(), &folder);
    assert_eq!(
        harness.state().document().scene().model.illumination,
        scene::Illumination::Lambert
    );
    assert!(status_says(&harness, "(made at "));
    crash(harness);

    // A new, unrelated scene made at its old name.
    let other = EXAMPLE.replace(r#"depth="2""#, r#"depth="5""#);
    std::fs::write(&path, &other).unwrap();
    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    harness.run_steps(2);
    assert!(
        !harness.state().document().has_unsaved_edits(),
        "not merged unasked"
    );
    assert!(
        harness
            .query_by_label("Unsaved edits of another file")
            .is_some()
    );
    harness.get_by_label("Keep them for later").click();
    harness.run_steps(2);
    assert!(!harness.state().document().has_unsaved_edits());
    assert!(
        harness
            .query_by_label("Unsaved edits of another file")
            .is_none()
    );
    crash(harness);
    assert_eq!(read(&path), other);
    // The file they were made on, opened: restored without a question.
    let harness = app_with_journal(Document::open(&moved).unwrap(), &folder);
    assert_eq!(
        harness.state().document().scene().model.illumination,
        scene::Illumination::Lambert
    );
    crash(harness);
    // Asked again at the new file, restored onto it when the user says so.
    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    harness.run_steps(2);
    harness.get_by_label("Restore them onto this file").click();
    harness.run_steps(2);
    let s = harness.state().document().scene().clone();
    assert_eq!(s.model.illumination, scene::Illumination::Lambert);
    assert_eq!(s.model.depth, 5, "onto the file as it is");
}

/// A save that finished before the app was killed (its
/// entry not yet removed): the next start says the edits are in the file
/// already, not "restored … merged", and nothing is unsaved.
#[test]
fn edits_saved_before_a_crash_are_not_restored_again() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    crash_with_an_edit_journaled(&path, &folder);
    // The save's new file, renamed into place as the app saves.
    replace_atomically(
        &path,
        &EXAMPLE.replace(r#"type="whitted""#, r#"type="lambert""#),
    );
    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(!harness.state().document().has_unsaved_edits());
    assert!(status_says(&harness, "are in the file already"));
    assert!(!status_says(&harness, "restored"));
    assert!(
        harness
            .query_by_label("Unsaved edits of another file")
            .is_none()
    );
    until_entries(&mut harness, &folder, 0);
}

/// After the user settles a conflict, the selection
/// (the list, the panel, the next edit) is still the object it was, and
/// the dialog numbers the value as the file numbers it now. (The
/// selection was left on the number, which another program's insertion
/// above had given to another object.)
#[test]
fn the_selection_keeps_its_object_when_a_conflict_is_settled() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut harness = app_on(Document::open(&path).unwrap());
    type_value(&mut harness, "#2 small red ball sphere", 0.4, "0.11");
    assert_eq!(harness.state().selected_object(), Some(1));
    assert_eq!(material(harness.state().document(), 1, Coef::Ka), 0.11);
    // Another program puts a sphere above the red ball and sets its ka.
    let theirs = EXAMPLE
        .replacen(
            "<!-- small red ball -->",
            "<!-- blue ball -->\n<sphere/>\n<!-- small red ball -->",
            1,
        )
        .replace(r#"<material ka="0.4""#, r#"<material ka="0.22""#);
    replace_atomically(&path, &theirs);
    step_until(
        &mut harness,
        Duration::from_secs(10),
        "the conflict",
        |app| app.document().conflict().is_some(),
    );
    harness.run_steps(2);
    assert!(
        harness.query_by_label("object[3].material.ka").is_some(),
        "numbered as the file has it now"
    );
    harness.get_by_label("Keep all of mine").click();
    harness.run_steps(2);
    let doc = harness.state().document();
    assert!(doc.conflict().is_none());
    assert_eq!(material(doc, 2, Coef::Ka), 0.11);
    assert_eq!(
        harness.state().selected_object(),
        Some(2),
        "still the red ball"
    );
    assert!(
        harness
            .query_by_label("Edit #3 small red ball sphere")
            .is_some()
    );
    // The next edit goes to it too.
    type_value(&mut harness, "#3 small red ball sphere", 0.5, "0.52");
    assert_eq!(material(harness.state().document(), 2, Coef::Kd), 0.52);
    assert_eq!(
        material(harness.state().document(), 1, Coef::Kd),
        parse(&theirs).objects[1].material.kd,
        "the blue ball untouched"
    );
}

/// Undoing a restore that was merged
/// with another program's change gives the file back as it opened, in one
/// step. (It took two, and the second left an "unsaved edit" that put the
/// other program's value back to the old one, which Ctrl+S would write.)
#[test]
fn undoing_a_restore_merged_with_the_files_change_gives_the_file_back() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let folder = dir.path().join("journal");
    crash_with_an_edit_journaled(&path, &folder);
    let theirs = EXAMPLE.replace(r#"<material ka="0.4""#, r#"<material ka="0.6""#);
    std::fs::write(&path, &theirs).unwrap();
    let mut harness = app_with_journal(Document::open(&path).unwrap(), &folder);
    assert!(status_says(&harness, "merged with the file's changes"));
    let doc = harness.state().document();
    assert_eq!(doc.scene().model.illumination, scene::Illumination::Lambert);
    assert_eq!(material(doc, 1, Coef::Ka), 0.6);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.run_steps(2);
    let doc = harness.state().document();
    assert!(!doc.has_unsaved_edits(), "{:?}", doc.unsaved_edits());
    assert_eq!(doc.scene(), &parse(&theirs));
    until_entries(&mut harness, &folder, 0);
}

/// A value typed a key at a time is one undo step,
/// ended by Enter (typing "0.19" over 0.4 left three); and every Ctrl+Z
/// press is one step, however fast they come (five in one frame, as a
/// held key repeats, undid one).
#[test]
fn a_typed_value_is_one_step_and_every_undo_press_counts() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut harness = app_on(Document::open(&path).unwrap());
    harness.get_by_label("#2 small red ball sphere").click();
    harness.run_steps(2);
    harness
        .get_by(|node| node.numeric_value().is_some_and(|v| (v - 0.4).abs() < 1e-9))
        .focus();
    harness.run_steps(2);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    harness.run_steps(1);
    for key in ["0", ".", "1", "9"] {
        harness.get_by(|node| node.is_focused()).type_text(key);
        harness.run_steps(1);
    }
    harness.key_press(egui::Key::Enter);
    harness.run_steps(2);
    assert_eq!(material(harness.state().document(), 1, Coef::Ka), 0.19);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.run_steps(2);
    let doc = harness.state().document();
    assert_eq!(material(doc, 1, Coef::Ka), 0.4, "one step undoes the entry");
    assert!(!doc.has_unsaved_edits());

    for model in ["lambert", "phong", "ambient", "lambert", "phong"] {
        harness.get_by_label(model).click();
        harness.run_steps(1);
    }
    assert_eq!(
        harness.state().document().scene().model.illumination,
        scene::Illumination::Phong
    );
    for _ in 0..5 {
        harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    }
    harness.run_steps(1);
    let doc = harness.state().document();
    assert_eq!(doc.scene().model.illumination, scene::Illumination::Whitted);
    assert!(!doc.has_unsaved_edits(), "five presses, five steps");
}

/// Ctrl+S after the file was renamed away asks (save
/// it there again, save as, cancel) rather than silently making a new
/// file at the old name.
#[test]
fn saving_a_file_renamed_away_asks_first() {
    let (dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let mut harness = app_on(Document::open(&path).unwrap());
    harness.get_by_label("lambert").click();
    harness.run_steps(1);
    let renamed = dir.path().join("renamed.xml");
    std::fs::rename(&path, &renamed).unwrap();
    step_until(
        &mut harness,
        Duration::from_secs(10),
        "the file missing",
        |app| *app.document().state() == rayoflight::session::document::FileState::Missing,
    );
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    harness.run_steps(3);
    assert!(harness.query_by_label("The file is gone").is_some());
    assert!(!path.exists(), "nothing written before the answer");
    harness.get_by_label("Cancel").click();
    harness.run_steps(3);
    assert!(!path.exists());
    assert!(harness.state().document().has_unsaved_edits());

    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    harness.run_steps(3);
    harness.get_by_label("Save it there again").click();
    step_until(&mut harness, Duration::from_secs(10), "the save", |app| {
        !app.is_saving() && !app.document().has_unsaved_edits()
    });
    assert_eq!(
        read(&path),
        EXAMPLE.replace(r#"type="whitted""#, r#"type="lambert""#)
    );
    assert_eq!(read(&renamed), EXAMPLE, "the renamed file left alone");
}

/// Found by hand: a notice too long for the status bar
/// is cut with "…" and shown whole on hover, once (a tooltip of the app's
/// own was drawn over egui's, the same text twice).
#[test]
fn a_long_notice_is_shown_whole_once_on_hover() {
    let (_dir, path) = common::scene_file("scene.xml", EXAMPLE);
    let long = format!("a notice {}end", "long words ".repeat(60));
    let persisted = Persisted {
        refused: vec![long.clone()],
        ..Persisted::in_memory()
    };
    let mut harness = app_keeping(Document::open(&path).unwrap(), persisted);
    let shown =
        |h: &Harness<'_, RayOfLightApp>| h.query_all_by_label_contains("a notice long").count();
    assert_eq!(shown(&harness), 1, "one label, cut");
    harness.get_by_label_contains("a notice long").hover();
    // Past egui's tooltip delay.
    for _ in 0..60 {
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(shown(&harness), 2, "the label and one tooltip");
}
