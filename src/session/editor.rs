//! Edit › Open in editor: the user's own editor started on the scene file
//! at a line and column.
//!
//! Which editor, the first that is set: the environment variable
//! `RAYOFLIGHT_EDITOR`, `editor = …` in settings.txt (both a template with
//! `{file}`, `{line}` and `{column}`), else `$VISUAL` or `$EDITOR` as
//! `EDITOR +{line} {file}`, run in a terminal emulator (`$TERMINAL`, else
//! `x-terminal-emulator`, with `-e`) when it is one that runs in a
//! terminal (vi, nano, emacs -nw…). A template is split into words as a
//! shell would split it (quotes, backslashes), and the placeholders are
//! filled in each word: a file name with spaces stays one argument, and no
//! shell ever reads it. A template without `{file}` gets the file last.

use std::path::Path;
use std::process::{Command, Stdio};

/// Where the editor's command came from, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    Environment,
    Settings,
    Visual,
    Editor,
}

impl Source {
    fn name(self) -> &'static str {
        match self {
            Source::Environment => "RAYOFLIGHT_EDITOR",
            Source::Settings => "editor in settings.txt",
            Source::Visual => "$VISUAL",
            Source::Editor => "$EDITOR",
        }
    }
}

/// The editor to run: a template of words and where it came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Editor {
    pub template: String,
    pub source: Source,
    /// Run it in a terminal emulator.
    pub in_terminal: bool,
}

/// What the environment looks like, read once (the tests give their own).
#[derive(Debug, Clone, Default)]
pub struct Environment {
    pub rayoflight_editor: Option<String>,
    pub visual: Option<String>,
    pub editor: Option<String>,
    pub terminal: Option<String>,
}

impl Environment {
    pub fn current() -> Environment {
        let var = |name| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
        Environment {
            rayoflight_editor: var("RAYOFLIGHT_EDITOR"),
            visual: var("VISUAL"),
            editor: var("EDITOR"),
            terminal: var("TERMINAL"),
        }
    }
}

/// Editors that draw in a terminal: they need one when the app starts
/// them.
const TERMINAL_EDITORS: &[&str] = &[
    "vi", "vim", "nvim", "nano", "pico", "micro", "hx", "helix", "kak", "ne", "joe", "jed", "mg",
    "ed", "ex", "vis", "mcedit", "tilde",
];

/// Whether the command line `command` runs a terminal editor.
fn is_terminal_editor(command: &str) -> bool {
    let words = split_words(command).unwrap_or_default();
    let Some(program) = words.first() else {
        return false;
    };
    let name = Path::new(program)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let emacs_in_terminal = name.starts_with("emacs")
        && words
            .iter()
            .any(|w| matches!(w.as_str(), "-nw" | "--no-window-system" | "-t" | "--tty"));
    TERMINAL_EDITORS.contains(&name.as_str()) || emacs_in_terminal
}

/// The editor to use, from `env` and the setting `configured`; `None`
/// when nothing says.
pub fn resolve(env: &Environment, configured: Option<&str>) -> Option<Editor> {
    let template = |template: &str, source| Editor {
        template: template.to_owned(),
        source,
        in_terminal: false,
    };
    if let Some(t) = &env.rayoflight_editor {
        return Some(template(t, Source::Environment));
    }
    if let Some(t) = configured.filter(|t| !t.trim().is_empty()) {
        return Some(template(t, Source::Settings));
    }
    let (command, source) = match (&env.visual, &env.editor) {
        (Some(v), _) => (v, Source::Visual),
        (None, Some(e)) => (e, Source::Editor),
        (None, None) => return None,
    };
    Some(Editor {
        template: format!("{command} +{{line}} {{file}}"),
        source,
        in_terminal: is_terminal_editor(command),
    })
}

/// Why the editor did not start.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EditorError {
    #[error(
        "no editor set: set RAYOFLIGHT_EDITOR (e.g. \"code -g {{file}}:{{line}}:{{column}}\"), editor = … in settings.txt, or $VISUAL"
    )]
    NoEditor,
    #[error("the editor command ({source_name}) is empty or has an unclosed quote: {template}")]
    BadTemplate {
        template: String,
        source_name: &'static str,
    },
    #[error("could not start {program} ({source_name}): {message}")]
    Spawn {
        program: String,
        source_name: &'static str,
        message: String,
    },
}

