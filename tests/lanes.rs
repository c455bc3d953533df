//! The renderer traces rays in packets: in AVX2 registers where the
//! processor has them, in pairs of SSE2 registers otherwise
//! (`RAYOFLIGHT_SIMD=baseline` asks for those). Both must give the same
//! image, byte for byte, with every study method: whichever a machine
//! takes, the picture is the contract's.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The golden scenes, with every method; the bench scenes (bigger), as
/// `auto` renders them.
fn cases() -> Vec<(PathBuf, Vec<&'static str>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut golden: Vec<PathBuf> = std::fs::read_dir(root.join("scenes/golden"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .collect();
    golden.sort();
    let methods = [
        "auto",
        "default",
        "textbook",
        "fixed-eps-1e-4",
        "no-offset",
        "no-early-stop",
        "draft",
        "aa2",
    ];
    let mut list = Vec::new();
    for scene in golden {
        for method in methods {
            list.push((scene.clone(), vec!["--method", method]));
        }
        list.push((scene, vec!["--aa", "3"]));
    }
    for name in ["mirrors", "room", "spheres-2000", "example-2000"] {
        list.push((root.join(format!("scenes/bench/{name}.xml")), vec![]));
    }
    list
}

/// The PNG the command line writes for `scene` with `args`, with the
/// baseline lanes or the widest.
fn render(scene: &Path, args: &[&str], baseline: bool, out: &Path) -> Vec<u8> {
    let mut command = Command::new(env!("CARGO_BIN_EXE_rayoflight"));
    command
        .arg("--no-gui")
        .arg(scene)
        .arg("-out")
        .arg(out)
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    if baseline {
        command.env("RAYOFLIGHT_SIMD", "baseline");
    } else {
        command.env_remove("RAYOFLIGHT_SIMD");
    }
    let o = command.output().unwrap();
    assert!(
        o.status.success(),
        "{}: {}",
        scene.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read(out).unwrap()
}

#[test]
fn baseline_and_widest_lanes_give_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    for (scene, args) in cases() {
        let baseline = render(&scene, &args, true, &out);
        let widest = render(&scene, &args, false, &out);
        assert!(
            baseline == widest,
            "{} {args:?}: the two lane widths differ",
            scene.display()
        );
    }
}
