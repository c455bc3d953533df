//! The recent-files list, kept in `$XDG_CONFIG_HOME/rayoflight/recent.txt`
//! (or `~/.config/…`), one path per line, newest first.

use std::path::{Path, PathBuf};

const MAX_RECENT: usize = 10;

fn store() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .filter(|p| p.is_absolute())
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("rayoflight").join("recent.txt"))
}

/// The stored list; empty when there is none or it cannot be read.
pub fn load() -> Vec<PathBuf> {
    store()
        .and_then(|f| std::fs::read_to_string(f).ok())
        .map(|text| {
            text.lines()
                .filter(|l| !l.trim().is_empty())
                .map(PathBuf::from)
                .take(MAX_RECENT)
                .collect()
        })
        .unwrap_or_default()
}

/// Puts `path` first in the list and stores the list (best effort: a
/// read-only home directory only loses the list).
pub fn push(list: &mut Vec<PathBuf>, path: &Path) {
    let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    list.retain(|p| p != &path);
    list.insert(0, path);
    list.truncate(MAX_RECENT);
    if let Some(file) = store() {
        let text: String = list.iter().map(|p| format!("{}\n", p.display())).collect();
        if let Some(dir) = file.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        let _ = crate::output::write_atomic(&file, text.as_bytes());
    }
}
