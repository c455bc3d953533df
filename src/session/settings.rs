//! What the app remembers between runs, in its own struct: the window's
//! size, the anti-aliasing, the study's runs, the last file open, the
//! editor of Edit › Open in editor
//! ([`Settings`], `settings.txt`), and the recent files ([`Recent`],
//! `recent.txt`, one path per line, newest first). Both live in
//! `$XDG_CONFIG_HOME/rayoflight/` (or `~/.config/rayoflight/`), used only
//! if that folder and the config home are the user's and closed to
//! others' writes ([`Persisted::in_homes`]), and are written the same way
//! ([`store`]: atomically, best effort); tests use them in memory only. Beside
//! them, where the journal of unsaved edits goes (a state, not a setting:
//! `$XDG_STATE_HOME`, [`crate::session::journal`]).
//!
//! `settings.txt` holds `key = value` lines. Unknown keys and bad values
//! are ignored: a stale or hand-edited file never stops the app.

use std::path::{Path, PathBuf};

const MAX_RECENT: usize = 10;

/// An XDG base folder: the variable `var` when it is an absolute path,
/// else `$HOME/default`; `None` without a home.
fn xdg_home(var: &str, default: &str) -> Option<PathBuf> {
    std::env::var_os(var)
        .map(PathBuf::from)
        .filter(|p| p.is_absolute())
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(default)))
}

/// Everything persisted.
#[derive(Debug, Clone, Default)]
pub struct Persisted {
    pub settings: Settings,
    pub recent: Recent,
    /// The folder of the journal of unsaved edits
    /// ([`crate::session::journal`]); `None`: no journal.
    pub journal: Option<PathBuf>,
    /// Why a folder of the user's state is not used (another user's, or
    /// open to others' writes), for the app to say once.
    pub refused: Vec<String>,
}

impl Persisted {
    /// The user's: settings and recent files in `$XDG_CONFIG_HOME` (or
    /// `~/.config`), the journal in `$XDG_STATE_HOME` (or
    /// `~/.local/state`).
    pub fn user() -> Persisted {
        Persisted::in_homes(
            xdg_home("XDG_CONFIG_HOME", ".config").as_deref(),
            xdg_home("XDG_STATE_HOME", ".local/state").as_deref(),
        )
    }

    /// What is kept in `config/rayoflight/` (settings, recent files) and
    /// `state/rayoflight/journal/`. Each folder is made where missing and
    /// used only if it and those above it up to its home are the user's
    /// and closed to others' writes ([`crate::system::files::own_folder`]):
    /// another user's `recent.txt` would choose the file the app opens,
    /// their journal the edits a save writes. A folder refused is left
    /// alone and said in [`Persisted::refused`].
    pub fn in_homes(config: Option<&Path>, state: Option<&Path>) -> Persisted {
        let mut refused = Vec::new();
        let mut usable = |found: Option<Result<PathBuf, crate::system::files::OwnFolderError>>,
                          what: &str| match found? {
            Ok(folder) => Some(folder),
            Err(e) => {
                refused.push(format!("{what} off: {e}"));
                None
            }
        };
        let config = usable(
            config.map(|home| crate::system::files::own_folder(home, &["rayoflight"], false)),
            "settings and recent files",
        );
        let journal = usable(
            state.map(crate::session::journal::folder_in),
            "unsaved edits journal",
        );
        Persisted {
            settings: Settings::load(config.as_ref().map(|d| d.join("settings.txt"))),
            recent: Recent::load(config.as_ref().map(|d| d.join("recent.txt"))),
            journal,
            refused,
        }
    }

    /// Defaults, never written anywhere (tests).
    pub fn in_memory() -> Persisted {
        Persisted::default()
    }
}

/// The app's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The window's inner size, in points.
    pub window: Option<[f32; 2]>,
    /// Anti-aliasing of the preview and of exports (N×N rays a pixel).
    pub aa: u32,
    /// Renders a method gets in the Study window.
    pub study_runs: usize,
    /// The scene file open when the app last closed (`None`: the built-in
    /// example); the app reopens it when started without a file.
    pub last_file: Option<PathBuf>,
    /// Edit › Open in editor's command (`editor = code -g {file}:{line}`),
    /// when RAYOFLIGHT_EDITOR does not say ([`crate::session::editor`]).
    pub editor: Option<String>,
    /// Where they are saved; `None`: nowhere.
    store: Option<PathBuf>,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            window: None,
            aa: 1,
            study_runs: 3,
            last_file: None,
            editor: None,
            store: None,
        }
    }
}

impl Settings {
    /// Reads `store` (defaults for what it lacks) and saves there later.
    pub fn load(store: Option<PathBuf>) -> Settings {
        let text = store
            .as_deref()
            .and_then(|p| std::fs::read_to_string(p).ok())
            .unwrap_or_default();
        Settings {
            store,
            ..Settings::parse(&text)
        }
    }

