//! Which application opens a type of file by default, as gio and
//! xdg-mime decide it (freedesktop.org's "Association between MIME types
//! and applications"), and the line of the user's `mimeapps.list` that
//! keeps that default when `install-desktop` adds RayOfLight.
//!
//! RayOfLight's entry lists XML (`application/xml`, `text/xml`) so that
//! it is offered in "Open with" for XML files. A default chosen in a
//! `mimeapps.list` outranks every entry; with none, the most preferred
//! application wins, and entries in the user's own data folder are
//! preferred to the system's: the install would make RayOfLight the
//! default for every XML file. So before it writes the entry, the install
//! asks who opens XML now; where that is an application the user has not
//! chosen in any `mimeapps.list`, it writes that choice into
//! `$XDG_CONFIG_HOME/mimeapps.list` (`[Default Applications]`, one line a
//! type, the group added where missing) and records what it wrote; the
//! uninstall removes those lines again where they are still as written,
//! and the file and group too where it made them and nothing else is in
//! them. A default the user chose since is theirs and stays.
//!
//! The user's file is read, changed where the lines go and nowhere else,
//! and written back only if it still holds what was read (read again just
//! before the rename, as `edit` does), never over a change made meanwhile.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The folders the spec looks in, in order of precedence.
#[derive(Debug, Clone)]
pub struct Places {
    /// `$XDG_CONFIG_HOME` (default `~/.config`): where the user's choices go.
    pub config_home: PathBuf,
    /// `$XDG_CONFIG_DIRS` (default `/etc/xdg`).
    pub config_dirs: Vec<PathBuf>,
    /// `$XDG_DATA_HOME` (default `~/.local/share`).
    pub data_home: PathBuf,
    /// `$XDG_DATA_DIRS` (default `/usr/local/share`, `/usr/share`).
    pub data_dirs: Vec<PathBuf>,
    /// `$XDG_CURRENT_DESKTOP`'s names, lower case: their
    /// `NAME-mimeapps.list` comes before `mimeapps.list`.
    pub desktops: Vec<String>,
}

impl Places {
    /// The folders the environment names, with `data_home` as the data
    /// folder. `None` without a config folder (no `XDG_CONFIG_HOME` nor
    /// `HOME` that is absolute).
    pub fn from_env(data_home: &Path) -> Option<Places> {
        let absolute = |v: std::ffi::OsString| Some(PathBuf::from(v)).filter(|p| p.is_absolute());
        let config_home = std::env::var_os("XDG_CONFIG_HOME")
            .and_then(absolute)
            .or_else(|| {
                std::env::var_os("HOME")
                    .and_then(absolute)
                    .map(|h| h.join(".config"))
            })?;
        let list = |name: &str, default: &[&str]| -> Vec<PathBuf> {
            let listed: Vec<PathBuf> = std::env::var_os(name)
                .map(|v| {
                    std::env::split_paths(&v)
                        .filter(|p| p.is_absolute())
                        .collect()
                })
                .unwrap_or_default();
            if listed.is_empty() {
                default.iter().map(PathBuf::from).collect()
            } else {
                listed
            }
        };
        let desktops = std::env::var("XDG_CURRENT_DESKTOP")
            .unwrap_or_default()
            .split(':')
            .filter(|d| !d.is_empty())
            .map(str::to_lowercase)
            .collect();
        Some(Places {
            config_home,
            config_dirs: list("XDG_CONFIG_DIRS", &["/etc/xdg"]),
            data_home: data_home.to_owned(),
            data_dirs: list("XDG_DATA_DIRS", &["/usr/local/share", "/usr/share"]),
            desktops,
        })
    }

    /// The user's own list, where a pinned default goes.
    pub fn user_list(&self) -> PathBuf {
        self.config_home.join("mimeapps.list")
    }

    /// The folders of `mimeapps.list` files, in order, each with the
    /// applications folder whose entries come at its level (none for
    /// the config folders).
    fn levels(&self) -> Vec<(PathBuf, Option<PathBuf>)> {
        let mut levels: Vec<(PathBuf, Option<PathBuf>)> = std::iter::once(&self.config_home)
            .chain(&self.config_dirs)
            .map(|d| (d.clone(), None))
            .collect();
        for data in std::iter::once(&self.data_home).chain(&self.data_dirs) {
            let applications = data.join("applications");
            levels.push((applications.clone(), Some(applications)));
        }
        levels
    }

