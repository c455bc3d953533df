//! The renderer traces rays in packets: eight in an AVX-512 register, four
//! in an AVX2 register or four in two SSE2 registers, the widest the
//! processor has (`RAYOFLIGHT_SIMD=avx2` or `baseline` asks for narrower).
//! All must give the same image, byte for byte, with every study method:
//! whichever a machine takes, the picture is the reference image. (On a machine
//! without AVX-512 or AVX2 the wider ones fall back, and the comparison is
//! between fewer widths.)

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
/// lanes `simd` asks for (`None`: the widest).
fn render(scene: &Path, args: &[&str], simd: Option<&str>, out: &Path) -> Vec<u8> {
    let mut command = Command::new(env!("CARGO_BIN_EXE_rayoflight"));
    command
        .arg("--no-gui")
        .arg(scene)
        .arg("-out")
        .arg(out)
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    match simd {
        Some(lanes) => command.env("RAYOFLIGHT_SIMD", lanes),
        None => command.env_remove("RAYOFLIGHT_SIMD"),
    };
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
fn every_lane_width_gives_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    for (scene, args) in cases() {
        let baseline = render(&scene, &args, Some("baseline"), &out);
        for simd in [Some("avx2"), None] {
            let wider = render(&scene, &args, simd, &out);
            assert!(
                baseline == wider,
                "{} {args:?}: {simd:?} differs from the baseline lanes",
                scene.display()
            );
        }
    }
}
