//! Command-line parsing, by hand: the brief's single-dash long options
//! (`-out`, `-time`) sit beside GNU-style flags, which argument-parsing
//! crates cannot mix.

use std::ffi::OsString;
use std::path::PathBuf;

/// What the user asked for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Command {
    Help,
    Version,
    /// Render a scene (headless), or open the app on it (GUI build, no
    /// headless flag).
    Render(RenderArgs),
    /// `export-pov scene.xml [-out scene.pov]`.
    ExportPov {
        scene: PathBuf,
        out: Option<PathBuf>,
    },
    /// `plan scene.xml`: print what `auto` decides for the scene.
    Plan {
        scene: PathBuf,
    },
    /// `bench [--threads N] [--runs K] [--csv FILE] [--no-pov]`.
    Bench(super::bench::BenchArgs),
    /// `study [--out DIR] [--runs K] [--threads N] [scene.xml…]`.
    Study(super::study::StudyArgs),
}

#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RenderArgs {
    /// The scene file; `None` means the built-in example (app only).
    pub scene: Option<PathBuf>,
    pub out: Option<PathBuf>,
    pub time: bool,
    pub no_gui: bool,
    pub threads: Option<usize>,
    pub aa: Option<u32>,
    /// A study method to render with instead of `auto` (`--method`).
    pub method: Option<rayoflight::study::Method>,
}

impl RenderArgs {
    /// Whether the command asks for headless work: any of `-out`, `-time`,
    /// `--no-gui`, `--threads`, `--aa`, `--method`. In the GUI build,
    /// anything else opens the app (the headless build never asks).
    #[cfg_attr(not(feature = "gui"), allow(dead_code))]
    pub fn headless(&self) -> bool {
        self.out.is_some()
            || self.time
            || self.no_gui
            || self.threads.is_some()
            || self.aa.is_some()
            || self.method.is_some()
    }
}

/// A command line that does not parse: exit status 2.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

fn usage(msg: impl Into<String>) -> UsageError {
    UsageError(msg.into())
}