    /// The `mimeapps.list` files of a folder, the desktops' first.
    fn lists_in(&self, folder: &Path) -> Vec<PathBuf> {
        self.desktops
            .iter()
            .map(|d| folder.join(format!("{d}-mimeapps.list")))
            .chain(std::iter::once(folder.join("mimeapps.list")))
            .collect()
    }

    fn applications(&self) -> impl Iterator<Item = PathBuf> + '_ {
        std::iter::once(&self.data_home)
            .chain(&self.data_dirs)
            .map(|d| d.join("applications"))
    }

    /// Whether the desktop entry `id` is installed and may run: found in
    /// the first applications folder that has it (`a-b.desktop` may be
    /// `a/b.desktop`), not `Hidden`, its `TryExec` (or `Exec`'s program)
    /// there. `ignored` is as if it were not.
    fn installed(&self, id: &str, ignored: &str) -> bool {
        if id == ignored {
            return false;
        }
        let Some(entry) = self.applications().find_map(|dir| find_entry(&dir, id)) else {
            return false;
        };
        let Ok(text) = std::fs::read_to_string(&entry) else {
            return false;
        };
        let group = KeyFile::parse(&text);
        let value = |key| group.value("Desktop Entry", key);
        if value("Hidden") == Some("true") {
            return false;
        }
        let program = value("TryExec")
            .map(str::to_owned)
            .or_else(|| value("Exec").and_then(first_word));
        program.is_some_and(|p| runnable(&p))
    }
}

/// Who opens a type by default.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Default {
    /// Chosen in a `mimeapps.list`: no entry added later changes it.
    Chosen(String),
    /// Not chosen: the most preferred of the entries that list the type,
    /// which an entry added to the user's data folder would displace.
    Preferred(String),
    /// No application opens it.
    Nobody,
}

/// Who opens `mime` by default under `places`, as if the entry
/// `ignored` (RayOfLight's own, on a reinstall) were not installed.
pub fn default_for(places: &Places, mime: &str, ignored: &str) -> Default {
    let levels = places.levels();
    let lists: Vec<Vec<KeyFile>> = levels
        .iter()
        .map(|(folder, _)| {
            places
                .lists_in(folder)
                .iter()
                .filter_map(|l| std::fs::read_to_string(l).ok())
                .map(|t| KeyFile::parse(&t))
                .collect()
        })
        .collect();
    for list in lists.iter().flatten() {
        let chosen = list.ids("Default Applications", mime);
        if let Some(id) = chosen.into_iter().find(|id| places.installed(id, ignored)) {
            return Default::Chosen(id);
        }
    }
    // The associations, level by level: those a list adds, then the
    // entries of the level's applications folder; those a list removes
    // are gone from the levels below it.
    let mut removed = HashSet::new();
    for ((_, applications), lists) in levels.iter().zip(&lists) {
        for list in lists {
            for id in list.ids("Added Associations", mime) {
                if !removed.contains(&id) && places.installed(&id, ignored) {
                    return Default::Preferred(id);
                }
            }
            removed.extend(list.ids("Removed Associations", mime));
        }
        let Some(applications) = applications else {
            continue;
        };
        for id in entries_for(applications, mime) {
            if !removed.contains(&id) && places.installed(&id, ignored) {
                return Default::Preferred(id);
            }
        }
    }
    Default::Nobody
}

/// The entries of one applications folder that list `mime`, in the order
/// of its `mimeinfo.cache` (update-desktop-database's, which xdg-mime
/// reads), then any others in the order of their ids.
fn entries_for(applications: &Path, mime: &str) -> Vec<String> {
    let cache = std::fs::read_to_string(applications.join("mimeinfo.cache")).unwrap_or_default();
    let mut ids = KeyFile::parse(&cache).ids("MIME Cache", mime);
    let mut others = Vec::new();
    desktop_ids(applications, "", &mut |id, path| {
        if ids.iter().any(|i| i == &id) {
            return;
        }
        let lists = std::fs::read_to_string(path).is_ok_and(|text| {
            KeyFile::parse(&text)
                .value("Desktop Entry", "MimeType")
                .is_some_and(|types| types.split(';').any(|t| t.trim() == mime))
        });
        if lists {
            others.push(id);
        }
    });
    others.sort();
    ids.extend(others);
    ids
}

