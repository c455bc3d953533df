//! At home on the desktop, in the shell and in the editor: the
//! completions a real bash computes from the generated script, the man
//! pages as man renders them, the schema as xmllint applies it to every
//! scene and to the bad-input corpus, `install-desktop` into a temporary
//! data folder and back out, the repository's desktop files through
//! desktop-file-validate and appstreamcli, and `new`.

use crate::common::{files_in, rayoflight, stderr, stdout, tool};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// `install-desktop` is in the GUI build only.
#[cfg(feature = "gui")]
const BIN: &str = env!("CARGO_BIN_EXE_rayoflight");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Every subcommand, as the man pages and completions name them: those
/// `rayoflight --help` lists under "Commands:" (a name, two spaces in),
/// read from the binary rather than kept as a copy of its list.
fn subcommands() -> Vec<String> {
    let help = run_ok(&["--help"]);
    let names: Vec<String> = help
        .lines()
        .skip_while(|l| l.trim_end() != "Commands:")
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter(|l| l.starts_with("  ") && !l[2..].starts_with(' '))
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_owned)
        .collect();
    for known in ["split", "edit", "man", "install-desktop", "lsp"] {
        assert!(
            names.iter().any(|n| n == known),
            "{known} not in {names:?}: {help}"
        );
    }
    names
}

