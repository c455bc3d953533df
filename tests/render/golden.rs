//! Golden tests: every scene in `scenes/golden/` rendered with the default
//! options must match the POV-Ray 3.7 reference in `tests/golden/<name>.png`
//! (made by `tests/golden/regenerate.sh` through `pov::export`; see
//! docs/scene-format.md, Cross-checking with POV-Ray).
//!
//! Tolerance (never loosen it): at least 99.99 % of the pixels within one
//! 8-bit level on every channel, and no pixel off by more than 8 unless it is
//! isolated (none of its 8 neighbours is off by more than 8). On failure the
//! statistics are printed and a diff image is written to
//! `target/golden-diff/<name>.png` (our render next to it as
//! `<name>-ours.png`).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use image::{Rgb, RgbImage};
use rayoflight::render::{RenderOptions, render};

/// Every golden scene. A scene or a reference missing from disk fails the
/// test; so does a scene on disk that is not listed here.
const SCENES: &[&str] = &[
    "camera-rotated",
    "coloured-lights",
    "ellipsoids",
    "example-ambient",
    "example-lambert",
    "example-phong",
    "example-whitted-d0",
    "example-whitted-d1",
    "example-whitted-d2",
    "example-whitted-d3",
    "far-origin",
    "floor-wall",
    "grazing-plane",
    "inside-sphere",
    "mirror-corridor",
    "mirror-spheres",
    "mirrored",
    "tall-120x240",
    "wide-320x180",
];

/// The scene the POV-Ray reproducibility test re-renders (small and quick,
/// with reflections and a sphere between the eye and the screen).
const POV_CHECK_SCENE: &str = "tall-120x240";

/// A pixel off by more than this must be isolated.
const BIG_DIFF: u8 = 8;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scene_path(name: &str) -> PathBuf {
    root().join("scenes/golden").join(format!("{name}.xml"))
}

fn reference_path(name: &str) -> PathBuf {
    root().join("tests/golden").join(format!("{name}.png"))
}

fn diff_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    let target = if target.is_relative() {
        root().join(target)
    } else {
        target
    };
    target.join("golden-diff")
}

fn read_png(path: &Path) -> RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("cannot read reference {}: {e}", path.display()))
        .to_rgb8()
}

fn render_scene(name: &str) -> RgbImage {
    let path = scene_path(name);
    let scene = rayoflight::scene::load(&path)
        .unwrap_or_else(|e| panic!("cannot load {}: {e}", path.display()));
    render(&scene, &RenderOptions::default())
        .unwrap_or_else(|e| panic!("cannot render {}: {e}", path.display()))
}

/// How two images of the same size differ.
#[derive(Debug)]
struct Comparison {
    pixels: usize,
    /// Pixels within one level on every channel.
    within_one: usize,
    /// Pixels off by more than [`BIG_DIFF`] on some channel.
    big: usize,
    /// Big pixels with a big neighbour.
    big_clustered: usize,
    max_diff: u8,
    /// Where the largest difference is, and the two colours there.
    worst: (u32, u32, [u8; 3], [u8; 3]),
    /// Per pixel: the largest channel difference.
    diffs: Vec<u8>,
}

impl Comparison {
    fn new(ours: &RgbImage, reference: &RgbImage) -> Comparison {
        let (w, h) = ours.dimensions();
        let diffs = rayoflight::render::measure::pixel_differences(ours, reference);
        let mut worst = (0, 0, [0; 3], [0; 3]);
        let mut max_diff = 0;
        for (k, &d) in diffs.iter().enumerate() {
            if d > max_diff {
                let (x, y) = (k as u32 % w, k as u32 / w);
                max_diff = d;
                worst = (x, y, ours.get_pixel(x, y).0, reference.get_pixel(x, y).0);
            }
        }
        let at = |x: i64, y: i64| -> u8 {
            if x < 0 || y < 0 || x >= i64::from(w) || y >= i64::from(h) {
                0
            } else {
                diffs[(y * i64::from(w) + x) as usize]
            }
        };
        let mut big = 0;
        let mut big_clustered = 0;
        for y in 0..i64::from(h) {
            for x in 0..i64::from(w) {
                if at(x, y) <= BIG_DIFF {
                    continue;
                }
                big += 1;
                let neighbour_big = (-1..=1).any(|dy| {
                    (-1..=1).any(|dx| (dx, dy) != (0, 0) && at(x + dx, y + dy) > BIG_DIFF)
                });
                if neighbour_big {
                    big_clustered += 1;
                }
            }
        }
        Comparison {
            pixels: diffs.len(),
            within_one: diffs.iter().filter(|&&d| d <= 1).count(),
            big,
            big_clustered,
            max_diff,
            worst,
            diffs,
        }
    }

    /// ≥ 99.99 % within one level, and big differences isolated.
    fn passes(&self) -> bool {
        self.within_one as u128 * 10_000 >= self.pixels as u128 * 9_999 && self.big_clustered == 0
    }

    fn summary(&self) -> String {
        let (x, y, a, b) = self.worst;
        format!(
            "{:.4} % within 1 level ({} of {} pixels off by more), max diff {} \
             (at {x},{y}: ours {a:?}, POV-Ray {b:?}), {} off by more than {BIG_DIFF} \
             ({} of them not isolated)",
            100.0 * self.within_one as f64 / self.pixels as f64,
            self.pixels - self.within_one,
            self.pixels,
            self.max_diff,
            self.big,
            self.big_clustered,
        )
    }