    fn parse(text: &str) -> Settings {
        let mut s = Settings::default();
        for line in text.lines() {
            let Some((key, value)) = line.split_once('=') else {
                continue;
            };
            let value = value.trim();
            match key.trim() {
                "window" => {
                    s.window = value
                        .split_once('x')
                        .and_then(|(w, h)| Some([w.trim().parse().ok()?, h.trim().parse().ok()?]))
                        .filter(|[w, h]: &[f32; 2]| {
                            w.is_finite() && h.is_finite() && *w >= 100.0 && *h >= 100.0
                        });
                }
                "aa" => {
                    if let Some(aa) = value.parse().ok().filter(|aa| (1..=4).contains(aa)) {
                        s.aa = aa;
                    }
                }
                "study_runs" => {
                    if let Some(runs) = value.parse().ok().filter(|r| (1..=1000).contains(r)) {
                        s.study_runs = runs;
                    }
                }
                "last_file" if !value.is_empty() => s.last_file = Some(PathBuf::from(value)),
                "editor" if !value.is_empty() => s.editor = Some(value.to_owned()),
                _ => {}
            }
        }
        s
    }

    fn to_text(&self) -> String {
        let mut text = String::new();
        if let Some([w, h]) = self.window {
            text.push_str(&format!("window = {w}x{h}\n"));
        }
        text.push_str(&format!("aa = {}\n", self.aa));
        text.push_str(&format!("study_runs = {}\n", self.study_runs));
        if let Some(path) = self.last_file.as_deref().and_then(as_line) {
            text.push_str(&format!("last_file = {path}\n"));
        }
        if let Some(editor) = self.editor.as_deref().filter(|e| !e.contains(['\n', '\r'])) {
            text.push_str(&format!("editor = {editor}\n"));
        }
        text
    }

    /// Writes them where they were loaded from (best effort: a read-only
    /// home only loses them).
    pub fn save(&self) {
        store(self.store.as_deref(), &self.to_text());
    }
}

/// `path` as one line of these files, or `None` where the line format
/// cannot hold it as it is (not UTF-8, a line break, spaces at its ends):
/// such a path is not remembered.
fn as_line(path: &Path) -> Option<&str> {
    path.to_str()
        .filter(|p| !p.contains(['\n', '\r']) && p.trim() == *p)
}

/// Writes `text` to `file` atomically, making its folder (best effort: a
/// read-only home only loses what would have been remembered). `None`:
/// kept in memory only.
fn store(file: Option<&Path>, text: &str) {
    let Some(file) = file else { return };
    if let Some(dir) = file.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    let _ = crate::system::files::write_atomic(file, text.as_bytes());
}

/// The recent files: the list and where it is stored.
#[derive(Debug, Clone, Default)]
pub struct Recent {
    paths: Vec<PathBuf>,
    /// `None`: kept in memory only (tests, a home without a config
    /// directory).
    store: Option<PathBuf>,
}

impl Recent {
    /// The list kept in `store` (`None`: in memory only).
    pub fn load(store: Option<PathBuf>) -> Recent {
        let paths = store
            .as_ref()
            .and_then(|f| std::fs::read_to_string(f).ok())
            .map(|text| {
                text.lines()
                    .filter(|l| !l.trim().is_empty())
                    .map(PathBuf::from)
                    .take(MAX_RECENT)
                    .collect()
            })
            .unwrap_or_default();
        Recent { paths, store }
    }

    /// An empty list that is never written anywhere.
    pub fn in_memory() -> Recent {
        Recent::default()
    }

    /// The files of the list that still exist, newest first.
    pub fn existing(&self) -> Vec<PathBuf> {
        self.paths.iter().filter(|p| p.exists()).cloned().collect()
    }

    /// Puts `path` first and stores the list ([`store`]; a path the file
    /// cannot hold stays in this run's list only).
    pub fn push(&mut self, path: &Path) {
        let path = crate::system::files::absolute(path);
        self.paths.retain(|p| p != &path);
        self.paths.insert(0, path);
        self.paths.truncate(MAX_RECENT);
        let text: String = self
            .paths
            .iter()
            .filter_map(|p| as_line(p))
            .map(|p| format!("{p}\n"))
            .collect();
        store(self.store.as_deref(), &text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_saved_and_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("rayoflight/settings.txt");
        let mut s = Settings::load(Some(file.clone()));
        assert_eq!(s.aa, 1);
        s.window = Some([900.0, 700.5]);
        s.aa = 3;
        s.study_runs = 5;
        s.last_file = Some(dir.path().join("a scene.xml"));
        s.editor = Some("code -g \"{file}:{line}:{column}\"".into());
        s.save();
        let back = Settings::load(Some(file));
        assert_eq!(back, s);
    }

    #[test]
    fn a_stale_or_broken_file_gives_defaults_for_what_it_breaks() {
        let s = Settings::parse("aa = 9\nwindow = 10x10\nstudy_runs = x\nnew_key = 1\nnonsense\n");
        assert_eq!(s, Settings::default());
        let s = Settings::parse("window = 1200 x 800\naa=2");
        assert_eq!((s.window, s.aa), (Some([1200.0, 800.0]), 2));
    }

    #[test]
    fn a_path_the_file_cannot_hold_is_not_remembered() {
        for odd in ["two\nlines.xml", " padded.xml"] {
            let s = Settings {
                last_file: Some(PathBuf::from(odd)),
                ..Settings::default()
            };
            assert_eq!(Settings::parse(&s.to_text()).last_file, None, "{odd:?}");
        }
    }
}
