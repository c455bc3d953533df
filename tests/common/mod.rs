//! Helpers shared by the test crates: the built binary's output, a tiny
//! scene, and a small deterministic random generator.
#![allow(dead_code)] // each test crate uses its own subset

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

/// xorshift64*: a small deterministic generator (seed ≠ 0).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A number in 0..n (0 when n is 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A 16×12 scene: one sphere, one light.
pub const TINY: &str = r#"<scene>
  <sphere><transformation><translate z="3"/></transformation></sphere>
  <light x="0" y="-3" z="-3"/>
  <camera width="16" height="12" eyeDistance="2"/>
</scene>
"#;

/// Two facing perfect mirrors with the camera between them, whitted
/// `depth`: every pixel bounces until the depth runs out. Slow on purpose
/// (depth 10 000 at 1920×1080 is seconds of work).
pub fn mirrors_text(depth: u32, width: u32, height: u32) -> String {
    format!(
        r#"<scene>
  <plane><material ka="0" kd="0.1" ks="1" m="1"/><transformation><translate z="5"/></transformation></plane>
  <plane><material ka="0" kd="0.1" ks="1" m="1"/><transformation><translate z="-5"/></transformation></plane>
  <light x="0" y="-1" z="0"/>
  <camera width="{width}" height="{height}" eyeDistance="1"/>
  <model type="whitted" depth="{depth}"/>
</scene>
"#
    )
}

/// Runs the built binary in `dir` with no display, so that it never opens
/// a window.
pub fn rayoflight(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .args(args)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The names in `dir`, sorted: what a command left behind.
pub fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The fuzz corpus (`fuzz/corpus/`), in file-name order: each file's bytes.
pub fn fuzz_corpus() -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    let mut files: Vec<std::path::PathBuf> = fs::read_dir(&dir)
        .expect("fuzz/corpus exists")
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.iter().map(|f| fs::read(f).unwrap()).collect()
}

/// A number from the environment (the fuzzers' seconds and seed), or
/// `default`.
pub fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A new temporary folder holding `files` (name, text) as a user's folder
/// holds them: the folder readable by all (0755), each file 0644, so that
/// a command run as another user can read them.
pub fn folder_with(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        fs::write(dir.path().join(name), text).unwrap();
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(dir.path(), fs::Permissions::from_mode(0o755)).unwrap();
        for (name, _) in files {
            fs::set_permissions(dir.path().join(name), fs::Permissions::from_mode(0o644)).unwrap();
        }
    }
    dir
}

/// A new temporary folder holding one scene file `name` with `text`: the
/// folder (kept while it lives) and the file's path.
pub fn scene_file(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = folder_with(&[(name, text)]);
    let path = dir.path().join(name);
    (dir, path)
}

/// A named pipe at `path` (coreutils' `mkfifo`).
#[cfg(unix)]
pub fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo").arg(path).status().unwrap().success();
    assert!(made, "mkfifo {}", path.display());
}

/// Whether the tests run as root (in CI they do: the tests that act as
/// another user need it).
#[cfg(unix)]
pub fn is_root() -> bool {
    rustix::process::geteuid().is_root()
}

/// A scene file holding `text` in a new temporary folder, opened as a
/// document: the folder (kept while it lives), the file's path, the
/// document.
#[cfg(feature = "session")]
pub fn document_on(
    text: &str,
) -> (
    tempfile::TempDir,
    std::path::PathBuf,
    rayoflight::session::document::Document,
) {
    let (dir, path) = scene_file("scene.xml", text);
    let doc = rayoflight::session::document::Document::open(&path).unwrap();
    (dir, path, doc)
}

/// The golden scenes' files (`scenes/golden/*.xml`), sorted.
pub fn golden_scenes() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/golden");
    let mut scenes: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .collect();
    scenes.sort();
    scenes
}

/// libxml2's `xmllint --noout` as an oracle of well-formed XML:
/// for each file, the line of the first error xmllint reports, or `None`
/// when it finds the file well-formed (warnings and namespace errors, which
/// leave its exit status 0, do not count). `None` as a whole when xmllint
/// is not installed and [`tool`] lets the test skip.
pub fn xmllint(files: &[std::path::PathBuf]) -> Option<Vec<Option<usize>>> {
    let output = match Command::new("xmllint")
        .args(["--noout", "--nonet"])
        .args(files)
        .output()
    {
        Ok(output) => output,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            assert!(
                !tool("xmllint", "libxml2-utils"),
                "xmllint did not run: {e}"
            );
            return None;
        }
        Err(e) => panic!("xmllint did not run: {e}"),
    };
    let stderr = String::from_utf8_lossy(&output.stderr);
    let lines: Vec<Option<usize>> = files
        .iter()
        .map(|file| {
            let prefix = format!("{}:", file.display());
            stderr.lines().find_map(|l| {
                let rest = l.strip_prefix(&prefix)?;
                let (line, kind) = rest.split_once(": ")?;
                let error = kind.contains("error :") && !kind.starts_with("namespace error");
                if error { line.parse().ok() } else { None }
            })
        })
        .collect();
    // Its exit status agrees with the errors read from its messages.
    assert_eq!(
        output.status.success(),
        lines.iter().all(Option::is_none),
        "xmllint's status and messages disagree: {}\n{stderr}",
        output.status
    );
    Some(lines)
}

/// Whether the program `tool` (from the Debian package `package`) is
/// installed. A test that needs one fails without it, naming the package
/// (.ci/run installs them all), unless `RAYOFLIGHT_SKIP_TOOLS` is set
/// outside CI: then it says on stderr that it is skipped and why.
pub fn tool(tool: &str, package: &str) -> bool {
    let found = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(tool).is_file()));
    if found {
        return true;
    }
    let skip =
        std::env::var_os("RAYOFLIGHT_SKIP_TOOLS").is_some() && std::env::var_os("CI").is_none();
    assert!(
        skip,
        "this test needs {tool}: install the Debian package {package} \
         (apt-get install {package}), or set RAYOFLIGHT_SKIP_TOOLS=1 to skip the tests that need a missing tool"
    );
    eprintln!("SKIPPED: {tool} is not installed (Debian package {package})");
    false
}