    /// Black where equal, grey for one level, yellow up to 8, red above.
    fn diff_image(&self, w: u32, h: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| match self.diffs[(y * w + x) as usize] {
            0 => Rgb([0, 0, 0]),
            1 => Rgb([70, 70, 70]),
            d if d <= BIG_DIFF => Rgb([255, 200, 0]),
            _ => Rgb([255, 0, 0]),
        })
    }
}

fn write_diff(name: &str, cmp: &Comparison, ours: &RgbImage) {
    let dir = diff_dir();
    let _ = std::fs::create_dir_all(&dir);
    let (w, h) = ours.dimensions();
    let _ = cmp.diff_image(w, h).save(dir.join(format!("{name}.png")));
    let _ = ours.save(dir.join(format!("{name}-ours.png")));
    eprintln!(
        "  diff image: {}",
        dir.join(format!("{name}.png")).display()
    );
}

fn sorted_names(dir: &Path, ext: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .filter_map(|entry| {
            let path = entry.ok()?.path();
            (path.extension()? == ext).then(|| path.file_stem()?.to_str().map(str::to_owned))?
        })
        .collect();
    names.sort();
    names
}

#[test]
fn golden_scene_set_is_complete() {
    let expected: Vec<String> = SCENES.iter().map(|s| s.to_string()).collect();
    assert!(
        expected.windows(2).all(|p| p[0] < p[1]),
        "SCENES must be sorted"
    );
    let scenes = sorted_names(&root().join("scenes/golden"), "xml");
    assert_eq!(scenes, expected, "scenes/golden/*.xml differs from SCENES");
    let references = sorted_names(&root().join("tests/golden"), "png");
    assert_eq!(
        references, expected,
        "tests/golden/*.png differs from SCENES (run tests/golden/regenerate.sh)"
    );
}

#[test]
fn golden_scenes_match_pov_ray() {
    let mut failures = Vec::new();
    for &name in SCENES {
        let reference = read_png(&reference_path(name));
        let ours = render_scene(name);
        if ours.dimensions() != reference.dimensions() {
            eprintln!(
                "{name}: size {:?}, reference {:?}",
                ours.dimensions(),
                reference.dimensions()
            );
            failures.push(name);
            continue;
        }
        let cmp = Comparison::new(&ours, &reference);
        let verdict = if cmp.passes() { "ok  " } else { "FAIL" };
        eprintln!("{verdict} {name}: {}", cmp.summary());
        if !cmp.passes() {
            write_diff(name, &cmp, &ours);
            failures.push(name);
        }
    }
    assert!(
        failures.is_empty(),
        "golden scenes differ from POV-Ray: {failures:?}"
    );
}

/// Re-renders one golden scene with POV-Ray through the exporter and checks
/// that it reproduces the committed reference (within one level on every
/// pixel): the references are what POV-Ray makes of our export today.
#[test]
fn committed_reference_is_reproducible_with_pov_ray() {
    let available = Command::new("povray")
        .arg("--version")
        .output()
        .is_ok_and(|o| {
            String::from_utf8_lossy(&o.stdout).contains("POV-Ray 3.7")
                || String::from_utf8_lossy(&o.stderr).contains("POV-Ray 3.7")
        });
    if !available && !common::tool("povray", "povray") {
        return;
    }
    assert!(
        available,
        "POV-Ray 3.7 is needed (`povray --version` says another)"
    );

    let name = POV_CHECK_SCENE;
    let path = scene_path(name);
    let scene = rayoflight::scene::load(&path)
        .unwrap_or_else(|e| panic!("cannot load {}: {e}", path.display()));
    let dir = tempfile::tempdir().unwrap();
    let home = dir.path().join("home");
    std::fs::create_dir_all(home.join(".povray/3.7")).unwrap();
    std::fs::write(home.join(".povray/3.7/povray.conf"), "").unwrap();
    let (xml, written) = (format!("{name}.xml"), format!("{name}.pov"));
    let header = rayoflight::pov::Header {
        scene: Path::new(&xml),
        written_to: Path::new(&written),
    };
    let pov = rayoflight::pov::export_named(&scene, Some(header));
    std::fs::write(dir.path().join(format!("{name}.pov")), pov).unwrap();
    let output = Command::new("povray")
        .current_dir(dir.path())
        .env("HOME", &home)
        .args(["-D", "-A", "+FN", "File_Gamma=1.0"])
        .arg(format!("+W{}", scene.camera.width))
        .arg(format!("+H{}", scene.camera.height))
        .arg(format!("+I{name}.pov"))
        .arg(format!("+O{name}.png"))
        .output()
        .expect("cannot run povray");
    assert!(
        output.status.success(),
        "povray failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let fresh = read_png(&dir.path().join(format!("{name}.png")));
    let committed = read_png(&reference_path(name));
    assert_eq!(fresh.dimensions(), committed.dimensions());
    let cmp = Comparison::new(&fresh, &committed);
    assert!(
        cmp.max_diff <= 1,
        "POV-Ray no longer reproduces tests/golden/{name}.png: {}",
        cmp.summary()
    );
}
