//! The app in a real window, as a person sees it: started under Xvfb with
//! Mesa's software OpenGL, looked at through screenshots (ImageMagick's
//! `import`). The scene file is changed by atomic rename and the new colour
//! must be on screen within 2 s (3x allowed on a noisy CI machine); a broken
//! save keeps the old picture and shows the error banner; a fix recovers.
//! Screenshots are kept in target/tmp/gui-screenshots/ for people to see.
//!
//! Finally a render of whitted depth 10 000 between two mirrors at 4K is
//! started and the window closed with Ctrl+Q: the process must exit within
//! 1 s (3x allowed).
//!
//! Needs Xvfb, ImageMagick and xdotool (`apt-get install xvfb imagemagick
//! xdotool libgl1-mesa-dri`); `.ci/run` installs them. Fails, never skips,
//! when they are missing.
#![cfg(feature = "gui")]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A sphere filling much of a 200×200 image, shaded `ambient` with ka = 1,
/// so every sphere pixel is exactly the colour given.
fn scene(rgb: [u8; 3]) -> String {
    let c = rgb.map(|v| f64::from(v) / 255.0);
    format!(
        r#"<?xml version="1.0"?>
<!-- gui_window test scene -->
<scene>
  <sphere>
    <color red="{}" green="{}" blue="{}"/>
    <material ka="1" kd="0" ks="0" m="1"/>
    <transformation><scale factor="1.5"/><translate z="2"/></transformation>
  </sphere>
  <camera width="200" height="200" eyeDistance="2"/>
  <model type="ambient"/>
</scene>
"#,
        c[0], c[1], c[2]
    )
}

const RED: [u8; 3] = [255, 0, 0];
const GREEN: [u8; 3] = [0, 255, 0];
const BLUE: [u8; 3] = [0, 0, 255];
/// The error banner's fill (`gui::app`).
const BANNER: [u8; 3] = [120, 20, 20];