/// Every `.desktop` file under `folder`, with its id (`sub/a.desktop` is
/// `sub-a.desktop`).
fn desktop_ids(folder: &Path, prefix: &str, found: &mut dyn FnMut(String, &Path)) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            desktop_ids(&path, &format!("{prefix}{name}-"), found);
        } else if name.ends_with(".desktop") {
            found(format!("{prefix}{name}"), &path);
        }
    }
}

/// The file of the entry `id` in `folder`: `folder/id`, or for an id with
/// dashes, a subfolder named by what comes before one.
fn find_entry(folder: &Path, id: &str) -> Option<PathBuf> {
    let direct = folder.join(id);
    if direct.is_file() {
        return Some(direct);
    }
    id.match_indices('-').find_map(|(at, _)| {
        let sub = folder.join(&id[..at]);
        sub.is_dir()
            .then(|| find_entry(&sub, &id[at + 1..]))
            .flatten()
    })
}

/// The program of an `Exec` line: its first word, quotes taken off.
fn first_word(exec: &str) -> Option<String> {
    let exec = exec.trim_start();
    let word = match exec.strip_prefix('"') {
        Some(rest) => rest.split('"').next()?.replace("\\\\", "\\"),
        None => exec.split_whitespace().next()?.to_owned(),
    };
    Some(word).filter(|w| !w.is_empty())
}

/// Whether `program` (a path, or a name looked up in `PATH`) is a file.
fn runnable(program: &str) -> bool {
    let path = Path::new(program);
    if path.is_absolute() {
        return path.is_file();
    }
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(path).is_file()))
}

/// A desktop entry or `mimeapps.list`, read as groups of `key=value`.
struct KeyFile {
    entries: Vec<(String, String, String)>,
}

impl KeyFile {
    fn parse(text: &str) -> KeyFile {
        let mut group = String::new();
        let mut entries = Vec::new();
        for line in text.lines() {
            let line = line.trim();
            if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
                group = name.to_owned();
            } else if !line.starts_with('#')
                && let Some((key, value)) = line.split_once('=')
            {
                entries.push((
                    group.clone(),
                    key.trim().to_owned(),
                    value.trim().to_owned(),
                ));
            }
        }
        KeyFile { entries }
    }

    fn value(&self, group: &str, key: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|(g, k, _)| g == group && k == key)
            .map(|(_, _, v)| v.as_str())
    }

    /// A list of desktop ids (`a.desktop;b.desktop;`).
    fn ids(&self, group: &str, key: &str) -> Vec<String> {
        self.value(group, key)
            .map(|v| {
                v.split(';')
                    .map(str::trim)
                    .filter(|id| !id.is_empty())
                    .map(str::to_owned)
                    .collect()
            })
            .unwrap_or_default()
    }
}

/// The group pinned defaults go in.
const GROUP: &str = "[Default Applications]";

/// What a pin added to the user's `mimeapps.list`, to take it out again.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Pinned {
    /// The lines added (`application/xml=editor.desktop;`).
    pub lines: Vec<String>,
    /// The group was added, at the end, after these newlines.
    pub group_after: Option<usize>,
    /// The file was made.
    pub made_file: bool,
    /// The group's header was the file's last line, without a newline:
    /// one was added after it.
    pub header_newline: bool,
}

/// `text` (the user's `mimeapps.list`, empty where there is none) with
/// `lines` added to its `[Default Applications]` group, right after its
/// header, or in a new group at the end; and what was added.
pub fn pin(text: &str, lines: &[String]) -> (String, Pinned) {
    let mut pinned = Pinned {
        lines: lines.to_vec(),
        ..Pinned::default()
    };
    let added: String = lines.iter().map(|l| format!("{l}\n")).collect();
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        at += line.len();
        if line.trim() == GROUP {
            // A header on the file's last line, without a newline.
            let newline = if line.ends_with('\n') { "" } else { "\n" };
            pinned.header_newline = !newline.is_empty();
            let out = format!("{}{newline}{added}{}", &text[..at], &text[at..]);
            return (out, pinned);
        }
    }
    let newlines = match text {
        "" => 0,
        t if t.ends_with("\n\n") => 0,
        t if t.ends_with('\n') => 1,
        _ => 2,
    };
    pinned.group_after = Some(newlines);
    let out = format!("{text}{}{GROUP}\n{added}", "\n".repeat(newlines));
    (out, pinned)
}

