//! The recent-files list, kept in `$XDG_CONFIG_HOME/rayoflight/recent.txt`
//! (or `~/.config/…`), one path per line, newest first. Files that are gone
//! are left out of the menu.

use std::path::{Path, PathBuf};

const MAX_RECENT: usize = 10;

/// The list and where it is stored.
#[derive(Debug, Clone, Default)]
pub struct Recent {
    paths: Vec<PathBuf>,
    /// `None`: kept in memory only (tests, a home without a config
    /// directory).
    store: Option<PathBuf>,
}

impl Recent {
    /// The user's list, from the config directory.
    pub fn user() -> Recent {
        let store = super::settings::config_file("recent.txt");
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

    /// Puts `path` first and stores the list (best effort: a read-only
    /// home directory only loses the list).
    pub fn push(&mut self, path: &Path) {
        let path = crate::files::absolute(path);
        self.paths.retain(|p| p != &path);
        self.paths.insert(0, path);
        self.paths.truncate(MAX_RECENT);
        if let Some(file) = &self.store {
            let text: String = self
                .paths
                .iter()
                .map(|p| format!("{}\n", p.display()))
                .collect();
            if let Some(dir) = file.parent() {
                let _ = std::fs::create_dir_all(dir);
            }
            let _ = crate::output::write_atomic(file, text.as_bytes());
        }
    }
}