/// Parses the arguments after the program name.
pub fn parse(args: impl IntoIterator<Item = OsString>) -> Result<Command, UsageError> {
    let mut args = args.into_iter();
    let mut r = RenderArgs::default();
    let mut positionals: Vec<PathBuf> = Vec::new();
    let mut help = false;
    let mut version = false;
    let mut runs: Option<usize> = None;
    let mut csv: Option<PathBuf> = None;
    let mut no_pov = false;
    let mut only_positionals = false;

    while let Some(arg) = args.next() {
        let Some(text) = arg
            .to_str()
            .filter(|t| t.starts_with('-') && !only_positionals)
        else {
            positionals.push(PathBuf::from(arg));
            continue;
        };
        // `--flag=value` form.
        let (flag, inline) = match text.split_once('=') {
            Some((f, v)) if f.starts_with("--") => (f, Some(v.to_owned())),
            _ => (text, None),
        };
        let mut value = |name: &str| -> Result<String, UsageError> {
            match inline.clone() {
                Some(v) => Ok(v),
                None => args
                    .next()
                    .map(|v| v.to_string_lossy().into_owned())
                    .ok_or_else(|| usage(format!("{name} needs a value"))),
            }
        };
        match flag {
            "--" => only_positionals = true,
            "-" => positionals.push(PathBuf::from(text)),
            "-h" | "--help" => help = true,
            "-V" | "--version" => version = true,
            "-out" | "--out" | "-o" => {
                if r.out.is_some() {
                    return Err(usage("-out given twice"));
                }
                r.out = Some(PathBuf::from(value(flag)?));
            }
            "-time" | "--time" => r.time = true,
            "--runs" => {
                let v = value(flag)?;
                runs = Some(
                    v.parse()
                        .ok()
                        .filter(|&n: &usize| (1..=1000).contains(&n))
                        .ok_or_else(|| {
                            usage(format!(
                                "--runs expects an integer from 1 to 1000, not {v:?}"
                            ))
                        })?,
                );
            }
            "--csv" => csv = Some(PathBuf::from(value(flag)?)),
            "--no-pov" => no_pov = true,
            "--no-gui" => r.no_gui = true,
            "--threads" => {
                let v = value(flag)?;
                r.threads = Some(v.parse().ok().filter(|&n: &usize| n >= 1).ok_or_else(|| {
                    usage(format!("--threads expects an integer >= 1, not {v:?}"))
                })?);
            }
            "--aa" => {
                let v = value(flag)?;
                let max = rayoflight::render::MAX_AA;
                r.aa = Some(
                    v.parse()
                        .ok()
                        .filter(|n| (1..=max).contains(n))
                        .ok_or_else(|| {
                            usage(format!(
                                "--aa expects an integer from 1 to {max}, not {v:?}"
                            ))
                        })?,
                );
            }
            "--method" => {
                let v = value(flag)?;
                r.method = Some(rayoflight::study::method(&v).ok_or_else(|| {
                    let names: Vec<_> = rayoflight::study::methods()
                        .iter()
                        .map(|m| m.name)
                        .collect();
                    usage(format!(
                        "--method expects one of {}, not {v:?}",
                        names.join(", ")
                    ))
                })?);
            }
            _ => return Err(usage(format!("unknown flag '{text}'"))),
        }
    }

    if help {
        return Ok(Command::Help);
    }
    if version {
        return Ok(Command::Version);
    }
    let mut positionals = positionals.into_iter();
    let first = positionals.next();
    let subcommand = first
        .as_deref()
        .and_then(|p| p.to_str())
        .filter(|p| ["bench", "study", "export-pov", "plan"].contains(p));
    if let (Some(name), Some(_)) = (subcommand, &r.method) {
        return Err(usage(format!(
            "--method belongs to rendering, not to '{name}'"
        )));
    }
    if first.as_deref() == Some(std::path::Path::new("bench")) {
        if let Some(extra) = positionals.next() {
            return Err(usage(format!("unexpected argument '{}'", extra.display())));
        }
        if r.time || r.aa.is_some() || (csv.is_some() && r.out.is_some()) {
            return Err(usage(
                "bench takes --threads, --runs, --csv (or -out) and --no-pov",
            ));
        }
        return Ok(Command::Bench(super::bench::BenchArgs {
            threads: r
                .threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
            runs: runs.unwrap_or(3),
            csv: csv.or(r.out),
            pov: !no_pov,
        }));
    }
    if first.as_deref() == Some(std::path::Path::new("study")) {
        if r.time || r.aa.is_some() || r.no_gui || csv.is_some() || no_pov {
            return Err(usage(
                "study takes --out DIR, --runs, --threads and scene files",
            ));
        }
        return Ok(Command::Study(super::study::StudyArgs {
            out: r.out.unwrap_or_else(|| PathBuf::from("study")),
            runs: runs.unwrap_or(3),
            threads: r.threads,
            scenes: positionals.collect(),
        }));
    }
    if runs.is_some() || csv.is_some() || no_pov {
        return Err(usage("--runs, --csv and --no-pov belong to 'bench'"));
    }
    if first.as_deref() == Some(std::path::Path::new("export-pov")) {
        let scene = positionals
            .next()
            .ok_or_else(|| usage("export-pov needs a scene file"))?;
        if let Some(extra) = positionals.next() {
            return Err(usage(format!("unexpected argument '{}'", extra.display())));
        }
        if r.time || r.no_gui || r.threads.is_some() || r.aa.is_some() {
            return Err(usage("export-pov takes only a scene and -out"));
        }
        return Ok(Command::ExportPov { scene, out: r.out });
    }
    if first.as_deref() == Some(std::path::Path::new("plan")) {
        let scene = positionals
            .next()
            .ok_or_else(|| usage("plan needs a scene file"))?;
        if let Some(extra) = positionals.next() {
            return Err(usage(format!("unexpected argument '{}'", extra.display())));
        }
        if r.out.is_some() || r.time || r.no_gui || r.threads.is_some() || r.aa.is_some() {
            return Err(usage("plan takes only a scene file"));
        }
        return Ok(Command::Plan { scene });
    }
    if let Some(extra) = positionals.next() {
        return Err(usage(format!(
            "unexpected argument '{}' (one scene at a time)",
            extra.display()
        )));
    }
    r.scene = first;
    Ok(Command::Render(r))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(args: &[&str]) -> Result<Command, UsageError> {
        parse(args.iter().map(OsString::from))
    }

    #[test]
    fn brief_syntax_and_gnu_forms_agree() {
        let brief = p(&["-time", "s.xml", "-out", "x.png"]).unwrap();
        let gnu = p(&["--time", "s.xml", "--out=x.png"]).unwrap();
        assert_eq!(brief, gnu);
        let Command::Render(r) = brief else { panic!() };
        assert_eq!(r.scene, Some(PathBuf::from("s.xml")));
        assert_eq!(r.out, Some(PathBuf::from("x.png")));
        assert!(r.time && r.headless());
    }

    #[test]
    fn numbers_are_checked() {
        assert!(p(&["s.xml", "--threads", "0"]).is_err());
        assert!(p(&["s.xml", "--aa", "17"]).is_err());
        assert!(p(&["s.xml", "--aa"]).is_err());
        let Ok(Command::Render(r)) = p(&["s.xml", "--aa", "4", "--threads=3"]) else {
            panic!()
        };
        assert_eq!((r.aa, r.threads), (Some(4), Some(3)));
    }

    #[test]
    fn unknown_flags_are_named() {
        assert_eq!(p(&["-x"]).unwrap_err().0, "unknown flag '-x'");
        assert_eq!(p(&["--outt", "a"]).unwrap_err().0, "unknown flag '--outt'");
    }

    #[test]
    fn export_pov_subcommand() {
        assert_eq!(
            p(&["export-pov", "s.xml", "-out", "s.pov"]).unwrap(),
            Command::ExportPov {
                scene: "s.xml".into(),
                out: Some("s.pov".into())
            }
        );
        assert!(p(&["export-pov"]).is_err());
    }

    #[test]
    fn bench_subcommand() {
        let Ok(Command::Bench(b)) = p(&["bench", "--threads", "3", "--runs", "7", "-out", "b.csv"])
        else {
            panic!()
        };
        assert_eq!((b.threads, b.runs, b.pov), (3, 7, true));
        assert_eq!(b.csv, Some(PathBuf::from("b.csv")));
        let Ok(Command::Bench(b)) = p(&["bench", "--no-pov"]) else {
            panic!()
        };
        assert!(!b.pov && b.runs == 3 && b.csv.is_none());
        assert!(p(&["bench", "--runs", "0"]).is_err());
        assert!(p(&["bench", "scene.xml"]).is_err());
        assert!(p(&["bench", "--aa", "2"]).is_err());
        assert!(
            p(&["s.xml", "--runs", "2"]).is_err(),
            "--runs belongs to bench"
        );
    }

    #[test]
    fn method_names_a_study_method() {
        let Ok(Command::Render(r)) = p(&["s.xml", "--method", "f32"]) else {
            panic!()
        };
        assert_eq!(r.method.as_ref().map(|m| m.name), Some("f32"));
        assert!(r.headless());
        assert!(p(&["s.xml", "--method", "fast"]).is_err());
        assert!(p(&["s.xml", "--method"]).is_err());
        assert!(p(&["study", "--method", "auto"]).is_err());
    }

    #[test]
    fn plan_subcommand() {
        assert_eq!(
            p(&["plan", "s.xml"]).unwrap(),
            Command::Plan {
                scene: PathBuf::from("s.xml")
            }
        );
        assert!(p(&["plan"]).is_err());
        assert!(p(&["plan", "a.xml", "b.xml"]).is_err());
        assert!(p(&["plan", "a.xml", "-out", "x.png"]).is_err());
    }

    #[test]
    fn study_subcommand() {
        let Ok(Command::Study(s)) = p(&["study", "--out", "d", "a.xml", "b.xml", "--runs=1"])
        else {
            panic!()
        };
        assert_eq!(s.out, PathBuf::from("d"));
        assert_eq!(s.scenes, [PathBuf::from("a.xml"), PathBuf::from("b.xml")]);
        assert_eq!((s.runs, s.threads), (1, None));
        let Ok(Command::Study(s)) = p(&["study"]) else {
            panic!()
        };
        assert_eq!((s.out, s.runs), (PathBuf::from("study"), 3));
        assert!(s.scenes.is_empty());
        assert!(p(&["study", "--aa", "2"]).is_err());
        assert!(p(&["study", "--csv", "x.csv"]).is_err());
    }

    #[test]
    fn double_dash_ends_flags() {
        let Ok(Command::Render(r)) = p(&["--", "-weird.xml"]) else {
            panic!()
        };
        assert_eq!(r.scene, Some(PathBuf::from("-weird.xml")));
    }
}