/// `text` with what [`pin`] added taken out where it is still as written:
/// each line (the first exactly equal in the group), the group if it was
/// added and holds nothing else, at the end of the file. Returns the text
/// and the lines not found (changed or removed since).
pub fn unpin(text: &str, pinned: &Pinned) -> (String, Vec<String>) {
    let mut lines: Vec<&str> = text.split_inclusive('\n').collect();
    let mut missing = Vec::new();
    let mut in_group = false;
    for wanted in &pinned.lines {
        let mut found = None;
        for (i, line) in lines.iter().enumerate() {
            let line = line.trim_end_matches('\n');
            if line.trim().starts_with('[') {
                in_group = line.trim() == GROUP;
            } else if in_group && line == wanted {
                found = Some(i);
                break;
            }
        }
        in_group = false;
        match found {
            Some(i) => {
                lines.remove(i);
            }
            None => missing.push(wanted.clone()),
        }
    }
    let mut out: String = lines.concat();
    if pinned.header_newline && out.ends_with(&format!("{GROUP}\n")) {
        out.pop();
    }
    if let Some(newlines) = pinned.group_after {
        let tail = format!("{GROUP}\n");
        if out.ends_with(&tail) {
            let before = out.len() - tail.len();
            let separator = "\n".repeat(newlines);
            if out[..before].ends_with(&separator) {
                out.truncate(before - separator.len());
            }
        }
    }
    (out, missing)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines() -> Vec<String> {
        vec![
            "application/xml=editor.desktop;".to_owned(),
            "text/xml=editor.desktop;".to_owned(),
        ]
    }

    #[test]
    fn a_pin_goes_in_the_group_or_a_new_one_and_comes_out_byte_for_byte() {
        for text in [
            "",
            "[Added Associations]\ntext/plain=a.desktop;\n",
            "[Added Associations]\ntext/plain=a.desktop;",
            "[Added Associations]\ntext/plain=a.desktop;\n\n",
            "[Default Applications]\ntext/plain=a.desktop;\n[Added Associations]\n",
            "# mine\n[Default Applications]",
        ] {
            let (pinned_text, pinned) = pin(text, &lines());
            assert!(
                pinned_text.contains("\n[Default Applications]\napplication/xml=editor.desktop;\ntext/xml=editor.desktop;\n")
                    || pinned_text.starts_with("[Default Applications]\napplication/xml"),
                "{pinned_text:?}"
            );
            let keys = KeyFile::parse(&pinned_text);
            assert_eq!(
                keys.ids("Default Applications", "text/xml"),
                ["editor.desktop"]
            );
            let (back, missing) = unpin(&pinned_text, &pinned);
            assert!(missing.is_empty());
            assert_eq!(back, text);
        }
    }

    #[test]
    fn a_line_the_user_changed_since_stays() {
        let (text, pinned) = pin("", &lines());
        let changed = text.replace("text/xml=editor.desktop;", "text/xml=mine.desktop;");
        let (back, missing) = unpin(&changed, &pinned);
        assert_eq!(back, "[Default Applications]\ntext/xml=mine.desktop;\n");
        assert_eq!(missing, ["text/xml=editor.desktop;"]);
        // A line of the same text in another group is not the pin's.
        let other = "[Added Associations]\ntext/xml=editor.desktop;\n";
        let (back, missing) = unpin(other, &pinned);
        assert_eq!(back, other);
        assert_eq!(missing.len(), 2);
    }

    #[test]
    fn an_exec_lines_program_is_its_first_word() {
        assert_eq!(first_word("gedit %U").as_deref(), Some("gedit"));
        assert_eq!(
            first_word("\"/opt/my editor/run\" %f").as_deref(),
            Some("/opt/my editor/run")
        );
        assert_eq!(first_word("  "), None);
    }
}
