//! Helpers shared by the tests that drive the built binary.
#![allow(dead_code)] // each test crate uses its own subset

use std::fs;
use std::path::Path;
use std::process::Output;

/// A 16×12 scene: one sphere, one light.
pub const TINY: &str = r#"<scene>
  <sphere><transformation><translate z="3"/></transformation></sphere>
  <light x="0" y="-3" z="-3"/>
  <camera width="16" height="12" eyeDistance="2"/>
</scene>
"#;

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