/// `text` split into words as a POSIX shell splits them (single and double
/// quotes, backslash escapes), without expanding anything; `None` for an
/// unclosed quote.
pub fn split_words(text: &str) -> Option<Vec<String>> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        match c {
            c if c.is_whitespace() => {
                if let Some(w) = word.take() {
                    words.push(w);
                }
            }
            '\'' => {
                let w = word.get_or_insert_with(String::new);
                loop {
                    match chars.next()? {
                        '\'' => break,
                        c => w.push(c),
                    }
                }
            }
            '"' => {
                let w = word.get_or_insert_with(String::new);
                loop {
                    match chars.next()? {
                        '"' => break,
                        '\\' => match chars.next()? {
                            c @ ('"' | '\\' | '$' | '`') => w.push(c),
                            c => {
                                w.push('\\');
                                w.push(c);
                            }
                        },
                        c => w.push(c),
                    }
                }
            }
            '\\' => {
                let next = chars.next()?;
                word.get_or_insert_with(String::new).push(next);
            }
            c => word.get_or_insert_with(String::new).push(c),
        }
    }
    words.extend(word);
    Some(words)
}

/// The program and arguments that open `file` at `line`, `column` (both
/// 1-based) with `editor`, in a terminal emulator where it needs one.
pub fn command_line(
    editor: &Editor,
    env: &Environment,
    file: &Path,
    line: usize,
    column: usize,
) -> Result<Vec<String>, EditorError> {
    let bad = || EditorError::BadTemplate {
        template: editor.template.clone(),
        source_name: editor.source.name(),
    };
    let words = split_words(&editor.template).ok_or_else(bad)?;
    if words.is_empty() {
        return Err(bad());
    }
    let file_text = file.to_string_lossy();
    let fill = |w: &str| {
        w.replace("{file}", &file_text)
            .replace("{line}", &line.to_string())
            .replace("{column}", &column.to_string())
    };
    let mut argv: Vec<String> = words.iter().map(|w| fill(w)).collect();
    if !words.iter().any(|w| w.contains("{file}")) {
        argv.push(file_text.into_owned());
    }
    if editor.in_terminal {
        let terminal = env
            .terminal
            .clone()
            .unwrap_or_else(|| "x-terminal-emulator".to_owned());
        let mut wrapped = split_words(&terminal).unwrap_or_else(|| vec![terminal.clone()]);
        wrapped.push("-e".to_owned());
        wrapped.extend(argv);
        argv = wrapped;
    }
    Ok(argv)
}