/// Replaces the file by rename, as vim and VS Code save.
fn atomic_save(path: &Path, text: &str) {
    let tmp = path.with_extension("xml.tmp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn start_xvfb() -> (Killed, String) {
    for n in 90..200 {
        if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
            || Path::new(&format!("/tmp/.X{n}-lock")).exists()
        {
            continue;
        }
        let display = format!(":{n}");
        let child = Command::new("Xvfb")
            .args([&display, "-screen", "0", "1280x900x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb runs (apt-get install xvfb)");
        let child = Killed(child);
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                return (child, display);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        panic!("Xvfb did not start on {display}");
    }
    panic!("no free X display number");
}

fn screenshot(display: &str, save_as: &Path) -> image::RgbImage {
    let out = Command::new("import")
        .args(["-display", display, "-window", "root"])
        .arg(format!("png:{}", save_as.display()))
        .output()
        .expect("ImageMagick's import runs (apt-get install imagemagick)");
    assert!(
        out.status.success(),
        "import failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    image::open(save_as).unwrap().to_rgb8()
}

fn count(image: &image::RgbImage, rgb: [u8; 3]) -> usize {
    image
        .pixels()
        .filter(|p| (0..3).all(|c| p.0[c].abs_diff(rgb[c]) <= 2))
        .count()
}

/// Takes screenshots until `ok` holds; returns the time it took.
fn wait_for(
    display: &str,
    shot: &Path,
    limit: Duration,
    what: &str,
    ok: impl Fn(&image::RgbImage) -> bool,
) -> Duration {
    let start = Instant::now();
    loop {
        let image = screenshot(display, shot);
        if ok(&image) {
            return start.elapsed();
        }
        assert!(
            start.elapsed() < limit,
            "{what}: not on screen after {limit:?}; see {}",
            shot.display()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn the_window_follows_saves_of_the_scene_file() {
    let shots = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("gui-screenshots");
    std::fs::create_dir_all(&shots).unwrap();
    let (_xvfb, display) = start_xvfb();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.xml");
    std::fs::write(&path, scene(RED)).unwrap();

    let app = Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .arg(&path)
        .env("DISPLAY", &display)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_CONFIG_HOME", dir.path())
        .env("LIBGL_ALWAYS_SOFTWARE", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut app = Killed(app);
    let sphere = 5_000;

    let took = wait_for(
        &display,
        &shots.join("1-start.png"),
        Duration::from_secs(60),
        "the first render",
        |s| count(s, RED) > sphere,
    );
    eprintln!("window with the first render after {took:?}");

    // A save by atomic rename: the new colour within 2 s (3x allowed).
    atomic_save(&path, &scene(GREEN));
    let took = wait_for(
        &display,
        &shots.join("2-saved.png"),
        Duration::from_secs(6),
        "the saved colour",
        |s| count(s, GREEN) > sphere && count(s, RED) < 50,
    );
    eprintln!("save to new pixels on screen: {took:?}");

    // A broken save: the app stays up, the picture stays, the banner shows.
    atomic_save(&path, "<scene>\n  <sphere>\n    <material ka=\"-1\"/>\n");
    let took = wait_for(
        &display,
        &shots.join("3-broken.png"),
        Duration::from_secs(6),
        "the error banner",
        |s| count(s, BANNER) > 2_000,
    );
    eprintln!("broken save to banner: {took:?}");
    let image = screenshot(&display, &shots.join("3-broken.png"));
    assert!(count(&image, GREEN) > sphere, "the last good picture stays");
    assert!(
        app.0.try_wait().unwrap().is_none(),
        "the app is still running"
    );

    // The fix: new picture, banner gone.
    atomic_save(&path, &scene(BLUE));
    let took = wait_for(
        &display,
        &shots.join("4-fixed.png"),
        Duration::from_secs(6),
        "the fixed scene",
        |s| count(s, BLUE) > sphere && count(s, BANNER) < 100,
    );
    eprintln!("fixed save to new pixels: {took:?}");
    assert!(
        app.0.try_wait().unwrap().is_none(),
        "the app is still running"
    );

    // A long render (whitted depth 10 000 between two perfect mirrors,
    // 3840×2160), then Ctrl+Q: the window closes within 1 s (3x allowed).
    atomic_save(&path, MIRRORS);
    std::thread::sleep(Duration::from_millis(800));
    assert!(
        app.0.try_wait().unwrap().is_none(),
        "rendering, still running"
    );
    let xdotool = |args: &[&str]| {
        Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &display)
            .output()
            .expect("xdotool runs (apt-get install xdotool)")
    };
    let found = xdotool(&["search", "--name", "RayOfLight"]);
    let window = String::from_utf8_lossy(&found.stdout)
        .lines()
        .next()
        .expect("the app's window is found")
        .to_owned();
    xdotool(&["windowfocus", "--sync", &window]);
    let start = Instant::now();
    xdotool(&["key", "--window", &window, "ctrl+q"]);
    loop {
        if let Some(status) = app.0.try_wait().unwrap() {
            let took = start.elapsed();
            eprintln!("window closed during a long render in {took:?} ({status})");
            assert!(status.success(), "clean exit");
            assert!(took < Duration::from_secs(3), "closing took {took:?}");
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(3),
            "the app did not exit within 3 s of Ctrl+Q"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Two facing perfect mirrors with the camera between them, whitted depth
/// 10 000 at 3840×2160: every pixel bounces until the depth runs out.
const MIRRORS: &str = r#"<scene>
  <plane><material ka="0" kd="0.1" ks="1" m="1"/><transformation><translate z="5"/></transformation></plane>
  <plane><material ka="0" kd="0.1" ks="1" m="1"/><transformation><translate z="-5"/></transformation></plane>
  <light x="0" y="-1" z="0"/>
  <camera width="3840" height="2160" eyeDistance="1"/>
  <model type="whitted" depth="10000"/>
</scene>
"#;