fn run_ok(args: &[&str]) -> String {
    let o = rayoflight(Path::new(ROOT), args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stdout(&o)
}

// ----- completions -----

/// What bash's completion function offers for the words of `line` (the
/// last one being completed), run in `dir`: the generated script sourced
/// in a real bash, the words given as bash gives them.
fn bash_completes(script: &Path, dir: &Path, line: &[&str]) -> Vec<String> {
    let words: Vec<String> = line.iter().map(|w| format!("'{w}'")).collect();
    let program = format!(
        r#"source '{}'
COMP_WORDS=({})
COMP_CWORD=$(( ${{#COMP_WORDS[@]}} - 1 ))
COMP_LINE="${{COMP_WORDS[*]}}"
COMP_POINT=${{#COMP_LINE}}
f=$(complete -p rayoflight | sed -E 's/.* -F ([^ ]+) .*/\1/')
"$f" rayoflight "${{COMP_WORDS[COMP_CWORD]}}" "${{COMP_WORDS[COMP_CWORD-1]}}"
printf '%s\n' "${{COMPREPLY[@]}}""#,
        script.display(),
        words.join(" ")
    );
    let o = Command::new("bash")
        .args(["--norc", "--noprofile", "-c", &program])
        .current_dir(dir)
        .output()
        .expect("bash runs");
    offered(&o, line)
}

/// What a shell printed of its matches for `line`, one a line (a match's
/// description after a tab left out), sorted; the shell must have
/// succeeded.
fn offered(o: &std::process::Output, line: &[&str]) -> Vec<String> {
    assert!(o.status.success(), "{line:?}: {}", stderr(o));
    let mut offered: Vec<String> = stdout(o)
        .lines()
        .filter_map(|l| l.split('\t').next())
        .filter(|l| !l.is_empty())
        .map(str::to_owned)
        .collect();
    offered.sort();
    offered
}

fn sorted(names: &[&str]) -> Vec<String> {
    let mut v: Vec<String> = names.iter().map(|s| s.to_string()).collect();
    v.sort();
    v
}

/// What a shell's completion offers, line by line (the last word being
/// completed), in a folder holding `scene.xml` and `shot.png`: the same in
/// bash, zsh and fish.
fn completion_cases() -> Vec<(Vec<&'static str>, Vec<String>)> {
    let methods: Vec<&str> = rayoflight::render::methods()
        .iter()
        .map(|m| m.name)
        .collect();
    let passes: Vec<&str> = rayoflight::render::Pass::ALL
        .iter()
        .map(|p| p.name())
        .collect();
    let both = sorted(&["scene.xml", "shot.png"]);
    let mut cases = vec![
        // Subcommands, and the scene, where the first word goes.
        (
            vec!["rayoflight", "s"],
            sorted(&["scene.xml", "schema", "sheet", "shot.png", "split", "study"]),
        ),
        (vec!["rayoflight", "install"], sorted(&["install-desktop"])),
        // Flags: the render's after a scene, a subcommand's after it.
        (
            vec!["rayoflight", "scene.xml", "--no"],
            sorted(&["--no-gui"]),
        ),
        (
            vec!["rayoflight", "edit", "scene.xml", "--re"],
            sorted(&["--remove"]),
        ),
        (vec!["rayoflight", "split", "--ta"], sorted(&["--tasks"])),
        (
            vec!["rayoflight", "install-desktop", "--u"],
            sorted(&["--uninstall"]),
        ),
        // Values: the names the parser takes, from the library's own lists.
        (
            vec!["rayoflight", "scene.xml", "--method", ""],
            sorted(&methods),
        ),
        (vec!["rayoflight", "--method", ""], sorted(&methods)),
        (
            vec![
                "rayoflight",
                "explain",
                "scene.xml",
                "1",
                "2",
                "--method",
                "f32",
            ],
            sorted(&["f32", "f32-eps-1e-3"]),
        ),
        (
            vec!["rayoflight", "scene.xml", "--pass", ""],
            sorted(&passes),
        ),
        (vec!["rayoflight", "--pass", ""], sorted(&passes)),
        (
            vec!["rayoflight", "edit", "scene.xml", "--add", ""],
            sorted(&["light", "plane", "sphere"]),
        ),
        (vec!["rayoflight", "completions", "z"], sorted(&["zsh"])),
        (
            vec!["rayoflight", "completions", ""],
            sorted(&["bash", "elvish", "fish", "powershell", "zsh"]),
        ),
        (
            vec!["rayoflight", "man", "ex"],
            sorted(&["explain", "export-pov"]),
        ),
        (vec!["rayoflight", "explain", "sc"], sorted(&["scene.xml"])),
        (
            vec!["rayoflight", "split", "scene.xml", "--tasks", ""],
            Vec::new(),
        ),
    ];
    // Files where a file goes: the scene, -out, parts, images.
    for line in [
        vec!["rayoflight", "-q", ""],
        vec!["rayoflight", "scene.xml", "-out", ""],
        vec!["rayoflight", "edit", ""],
        vec!["rayoflight", "plan", ""],
        vec!["rayoflight", "assemble", "-o", "all.png", ""],
        vec!["rayoflight", "sheet", "-o", "sheet.png", "shot.png", ""],
        vec!["rayoflight", "bench", "--csv", ""],
    ] {
        cases.push((line, both.clone()));
    }
    // Nothing after a flag whose value is a number or PATH=VALUE.
    for flag in ["--threads", "--aa", "--set", "--region"] {
        cases.push((vec!["rayoflight", "scene.xml", flag, ""], Vec::new()));
    }
    cases
}

/// Every case of [`completion_cases`] through `complete`; all the lines
/// that differ, in one failure.
fn completes_every_case(shell: &str, complete: impl Fn(&[&str]) -> Vec<String>) {
    let wrong: Vec<String> = completion_cases()
        .into_iter()
        .filter_map(|(line, expected)| {
            let offered = complete(&line);
            (offered != expected)
                .then(|| format!("{shell} {line:?}: offered {offered:?}, expected {expected:?}"))
        })
        .collect();
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The folder the cases complete in, and the script of `shell` in it.
fn completion_folder(shell: &str, file: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    fs::create_dir(&work).unwrap();
    for f in ["scene.xml", "shot.png"] {
        fs::write(work.join(f), "").unwrap();
    }
    fs::write(dir.path().join(file), run_ok(&["completions", shell])).unwrap();
    (dir, work)
}

#[test]
fn bash_completes_subcommands_flags_files_and_values() {
    if !tool("bash", "bash") {
        return;
    }
    let (dir, work) = completion_folder("bash", "rayoflight.bash");
    let script = dir.path().join("rayoflight.bash");
    completes_every_case("bash", |line| bash_completes(&script, &work, line));
}

/// What zsh offers for `line`, as a Tab in an interactive zsh would
/// (`tests/desktop/zsh-complete.zsh`: the completion system in a
/// pseudo-terminal, each match printed).
fn zsh_completes(fpath: &Path, dir: &Path, line: &[&str]) -> Vec<String> {
    let capture = Path::new(ROOT).join("tests/desktop/zsh-complete.zsh");
    let o = Command::new("zsh")
        .arg("-f")
        .arg(&capture)
        .arg(fpath)
        .arg(line.join(" "))
        .current_dir(dir)
        .env("HOME", dir)
        .output()
        .expect("zsh runs");
    // A match offered under two tags is printed twice.
    let mut offered = offered(&o, line);
    offered.dedup();
    offered
}

#[test]
fn zsh_completes_as_bash_does() {
    if !tool("zsh", "zsh") {
        return;
    }
    let (dir, work) = completion_folder("zsh", "_rayoflight");
    completes_every_case("zsh", |line| zsh_completes(dir.path(), &work, line));
}

/// What fish offers for `line` (`complete -C`, the script sourced).
fn fish_completes(script: &Path, dir: &Path, line: &[&str]) -> Vec<String> {
    let program = format!(
        "source '{}'; complete -C '{}'",
        script.display(),
        line.join(" ")
    );
    let o = Command::new("fish")
        .args(["--no-config", "-c", &program])
        .current_dir(dir)
        .env("HOME", dir)
        .output()
        .expect("fish runs");
    let mut offered = offered(&o, line);
    offered.dedup();
    offered
}

#[test]
fn fish_completes_as_bash_does() {
    if !tool("fish", "fish") {
        return;
    }
    let (dir, work) = completion_folder("fish", "rayoflight.fish");
    let script = dir.path().join("rayoflight.fish");
    completes_every_case("fish", |line| fish_completes(&script, &work, line));
}

#[test]
fn every_shell_gets_a_script_with_the_subcommands_and_values() {
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let script = run_ok(&["completions", shell]);
        for needle in ["install-desktop", "export-pov", "no-gui", "method"] {
            assert!(script.contains(needle), "{shell}: no {needle}");
        }
        // clap_complete's PowerShell and Elvish scripts complete no values.
        if ["bash", "zsh", "fish"].contains(&shell) {
            for needle in ["no-early-stop", "reflection", "sphere"] {
                assert!(script.contains(needle), "{shell}: no {needle}");
            }
        }
    }
    let o = rayoflight(Path::new(ROOT), &["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("bash, elvish, fish, powershell, zsh"),
        "{}",
        stderr(&o)
    );
}

// ----- man pages -----

#[test]
fn man_renders_every_page_without_a_warning() {
    if !tool("man", "man-db") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let top = run_ok(&["man"]);
    let subcommands = subcommands();
    for sub in &subcommands {
        assert!(
            top.contains(&format!("rayoflight\\-{}(1)", sub.replace('-', "\\-"))),
            "rayoflight(1) does not name rayoflight-{sub}(1)"
        );
    }
    let pages = std::iter::once(None).chain(subcommands.iter().map(|s| Some(s.as_str())));
    for sub in pages {
        let page = match sub {
            Some(sub) => run_ok(&["man", sub]),
            None => top.clone(),
        };
        let file = dir
            .path()
            .join(format!("{}.1", sub.unwrap_or("rayoflight")));
        fs::write(&file, &page).unwrap();
        let o = Command::new("man")
            .arg("--warnings")
            .arg("-l")
            .arg(&file)
            .env("MANWIDTH", "80")
            .env("LC_ALL", "C.UTF-8")
            .env("MAN_KEEP_FORMATTING", "0")
            .output()
            .expect("man runs");
        assert!(o.status.success(), "{sub:?}: {}", stderr(&o));
        assert_eq!(stderr(&o), "", "{sub:?}: man warns");
        let shown = stdout(&o);
        let name = match sub {
            Some(sub) => format!("rayoflight-{sub}"),
            None => "rayoflight".to_owned(),
        };
        assert!(shown.contains(&name), "{sub:?}: {shown}");
        // Each heading of the edit page's list starts a line of its own
        // (they ran into the line before).
        if sub == Some("edit") {
            for heading in [
                "Values (--set PATH=VALUE):",
                "Elements (--remove PATH):",
                "Each ",
            ] {
                assert!(
                    shown.lines().any(|l| l.trim_start().starts_with(heading)),
                    "{heading}: {shown}"
                );
            }
        }
    }
    let o = rayoflight(Path::new(ROOT), &["man", "frobnicate"]);
    assert_eq!(o.status.code(), Some(2));

    // --dir writes them all, the same pages.
    let all = dir.path().join("man1");
    let o = rayoflight(Path::new(ROOT), &["man", "--dir", all.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o), "");
    let mut expected: Vec<String> = subcommands
        .iter()
        .map(|s| format!("rayoflight-{s}.1"))
        .chain(["rayoflight.1".to_owned()])
        .collect();
    expected.sort();
    assert_eq!(files_in(&all), expected);
    assert_eq!(
        fs::read_to_string(all.join("rayoflight-edit.1")).unwrap(),
        run_ok(&["man", "edit"])
    );
    assert_eq!(fs::read_to_string(all.join("rayoflight.1")).unwrap(), top);
}

/// Help, man pages and completions come from one definition: every flag
/// `--help` shows is in the man page and in the bash script.
#[test]
fn help_man_pages_and_completions_name_the_same_flags() {
    let bash = run_ok(&["completions", "bash"]);
    let subcommands = subcommands();
    for sub in std::iter::once(None).chain(subcommands.iter().map(|s| Some(s.as_str()))) {
        let (help, page) = match sub {
            Some(sub) => (run_ok(&[sub, "--help"]), run_ok(&["man", sub])),
            None => (run_ok(&["--help"]), run_ok(&["man"])),
        };
        let flags: Vec<&str> = help
            .split(|c: char| c.is_whitespace() || c == ',' || c == '[' || c == ']')
            .filter(|w| {
                w.starts_with("--")
                    && w.len() > 2
                    && w[2..].chars().all(|c| c.is_ascii_lowercase() || c == '-')
            })
            .collect();
        assert!(
            !flags.is_empty() || sub == Some("schema"),
            "{sub:?}: {help}"
        );
        for flag in flags {
            assert!(
                page.contains(&flag.replace('-', "\\-")),
                "{sub:?}: {flag} is in --help but not in the man page"
            );
            assert!(
                bash.contains(flag),
                "{sub:?}: {flag} is in --help but not in the completions"
            );
        }
    }
}

// ----- the schema -----

fn schema_file(dir: &Path) -> PathBuf {
    let path = dir.join("rayoflight.xsd");
    fs::write(&path, run_ok(&["schema"])).unwrap();
    path
}

/// xmllint's verdict on each file against `schema`: `Ok` when it
/// validates, else its first error line.
fn validate(schema: &Path, files: &[PathBuf]) -> Vec<Result<(), String>> {
    let o = Command::new("xmllint")
        .args(["--noout", "--nonet", "--schema"])
        .arg(schema)
        .args(files)
        .output()
        .expect("xmllint runs");
    let err = stderr(&o);
    files
        .iter()
        .map(|f| {
            let name = f.display().to_string();
            if err.lines().any(|l| l == format!("{name} validates")) {
                Ok(())
            } else {
                Err(err
                    .lines()
                    .find(|l| l.starts_with(&format!("{name}:")))
                    .unwrap_or("refused")
                    .to_owned())
            }
        })
        .collect()
}

fn scene_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            scene_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "xml") {
            out.push(path);
        }
    }
}

#[test]
fn the_schema_is_a_valid_xsd_and_every_scene_validates() {
    if !tool("xmllint", "libxml2-utils") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let schema = schema_file(dir.path());
    // The schema itself is a well-formed XML Schema (xmllint refuses to
    // validate anything with a broken one).
    let mut scenes = Vec::new();
    scene_files(&Path::new(ROOT).join("scenes"), &mut scenes);
    scenes.sort();
    assert!(scenes.len() >= 20, "{scenes:?}");
    // The fuzz corpus's scenes the loader accepts, too.
    for entry in fs::read_dir(Path::new(ROOT).join("fuzz/corpus")).unwrap() {
        let path = entry.unwrap().path();
        if rayoflight::scene::load(&path).is_ok() {
            scenes.push(path);
        }
    }
    for (scene, verdict) in scenes.iter().zip(validate(&schema, &scenes)) {
        assert!(
            rayoflight::scene::load(scene).is_ok(),
            "{}",
            scene.display()
        );
        assert_eq!(verdict, Ok(()), "{}", scene.display());
    }
}

/// The bad-input corpus's refusals that XSD 1.0 cannot say, with why: the
/// schema's documentation says them, the loader refuses them.
const NOT_IN_XSD: &[(&str, &str)] = &[
    (
        "44_image_too_large.xml",
        "width × height: a product of two attributes",
    ),
    (
        "45_scale_factor_with_x.xml",
        "factor excludes x, y, z: no co-occurrence rules in XSD 1.0",
    ),
    ("46_scale_y_then_factor.xml", "the same"),
    (
        "47_zero_scale.xml",
        "a singular transformation: arithmetic on the steps",
    ),
    ("48_zero_scale_component.xml", "the same"),
    (
        "69_composed_overflow.xml",
        "an overflow of the composed matrix",
    ),
    ("70_scale_overflow.xml", "the same"),
    (
        "71_scale_inverse_overflow.xml",
        "an overflow of the inverse",
    ),
];

#[test]
fn the_schema_refuses_every_structural_error_of_the_bad_input_corpus() {
    if !tool("xmllint", "libxml2-utils") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let schema = schema_file(dir.path());
    let mut bad: Vec<PathBuf> = fs::read_dir(Path::new(ROOT).join("tests/malformed"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    bad.sort();
    assert!(bad.len() >= 80);
    for (file, verdict) in bad.iter().zip(validate(&schema, &bad)) {
        assert!(rayoflight::scene::load(file).is_err(), "{}", file.display());
        let name = file.file_name().unwrap().to_str().unwrap();
        match NOT_IN_XSD.iter().find(|(n, _)| *n == name) {
            Some((_, why)) => assert_eq!(
                verdict,
                Ok(()),
                "{name} is refused by the schema now: take it off NOT_IN_XSD ({why})"
            ),
            None => assert!(verdict.is_err(), "{name}: the schema accepts it"),
        }
    }
}

/// The schema's numbers and integers are the loader's: each spelling is
/// accepted by both or refused by both.
#[test]
fn the_schema_reads_numbers_as_the_loader_does() {
    if !tool("xmllint", "libxml2-utils") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let schema = schema_file(dir.path());
    let numbers = [
        "1",
        "-1",
        "+1",
        "0",
        "-0",
        "1.5",
        ".5",
        "5.",
        "-.5",
        "1e3",
        "1E3",
        "1e+3",
        "1e-3",
        "1.e3",
        " 2 ",
        "1e308",
        "1.7976931348623157e308",
        "1e309",
        "-1e400",
        "1e-400",
        "inf",
        "INF",
        "-INF",
        "NaN",
        "nan",
        "infinity",
        "0x10",
        "1,5",
        "1_000",
        "",
        " ",
        ".",
        "e3",
        "1e",
        "++1",
        "1 2",
        "١",
        "0.0000001",
        "00012",
    ];
    let integers = [
        "1",
        "+1",
        "007",
        "0",
        "-0",
        "-1",
        "1.0",
        "1e3",
        " 3 ",
        "",
        "4294967295",
        "4294967296",
        "99999999999999999999",
        "0x10",
        "+",
        "١",
    ];
    let mut cases: Vec<(String, PathBuf)> = Vec::new();
    let scene = |material: &str, camera: &str, depth: &str| {
        format!(
            "<scene><sphere><material {material}/></sphere>\
             <camera {camera} height=\"2\" eyeDistance=\"1\"/><model type=\"whitted\" {depth}/></scene>"
        )
    };
    for (i, n) in numbers.iter().enumerate() {
        let text = scene(&format!("ka=\"{n}\""), "width=\"2\"", "");
        let ten = scene("", "width=\"2\"", "").replace(
            "<sphere>",
            &format!("<sphere><transformation><translate x=\"{n}\"/></transformation>"),
        );
        for (j, text) in [text, ten].into_iter().enumerate() {
            let path = dir.path().join(format!("n{i}-{j}.xml"));
            fs::write(&path, &text).unwrap();
            cases.push((format!("number {n:?} ({j})"), path));
        }
    }
    for (i, n) in integers.iter().enumerate() {
        for (j, text) in [
            scene("", &format!("width=\"{n}\""), ""),
            scene("", "width=\"2\"", &format!("depth=\"{n}\"")),
        ]
        .into_iter()
        .enumerate()
        {
            let path = dir.path().join(format!("i{i}-{j}.xml"));
            fs::write(&path, &text).unwrap();
            cases.push((format!("integer {n:?} ({j})"), path));
        }
    }
    let files: Vec<PathBuf> = cases.iter().map(|(_, p)| p.clone()).collect();
    let mut accepted = 0;
    for ((what, path), verdict) in cases.iter().zip(validate(&schema, &files)) {
        let loaded = rayoflight::scene::load(path);
        // The image-size rule (width × height ≤ 2^28) is the loader's
        // alone.
        if let Err(e) = &loaded
            && matches!(
                e.kind,
                rayoflight::scene::LoadErrorKind::ImageTooLarge { .. }
            )
        {
            assert_eq!(verdict, Ok(()), "{what}");
            continue;
        }
        assert_eq!(
            loaded.is_ok(),
            verdict.is_ok(),
            "{what}: loader {loaded:?}, schema {verdict:?}"
        );
        accepted += usize::from(loaded.is_ok());
    }
    assert!(accepted > 20 && accepted < cases.len() - 20, "{accepted}");
}

const NAMED: &str = r#"<?xml version="1.0"?>
<?xml-model href="rayoflight.xsd"?>
<scene xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
       xsi:noNamespaceSchemaLocation="rayoflight.xsd">
  <sphere><material ka="0.2"/></sphere>
  <light x="0" y="-3" z="-3"/>
  <camera width="16" height="12" eyeDistance="2"/>
</scene>
"#;

#[test]
fn a_scene_that_names_its_schema_loads_validates_and_keeps_it_through_edit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.xml");
    fs::write(&path, NAMED).unwrap();
    assert!(rayoflight::scene::load(&path).is_ok());
    if tool("xmllint", "libxml2-utils") {
        // xmllint finds the schema by the scene's own say-so.
        schema_file(dir.path());
        let o = Command::new("xmllint")
            .args(["--noout", "--nonet", "--schema", "rayoflight.xsd", "s.xml"])
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = rayoflight(
        dir.path(),
        &["edit", "s.xml", "--set", "object[1].material.ka=0.5"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        fs::read_to_string(&path).unwrap(),
        NAMED.replace(r#"ka="0.2""#, r#"ka="0.5""#)
    );

    // Exactly these: the XSI namespace, by that name.
    for (text, message) in [
        (
            NAMED.replace("XMLSchema-instance", "XMLSchema-instanc"),
            "3:8: <scene> names its schema with xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\", not \"http://www.w3.org/2001/XMLSchema-instanc\"",
        ),
        (
            NAMED.replace(
                "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\"\n       ",
                "",
            ),
            "3:8: <scene> names its schema with xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" first",
        ),
        (
            NAMED.replace("xmlns:xsi=", "xmlns:xs="),
            "3:8: unknown attribute xmlns:xs on <scene>",
        ),
        (
            NAMED.replace("xsi:noNamespaceSchemaLocation", "xsi:schemaLocation"),
            "4:8: unknown attribute xsi:schemaLocation on <scene>",
        ),
    ] {
        let err = rayoflight::scene::parse(&text, Path::new("s.xml"))
            .expect_err(message)
            .to_string();
        assert!(err.starts_with(&format!("s.xml:{message}")), "{err}");
    }
}

// ----- the desktop -----

/// Every file and folder under `dir`, relative, sorted.
#[cfg(feature = "gui")]
fn tree(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
        for entry in fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            out.push(path.strip_prefix(root).unwrap().display().to_string());
            if path.is_dir() {
                walk(root, &path, out);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// `install-desktop` with `home` as the data folder, a config folder
/// beside it and no system folders (none of this machine's applications).
#[cfg(feature = "gui")]
fn install_desktop(home: &Path, args: &[&str]) -> std::process::Output {
    let beside = |name| home.with_file_name(name).into_os_string();
    let places = [
        ("XDG_DATA_HOME", home.as_os_str().to_owned()),
        ("XDG_CONFIG_HOME", beside("config")),
        ("XDG_DATA_DIRS", beside("no-system-data")),
        ("XDG_CONFIG_DIRS", beside("no-system-config")),
    ];
    install_desktop_in(&places, args)
}

/// `install-desktop` with these XDG folders and no desktop named.
#[cfg(feature = "gui")]
fn install_desktop_in(
    places: &[(&str, std::ffi::OsString)],
    args: &[&str],
) -> std::process::Output {
    Command::new(BIN)
        .arg("install-desktop")
        .args(args)
        .envs(places.iter().map(|(k, v)| (k, v)))
        .env_remove("XDG_CURRENT_DESKTOP")
        .output()
        .unwrap()
}

#[cfg(feature = "gui")]
#[test]
fn install_desktop_and_back_out_leaves_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    // A data folder a user already has: another app's entry and type.
    let home = dir.path().join("share");
    fs::create_dir_all(home.join("applications")).unwrap();
    fs::write(
        home.join("applications/other.desktop"),
        "[Desktop Entry]\nType=Application\nName=Other\nExec=other %f\nMimeType=text/plain;\n",
    )
    .unwrap();
    let before = tree(&home);

    let o = install_desktop(&home, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let id = rayoflight::desktop::APP_ID;
    let entry = home.join(format!("applications/{id}.desktop"));
    let text = fs::read_to_string(&entry).unwrap();
    let exec = fs::canonicalize(BIN).unwrap();
    assert!(
        text.contains(&format!("\nExec={} %f\n", exec.display())),
        "{text}"
    );
    for icon in [
        format!("icons/hicolor/scalable/apps/{id}.svg"),
        format!("icons/hicolor/48x48/apps/{id}.png"),
        format!("icons/hicolor/256x256/apps/{id}.png"),
        format!("mime/packages/{id}.xml"),
    ] {
        assert!(home.join(&icon).is_file(), "{icon}");
    }
    let png = image::open(home.join(format!("icons/hicolor/48x48/apps/{id}.png"))).unwrap();
    assert_eq!((png.width(), png.height()), (48, 48));
    if tool("desktop-file-validate", "desktop-file-utils") {
        let o = Command::new("desktop-file-validate")
            .arg(&entry)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));
        assert_eq!(stdout(&o), "");
    }
    if tool("update-mime-database", "shared-mime-info") {
        // The type of its own: a scene that names the schema, as the
        // database says, and never every XML file.
        let globs = fs::read_to_string(home.join("mime/globs2")).unwrap();
        assert!(
            globs
                .lines()
                .any(|l| l.ends_with(":application/x-rayoflight-scene:*.rayoflight.xml")),
            "{globs}"
        );
        assert!(
            !globs
                .lines()
                .any(|l| l.ends_with(":application/x-rayoflight-scene:*.xml")),
            "{globs}"
        );
    }
    // Again: it replaces what it wrote.
    let o = install_desktop(&home, &[]);
    assert!(o.status.success(), "{}", stderr(&o));

    let o = install_desktop(&home, &["--uninstall"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let after: Vec<String> = tree(&home)
        .into_iter()
        .filter(|p| p != "applications/mimeinfo.cache")
        .collect();
    assert_eq!(after, before);
    // Twice: nothing to do.
    let o = install_desktop(&home, &["--uninstall"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("nothing to remove"), "{}", stderr(&o));

    // An empty data folder is left empty.
    let empty = dir.path().join("empty");
    fs::create_dir(&empty).unwrap();
    assert!(install_desktop(&empty, &[]).status.success());
    assert!(tree(&empty).len() > 10);
    assert!(install_desktop(&empty, &["--uninstall"]).status.success());
    assert_eq!(tree(&empty), Vec::<String>::new());
}

#[cfg(feature = "gui")]
#[test]
fn install_desktop_never_writes_over_a_file_it_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let id = rayoflight::desktop::APP_ID;
    let mine = dir
        .path()
        .join(format!("icons/hicolor/48x48/apps/{id}.png"));
    fs::create_dir_all(mine.parent().unwrap()).unwrap();
    fs::write(&mine, "the user's own icon").unwrap();
    let before = tree(dir.path());
    let o = install_desktop(dir.path(), &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("was not written by install-desktop; nothing was written"),
        "{}",
        stderr(&o)
    );
    assert_eq!(tree(dir.path()), before);
    assert_eq!(fs::read(&mine).unwrap(), b"the user's own icon");
}

#[test]
fn the_repositorys_desktop_files_pass_their_validators() {
    let linux = Path::new(ROOT).join("assets/linux");
    let id = rayoflight::desktop::APP_ID;
    if tool("desktop-file-validate", "desktop-file-utils") {
        let o = Command::new("desktop-file-validate")
            .arg(linux.join(format!("{id}.desktop")))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stdout(&o));
        assert_eq!(stdout(&o), "", "desktop-file-validate has remarks");
    }
    if tool("appstreamcli", "appstream") {
        let o = Command::new("appstreamcli")
            .args(["validate", "--pedantic", "--no-net", "--no-color"])
            .arg(linux.join(format!("{id}.metainfo.xml")))
            .output()
            .unwrap();
        let said = format!("{}{}", stdout(&o), stderr(&o));
        assert!(o.status.success(), "{said}");
        // No error or warning; infos and pedantic hints are listed in
        // the README (a capital in the id, Debian 12's older tag list).
        assert!(
            !said
                .lines()
                .any(|l| l.starts_with("E:") || l.starts_with("W:")),
            "{said}"
        );
    }
    if tool("xmllint", "libxml2-utils") {
        let o = Command::new("xmllint")
            .arg("--noout")
            .arg(linux.join(format!("{id}.mime.xml")))
            .arg(linux.join(format!("{id}.svg")))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
    }
}

// ----- a starting scene -----

#[test]
fn new_writes_the_example_and_never_over_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let o = rayoflight(dir.path(), &["new", "start.xml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let written = fs::read_to_string(dir.path().join("start.xml")).unwrap();
    assert_eq!(written, rayoflight::EXAMPLE_SCENE);
    assert!(rayoflight::scene::load(&dir.path().join("start.xml")).is_ok());

    fs::write(dir.path().join("mine.xml"), "my own words").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("nowhere.xml", dir.path().join("dangling.xml")).unwrap();
    for name in ["mine.xml", "dangling.xml", "start.xml"] {
        let o = rayoflight(dir.path(), &["new", name]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        assert!(
            stderr(&o).contains(&format!("{name}: already exists; nothing was written")),
            "{}",
            stderr(&o)
        );
    }
    assert_eq!(
        fs::read_to_string(dir.path().join("mine.xml")).unwrap(),
        "my own words"
    );
    assert_eq!(
        files_in(dir.path()),
        ["dangling.xml", "mine.xml", "start.xml"]
    );
    let o = rayoflight(dir.path(), &["new", "-"]);
    assert_eq!(stdout(&o), rayoflight::EXAMPLE_SCENE);
}

/// Install-desktop writes and deletes only what it
/// owns. After an install, a file another program replaced and an icon
/// the user edited are left by `--uninstall` and named (it deleted both);
/// a desktop entry replaced by a link to the user's notes is not written
/// through by a second install (it overwrote the notes), nor is a folder
/// link; in a fresh home without `~/.local/share` it makes the folders,
/// records them, and removes them again (it failed: "No such file or
/// directory").
#[cfg(all(feature = "gui", unix))]
#[test]
fn install_desktop_writes_and_removes_only_what_it_owns() {
    let id = rayoflight::desktop::APP_ID;
    let dir = tempfile::tempdir().unwrap();
    // A fresh home: no .local at all. Made, then removed again.
    let home = dir.path().join("home/.local/share");
    fs::create_dir(dir.path().join("home")).unwrap();
    let o = install_desktop(&home, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(home.join(format!("applications/{id}.desktop")).is_file());
    let o = install_desktop(&home, &["--uninstall"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(tree(&dir.path().join("home")), Vec::<String>::new());

    let o = install_desktop(&home, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let entry = home.join(format!("applications/{id}.desktop"));
    let svg = home.join(format!("icons/hicolor/scalable/apps/{id}.svg"));
    fs::write(&entry, "[Desktop Entry]\nName=Another program's\n").unwrap();
    let mut edited = fs::read_to_string(&svg).unwrap();
    edited.push_str("<!-- the user's touch -->\n");
    fs::write(&svg, &edited).unwrap();
    let o = install_desktop(&home, &["--uninstall"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for kept in [&entry, &svg] {
        assert!(
            stderr(&o).contains(&format!(
                "left {}: it changed since install-desktop wrote it",
                kept.display()
            )),
            "{}",
            stderr(&o)
        );
    }
    assert_eq!(
        fs::read_to_string(&entry).unwrap(),
        "[Desktop Entry]\nName=Another program's\n"
    );
    assert_eq!(fs::read_to_string(&svg).unwrap(), edited);
    // Nothing else of it is left: only the two changed files, in their
    // folders (and the desktop database's cache, as an entry is left).
    let left: Vec<String> = tree(&home)
        .into_iter()
        .filter(|p| p.contains('.') && !p.ends_with("mimeinfo.cache"))
        .collect();
    assert_eq!(
        left,
        [
            format!("applications/{id}.desktop"),
            format!("icons/hicolor/scalable/apps/{id}.svg")
        ],
    );

    // Installed again; the entry replaced by a link to the user's notes.
    let home = dir.path().join("share");
    assert!(install_desktop(&home, &[]).status.success());
    let notes = dir.path().join("notes.txt");
    fs::write(&notes, "my notes\n").unwrap();
    let entry = home.join(format!("applications/{id}.desktop"));
    fs::remove_file(&entry).unwrap();
    std::os::unix::fs::symlink(&notes, &entry).unwrap();
    let o = install_desktop(&home, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("a symbolic link install-desktop did not make"));
    assert_eq!(fs::read_to_string(&notes).unwrap(), "my notes\n");
    fs::remove_file(&entry).unwrap();

    // A folder link to elsewhere is not written through.
    let elsewhere = dir.path().join("elsewhere");
    fs::create_dir(&elsewhere).unwrap();
    let home = dir.path().join("linked");
    fs::create_dir(&home).unwrap();
    std::os::unix::fs::symlink(&elsewhere, home.join("icons")).unwrap();
    let o = install_desktop(&home, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!(
            "{}: a symbolic link install-desktop did not make",
            home.join("icons").display()
        )),
        "{}",
        stderr(&o)
    );
    assert_eq!(tree(&elsewhere), Vec::<String>::new());
    assert_eq!(tree(&home), ["icons"]);
}

/// A throwaway desktop under `dir`: system applications (`system/`) with
/// these entries (name, MIME types; each runs `cat`, which exists: gio
/// lists an entry only if its program does), the user's data folder
/// `share/` and config folder `config/`, no system config; the XDG
/// variables that say so.
#[cfg(all(feature = "gui", unix))]
fn throwaway_desktop(
    dir: &Path,
    entries: &[(&str, &str)],
) -> [(&'static str, std::ffi::OsString); 4] {
    let system = dir.join("system");
    fs::create_dir_all(system.join("applications")).unwrap();
    for (name, types) in entries {
        fs::write(
            system.join(format!("applications/{name}.desktop")),
            format!(
                "[Desktop Entry]\nType=Application\nName={name}\nExec=cat %f\nMimeType={types}\n"
            ),
        )
        .unwrap();
    }
    [
        ("XDG_DATA_HOME", dir.join("share").into_os_string()),
        ("XDG_CONFIG_HOME", dir.join("config").into_os_string()),
        ("XDG_DATA_DIRS", system.into_os_string()),
        ("XDG_CONFIG_DIRS", dir.join("etc").into_os_string()),
    ]
}

/// An XML editor is installed for the system and nobody chose a default
/// for XML: gio and xdg-mime named RayOfLight the default for every XML
/// file once it was installed (they prefer the user's own folder). Now the
/// editor stays the default (written as the user's choice, in the user's
/// `mimeapps.list`, a file of theirs or none yet), RayOfLight is offered
/// for XML and is the default for scenes; the uninstall gives the list
/// back byte for byte. A default the user chose is left alone; a pinned
/// line the user changed since stays.
#[cfg(all(feature = "gui", unix))]
#[test]
fn install_desktop_leaves_xml_to_the_editor_that_had_it() {
    if !(tool("gio", "libglib2.0-bin")
        && tool("xdg-mime", "xdg-utils")
        && tool("update-desktop-database", "desktop-file-utils"))
    {
        return;
    }
    let id = rayoflight::desktop::APP_ID;
    let ours = format!("{id}.desktop");
    for user_list in [
        None,
        Some("[Added Associations]\ntext/plain=xmleditor.desktop;"),
        Some(
            "# mine\n[Default Applications]\ntext/plain=xmleditor.desktop;\n\n[Added Associations]\n",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let places = throwaway_desktop(
            dir.path(),
            &[
                ("xmleditor", "application/xml;text/xml;"),
                ("other", "text/xml;"),
            ],
        );
        let o = Command::new("update-desktop-database")
            .arg(dir.path().join("system/applications"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let config = dir.path().join("config");
        let list = config.join("mimeapps.list");
        if let Some(text) = user_list {
            fs::create_dir(&config).unwrap();
            fs::write(&list, text).unwrap();
        }
        let defaults = |mime: &str| -> (String, String, String) {
            let gio = Command::new("gio")
                .args(["mime", mime])
                .envs(places.iter().map(|(k, v)| (k, v)))
                .env_remove("XDG_CURRENT_DESKTOP")
                .output()
                .unwrap();
            let gio = stdout(&gio);
            let xdg = Command::new("xdg-mime")
                .args(["query", "default", mime])
                .envs(places.iter().map(|(k, v)| (k, v)))
                .env_remove("XDG_CURRENT_DESKTOP")
                .env_remove("DESKTOP_SESSION")
                .output()
                .unwrap();
            let first = gio.lines().next().unwrap_or_default();
            let default = first.rsplit(": ").next().unwrap_or_default().to_owned();
            let recommended = gio
                .split("Recommended applications:")
                .nth(1)
                .unwrap_or_default();
            (
                default,
                stdout(&xdg).trim().to_owned(),
                recommended.to_owned(),
            )
        };
        // Who opens XML before: the same for both tools, one of the two.
        let had: Vec<String> = ["application/xml", "text/xml"]
            .iter()
            .map(|mime| {
                let (gio, xdg, _) = defaults(mime);
                assert_eq!(gio, xdg, "{mime} before");
                assert!(
                    gio == "xmleditor.desktop" || gio == "other.desktop",
                    "{gio}"
                );
                gio
            })
            .collect();
        let before = tree(dir.path());

        let o = install_desktop_in(&places, &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!(
                "{} stays the default for application/xml, as your choice in",
                had[0]
            )),
            "{}",
            stderr(&o)
        );
        for (mime, had) in ["application/xml", "text/xml"].iter().zip(&had) {
            let (gio, xdg, recommended) = defaults(mime);
            assert_eq!((&gio, &xdg), (had, had), "{mime} after");
            assert!(recommended.contains(&ours), "{mime}: {recommended}");
        }
        let (gio, _, _) = defaults("application/x-rayoflight-scene");
        assert_eq!(gio, ours);
        let pinned = fs::read_to_string(&list).unwrap();
        assert!(
            pinned.contains(&format!(
                "[Default Applications]\napplication/xml={}\ntext/xml={}\n",
                had[0].clone() + ";",
                had[1].clone() + ";"
            )),
            "{pinned}"
        );
        // Installed again: nothing more written into the list.
        assert!(install_desktop_in(&places, &[]).status.success());
        assert_eq!(fs::read_to_string(&list).unwrap(), pinned);

        let o = install_desktop_in(&places, &["--uninstall"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let after: Vec<String> = tree(dir.path())
            .into_iter()
            .filter(|p| p != "share/applications/mimeinfo.cache")
            .collect();
        assert_eq!(after, before);
        match user_list {
            Some(text) => assert_eq!(fs::read_to_string(&list).unwrap(), text),
            None => assert!(!config.exists()),
        }

        // The user's own choice of default: not written over, nor added to.
        fs::create_dir_all(&config).unwrap();
        let chosen =
            "[Default Applications]\napplication/xml=other.desktop;\ntext/xml=other.desktop;\n";
        fs::write(&list, chosen).unwrap();
        assert!(install_desktop_in(&places, &[]).status.success());
        assert_eq!(fs::read_to_string(&list).unwrap(), chosen);
        assert_eq!(defaults("application/xml").0, "other.desktop");
        assert!(
            install_desktop_in(&places, &["--uninstall"])
                .status
                .success()
        );
        assert_eq!(fs::read_to_string(&list).unwrap(), chosen);

        // A pinned line the user changed since is theirs: it stays.
        fs::remove_file(&list).unwrap();
        assert!(install_desktop_in(&places, &[]).status.success());
        let pinned = fs::read_to_string(&list).unwrap();
        let line = format!("application/xml={};", had[0]);
        let changed = pinned.replace(&line, "application/xml=cat.desktop;");
        fs::write(&list, &changed).unwrap();
        let o = install_desktop_in(&places, &["--uninstall"]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!("left the default {line} out of")),
            "{}",
            stderr(&o)
        );
        assert_eq!(
            fs::read_to_string(&list).unwrap(),
            "[Default Applications]\napplication/xml=cat.desktop;\n"
        );
    }
}

/// The user's `mimeapps.list` is written back as read but for the lines
/// added: one that is not UTF-8 is not rewritten at all (its bytes would
/// have become U+FFFD), and the install says the default was not kept and
/// writes no file (its folders, recorded, go with the uninstall). A
/// reinstall after the user removed the list pins again without
/// recording the lines twice (the uninstall named the second as changed).
#[cfg(all(feature = "gui", unix))]
#[test]
fn install_desktop_never_rewrites_a_list_it_cannot_read_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let places = throwaway_desktop(dir.path(), &[("xmleditor", "application/xml;text/xml;")]);
    let config = dir.path().join("config");
    fs::create_dir(&config).unwrap();
    let list = config.join("mimeapps.list");
    let latin1 = b"# caf\xe9\n[Added Associations]\ntext/plain=xmleditor.desktop;\n".to_vec();
    fs::write(&list, &latin1).unwrap();
    let before = tree(dir.path());
    let o = install_desktop_in(&places, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("nothing installed: the application that opens XML files could not be kept as the default")
            && stderr(&o).contains("not UTF-8 text; left as it is"),
        "{}",
        stderr(&o)
    );
    assert_eq!(fs::read(&list).unwrap(), latin1);
    // No entry that would have taken XML from the editor that has it.
    let entry = format!("share/applications/{}.desktop", rayoflight::desktop::APP_ID);
    assert!(!dir.path().join(&entry).exists());
    let o = install_desktop_in(&places, &["--uninstall"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("folders install-desktop made, empty (it wrote no file under"),
        "{}",
        stderr(&o)
    );
    assert_eq!(fs::read(&list).unwrap(), latin1);
    assert_eq!(tree(dir.path()), before);

    // Pinned, the list removed by the user, installed again: pinned
    // again, recorded once.
    fs::remove_file(&list).unwrap();
    assert!(install_desktop_in(&places, &[]).status.success());
    fs::remove_file(&list).unwrap();
    let o = install_desktop_in(&places, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let record = fs::read_to_string(dir.path().join("share/rayoflight/installed-files")).unwrap();
    assert_eq!(
        record.matches("default application/xml=").count(),
        1,
        "{record}"
    );
    let o = install_desktop_in(&places, &["--uninstall"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("left the default"), "{}", stderr(&o));
    assert!(!list.exists());
}