/// Starts `argv` detached from the app (its own process group, no
/// terminal input), and waits for it on a thread of its own so that it
/// leaves no zombie; `exited` is told its status if it fails within a few
/// seconds (a bad flag, a missing file it cannot open).
pub fn start(
    argv: &[String],
    source: Source,
    exited: impl FnOnce(String) + Send + 'static,
) -> Result<(), EditorError> {
    let (program, args) = argv.split_first().ok_or(EditorError::NoEditor)?;
    let mut command = Command::new(program);
    command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        command.process_group(0);
    }
    let mut child = command.spawn().map_err(|e| EditorError::Spawn {
        program: program.clone(),
        source_name: source.name(),
        message: e.to_string(),
    })?;
    let program = program.clone();
    let started = std::time::Instant::now();
    std::thread::Builder::new()
        .name("editor".into())
        .spawn(move || {
            let stderr = child.stderr.take();
            let said = stderr
                .map(|mut s| {
                    let mut text = String::new();
                    let _ = std::io::Read::read_to_string(&mut s, &mut text);
                    text
                })
                .unwrap_or_default();
            if let Ok(status) = child.wait()
                && !status.success()
                && started.elapsed() < std::time::Duration::from_secs(10)
            {
                let first = said.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
                exited(format!(
                    "{program} failed ({status}){}{first}",
                    if first.is_empty() { "" } else { ": " }
                ));
            }
        })
        .map_err(|e| EditorError::Spawn {
            program: argv[0].clone(),
            source_name: source.name(),
            message: e.to_string(),
        })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(visual: Option<&str>, editor: Option<&str>) -> Environment {
        Environment {
            visual: visual.map(str::to_owned),
            editor: editor.map(str::to_owned),
            ..Environment::default()
        }
    }

    #[test]
    fn the_first_that_is_set_wins() {
        let mut e = env(Some("gvim"), Some("nano"));
        assert_eq!(resolve(&e, None).unwrap().template, "gvim +{line} {file}");
        assert_eq!(
            resolve(&e, Some("kate -l {line} {file}")).unwrap().source,
            Source::Settings
        );
        e.rayoflight_editor = Some("code -g {file}:{line}:{column}".into());
        let chosen = resolve(&e, Some("kate")).unwrap();
        assert_eq!(chosen.source, Source::Environment);
        assert!(!chosen.in_terminal);
        let nano = resolve(&env(None, Some("nano")), None).unwrap();
        assert!(nano.in_terminal && nano.source == Source::Editor);
        assert!(resolve(&env(None, None), None).is_none());
        assert!(resolve(&env(None, None), Some("  ")).is_none());
    }

    #[test]
    fn terminal_editors_run_in_a_terminal() {
        for t in ["vi", "/usr/bin/vim", "nvim -u NONE", "emacs -nw", "hx"] {
            assert!(is_terminal_editor(t), "{t}");
        }
        for g in ["gvim", "emacs", "code --wait", "emacsclient -c", "gedit"] {
            assert!(!is_terminal_editor(g), "{g}");
        }
        let e = Environment {
            editor: Some("vim".into()),
            terminal: Some("foot".into()),
            ..Environment::default()
        };
        let vim = resolve(&e, None).unwrap();
        let argv = command_line(&vim, &e, Path::new("/s/a b.xml"), 12, 3).unwrap();
        assert_eq!(argv, ["foot", "-e", "vim", "+12", "/s/a b.xml"]);
        let e = Environment {
            terminal: None,
            ..e
        };
        let argv = command_line(&vim, &e, Path::new("s.xml"), 1, 1).unwrap();
        assert_eq!(argv[..2], ["x-terminal-emulator", "-e"]);
    }

    #[test]
    fn placeholders_fill_words_and_a_file_name_stays_one_argument() {
        let e = Environment::default();
        let code = Editor {
            template: "code -g {file}:{line}:{column}".into(),
            source: Source::Environment,
            in_terminal: false,
        };
        let argv = command_line(&code, &e, Path::new("/home/me/my scene; rm.xml"), 7, 5).unwrap();
        assert_eq!(argv, ["code", "-g", "/home/me/my scene; rm.xml:7:5"]);
        let no_file = Editor {
            template: "'my editor' --line={line}".into(),
            ..code.clone()
        };
        let argv = command_line(&no_file, &e, Path::new("s.xml"), 2, 1).unwrap();
        assert_eq!(argv, ["my editor", "--line=2", "s.xml"]);
        let broken = Editor {
            template: "code \"{file}".into(),
            ..code
        };
        assert!(matches!(
            command_line(&broken, &e, Path::new("s.xml"), 1, 1),
            Err(EditorError::BadTemplate { .. })
        ));
    }

    #[test]
    fn words_split_as_a_shell_splits_them() {
        let w = |s: &str| split_words(s);
        assert_eq!(w("a  b\tc").unwrap(), ["a", "b", "c"]);
        assert_eq!(
            w(r#"emacsclient -c -a "" +{line}"#).unwrap(),
            ["emacsclient", "-c", "-a", "", "+{line}"]
        );
        assert_eq!(
            w(r#"a\ b 'c d' "e \"f\" \g""#).unwrap(),
            ["a b", "c d", r#"e "f" \g"#]
        );
        assert_eq!(w("'open"), None);
        assert_eq!(w("").unwrap(), Vec::<String>::new());
    }

    #[test]
    fn a_program_that_is_not_there_says_so() {
        let err = start(&["/nonexistent/editor".into()], Source::Settings, |_| {}).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("could not start /nonexistent/editor (editor in settings.txt): "),
            "{err}"
        );
    }
}
