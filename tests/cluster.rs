//! Past one machine: `--region` renders the same pixels as the whole
//! render, with every method and anti-aliasing; `assemble` puts
//! irregular parts back into the very file a one-machine render writes,
//! and refuses, naming the culprit, whatever does not fit; `split` covers
//! the image once with regions whose real cost (rays traced) is even.

mod common;

use common::{Rng, rayoflight, stderr, stdout};
use image::RgbImage;
use rayoflight::cluster::part::{self, Part};
use rayoflight::cluster::split;
use rayoflight::render::region::Region;
use rayoflight::render::request::RenderRequest;
use rayoflight::render::{self, RenderOptions};
use rayoflight::scene::{self, Scene};
use std::fs;
use std::path::{Path, PathBuf};

fn render(scene: &Scene, options: &RenderOptions) -> RgbImage {
    render::render(scene, options).expect("the render runs")
}

fn crop(image: &RgbImage, r: Region) -> RgbImage {
    image::imageops::crop_imm(image, r.x0, r.y0, r.width(), r.height()).to_image()
}

/// A random region of a `width × height` image: odd and even edges,
/// slivers one pixel wide, edges on and off the 32-pixel tile grid.
fn random_region(rng: &mut Rng, width: u32, height: u32) -> Region {
    let span = |rng: &mut Rng, size: u32| {
        let a = rng.below(size as usize) as u32;
        let b = rng.below(size as usize) as u32;
        let (lo, hi) = (a.min(b), a.max(b) + 1);
        match rng.below(4) {
            0 => (lo, lo + 1),
            _ => (lo, hi),
        }
    };
    let (x0, x1) = span(rng, width);
    let (y0, y1) = span(rng, height);
    Region::new(x0, y0, x1, y1).unwrap()
}

#[test]
fn a_region_is_the_same_rectangle_of_the_whole_render_with_every_method() {
    let mut rng = Rng(0x5eed_2026_1201);
    let mut checked = 0;
    for path in common::golden_scenes() {
        let scene = scene::load(&path).unwrap();
        let (width, height) = (scene.camera.width, scene.camera.height);
        let mut requests: Vec<RenderRequest> = rayoflight::render::methods()
            .into_iter()
            .map(|method| RenderRequest {
                method: Some(method),
                ..RenderRequest::default()
            })
            .collect();
        requests.push(RenderRequest {
            aa: Some(3),
            ..RenderRequest::default()
        });
        for request in requests {
            let options = request.options(&scene);
            let whole = render(&scene, &options);
            let mut regions: Vec<Region> = (0..4)
                .map(|_| random_region(&mut rng, width, height))
                .collect();
            regions.push(Region::whole(width, height));
            // Odd starts: a draft's 2×2 blocks begin outside the region.
            regions.push(Region::new(1, 1, width.min(71), height.min(37)).unwrap());
            for region in regions {
                let part = render(
                    &scene,
                    &RenderOptions {
                        region: Some(region),
                        ..options.clone()
                    },
                );
                let method = request.method.as_ref().map_or("aa 3", |m| m.name);
                assert!(
                    part == crop(&whole, region),
                    "{}: --region {region} with {method} differs from the whole render",
                    path.display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 1000, "{checked} regions checked");
}

/// A guillotine tiling of the image into about `count` irregular regions:
/// cuts at random pixels, odd ones included.
fn random_tiling(rng: &mut Rng, frame: Region, count: usize) -> Vec<Region> {
    let mut regions = vec![frame];
    while regions.len() < count {
        let k = rng.below(regions.len());
        let r = regions[k];
        let vertical = rng.below(2) == 0;
        let (start, end) = if vertical { (r.x0, r.x1) } else { (r.y0, r.y1) };
        if end - start < 2 {
            continue;
        }
        let at = start + 1 + rng.below((end - start - 1) as usize) as u32;
        let (a, b) = if vertical {
            (Region { x1: at, ..r }, Region { x0: at, ..r })
        } else {
            (Region { y1: at, ..r }, Region { y0: at, ..r })
        };
        regions[k] = a;
        regions.push(b);
    }
    regions
}

/// Renders `scene_file`'s regions with the CLI (extra arguments `args`)
/// into `dir`: the parts' paths.
fn render_parts(dir: &Path, scene_file: &Path, regions: &[Region], args: &[&str]) -> Vec<PathBuf> {
    let stem = scene_file.file_stem().unwrap().to_string_lossy();
    let taken = common::files_in(dir).len();
    regions
        .iter()
        .enumerate()
        .map(|(k, region)| {
            let part = dir.join(format!("{stem}-{taken}-{k}.png"));
            let region = region.to_string();
            let mut all = vec![
                scene_file.to_str().unwrap(),
                "--region",
                &region,
                "-out",
                part.to_str().unwrap(),
                "--quiet",
            ];
            all.extend(args);
            let out = rayoflight(dir, &all);
            assert!(out.status.success(), "{}", stderr(&out));
            part
        })
        .collect()
}

fn assemble(dir: &Path, out: &Path, parts: &[PathBuf]) -> std::process::Output {
    let mut args = vec!["assemble", "-out", out.to_str().unwrap()];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    rayoflight(dir, &args)
}

#[test]
fn irregular_parts_assemble_into_the_one_machine_file_on_every_golden_scene() {
    let mut rng = Rng(0xa55e_b1e5);
    for (k, path) in common::golden_scenes().into_iter().enumerate() {
        let dir = tempfile::tempdir().unwrap();
        let scene = scene::load(&path).unwrap();
        let frame = Region::whole(scene.camera.width, scene.camera.height);
        // Every third scene with anti-aliasing, every fifth as a draft.
        let mut extra: Vec<&str> = Vec::new();
        if k % 3 == 1 {
            extra.extend(["--aa", "2"]);
        }
        if k % 5 == 2 {
            extra.extend(["--method", "draft"]);
        }
        let whole = dir.path().join("whole.png");
        let mut args = vec![
            path.to_str().unwrap(),
            "-out",
            whole.to_str().unwrap(),
            "-q",
        ];
        args.extend(&extra);
        assert!(rayoflight(dir.path(), &args).status.success());
        let count = 3 + rng.below(6);
        let regions = random_tiling(&mut rng, frame, count);
        let mut parts = render_parts(dir.path(), &path, &regions, &extra);
        // Any order.
        parts.reverse();
        let assembled = dir.path().join("assembled.png");
        let out = assemble(dir.path(), &assembled, &parts);
        assert!(out.status.success(), "{}: {}", path.display(), stderr(&out));
        assert!(stdout(&out).is_empty() && stderr(&out).is_empty());
        assert!(
            fs::read(&assembled).unwrap() == fs::read(&whole).unwrap(),
            "{}: the assembled file differs from the one-machine render ({regions:?}, {extra:?})",
            path.display()
        );
    }
}

/// The message and exit status of `assemble` on `parts`, and that it
/// wrote nothing.
fn refused(dir: &Path, parts: &[PathBuf]) -> String {
    let out_file = dir.join("refused.png");
    let out = assemble(dir, &out_file, parts);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(!out_file.exists(), "nothing written");
    stderr(&out).trim().to_owned()
}

#[test]
fn assemble_refuses_what_does_not_fit_and_names_the_culprit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene_file = d.join("scene.xml");
    fs::write(&scene_file, rayoflight::EXAMPLE_SCENE.replace("600", "64")).unwrap();
    let scene = scene::load(&scene_file).unwrap();
    assert_eq!((scene.camera.width, scene.camera.height), (64, 64));
    let halves = [
        Region::new(0, 0, 64, 30).unwrap(),
        Region::new(0, 30, 64, 64).unwrap(),
    ];
    let parts = render_parts(d, &scene_file, &halves, &[]);
    let name = |p: &Path| p.display().to_string();
    let (top, bottom) = (parts[0].clone(), parts[1].clone());

    // A missing part: the pixels no part holds.
    assert_eq!(
        refused(d, std::slice::from_ref(&top)),
        "no part holds pixels 0,30,64,64 of the 64×64 image: a part is missing"
    );
    // The same part twice.
    assert_eq!(
        refused(d, &[top.clone(), bottom.clone(), top.clone()]),
        format!("{}: given twice", name(&top))
    );
    // Overlapping parts.
    let overlapping = render_parts(d, &scene_file, &[Region::new(0, 20, 64, 64).unwrap()], &[]);
    let over = d.join("over.png");
    fs::rename(&overlapping[0], &over).unwrap();
    assert_eq!(
        refused(d, &[top.clone(), over.clone()]),
        format!(
            "{} and {} overlap: both hold pixels 0,20,64,30",
            name(&top),
            name(&over)
        )
    );
    // A part of another scene, of other options.
    let other_scene = d.join("other.xml");
    fs::write(
        &other_scene,
        rayoflight::EXAMPLE_SCENE
            .replace("600", "64")
            .replace("0.3", "0.31"),
    )
    .unwrap();
    let other = render_parts(d, &other_scene, &halves[1..], &[]);
    let message = refused(d, &[top.clone(), other[0].clone()]);
    assert_eq!(
        message,
        format!(
            "{}: a part of another scene or other render options than {}",
            name(&other[0]),
            name(&top)
        )
    );
    let aa = render_parts(d, &scene_file, &halves[1..], &["--aa", "2"]);
    assert!(refused(d, &[top.clone(), aa[0].clone()]).contains("other render options"));
    // A part of another image size.
    let bigger = d.join("bigger.xml");
    fs::write(&bigger, rayoflight::EXAMPLE_SCENE.replace("600", "65")).unwrap();
    let wide = render_parts(d, &bigger, &halves[1..], &[]);
    assert_eq!(
        refused(d, &[top.clone(), wide[0].clone()]),
        format!(
            "{}: a part of a 65×65 image, but {} of a 64×64 one",
            name(&wide[0]),
            name(&top)
        )
    );
    // Records made by hand: another version, a region outside the image,
    // pixels of another size than the region.
    let options = RenderRequest::default().options(&scene);
    let pixels = image::open(&bottom).unwrap().to_rgb8();
    let forged = |file: &str, part: Part, image: &RgbImage| {
        let path = d.join(file);
        rayoflight::cluster::part::save(image, &part, &path).unwrap();
        path
    };
    let honest = Part::new(&scene, &options, halves[1]);
    let old = forged(
        "old.png",
        Part {
            version: "0.0.1".to_owned(),
            ..honest.clone()
        },
        &pixels,
    );
    assert_eq!(
        refused(d, &[top.clone(), old.clone()]),
        format!(
            "{}: made by rayoflight 0.0.1, but {} by {}: renderers of two versions may not agree",
            name(&old),
            name(&top),
            env!("CARGO_PKG_VERSION")
        )
    );
    let outside_region = Region::new(0, 30, 64, 70).unwrap();
    let outside = forged(
        "outside.png",
        Part {
            region: outside_region,
            ..honest.clone()
        },
        &RgbImage::new(64, 40),
    );
    assert_eq!(
        refused(d, &[top.clone(), outside.clone()]),
        format!(
            "{}: its region 0,30,64,70 is outside the 64×64 image",
            name(&outside)
        )
    );
    let short = forged("short.png", honest.clone(), &RgbImage::new(64, 33));
    assert_eq!(
        refused(d, &[top.clone(), short.clone()]),
        format!(
            "{}: holds 64×33 pixels, but its region 0,30,64,64 is 64×34",
            name(&short)
        )
    );
    // Not a part: a plain render, a file that is no PNG, a truncated part.
    let plain = d.join("plain.png");
    assert!(
        rayoflight(
            d,
            &[
                scene_file.to_str().unwrap(),
                "-out",
                plain.to_str().unwrap()
            ]
        )
        .status
        .success()
    );
    assert!(
        refused(d, &[top.clone(), plain.clone()]).starts_with(&format!(
            "{}: not a part of a render: no 'RayOfLight part' record before its pixels",
            name(&plain)
        ))
    );
    let text = d.join("notes.png");
    fs::write(&text, "not an image").unwrap();
    assert!(
        refused(d, &[top.clone(), text.clone()])
            .starts_with(&format!("{}: not a PNG that can be read", name(&text)))
    );
    let bytes = fs::read(&bottom).unwrap();
    // A bit flipped in a part's pixels, or in a chunk's CRC: caught by the
    // checksums, not passed into the image.
    let idat = bytes.windows(4).position(|w| w == b"IDAT").unwrap();
    let length = u32::from_be_bytes(bytes[idat - 4..idat].try_into().unwrap()) as usize;
    for (file, at) in [
        ("flipped.png", idat + 4 + length / 2),
        ("crc.png", idat + 4 + length),
    ] {
        let mut damaged = bytes.clone();
        damaged[at] ^= 0x10;
        let path = d.join(file);
        fs::write(&path, &damaged).unwrap();
        let message = refused(d, &[top.clone(), path.clone()]);
        assert!(message.starts_with(&name(&path)), "{message}");
    }
    // The odd one out is blamed, even when it comes first.
    let message = refused(d, &[aa[0].clone(), top.clone(), bottom.clone()]);
    assert!(
        message.starts_with(&format!("{}: ", name(&aa[0]))),
        "{message}"
    );
    // A hard link is the file itself.
    let hard = d.join("hard.png");
    fs::hard_link(&top, &hard).unwrap();
    assert_eq!(
        refused(d, &[top.clone(), bottom.clone(), hard.clone()]),
        format!("{}: given twice", name(&hard))
    );
    // A FIFO is refused unopened (opening it would wait for a writer).
    #[cfg(unix)]
    {
        let fifo = d.join("fifo.png");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.unwrap().success());
        assert_eq!(
            refused(d, &[top.clone(), fifo.clone()]),
            format!("{}: is a FIFO, not a part", name(&fifo))
        );
    }
    let cut = d.join("cut.png");
    fs::write(&cut, &bytes[..bytes.len() - 40]).unwrap();
    assert!(refused(d, &[top.clone(), cut.clone()]).starts_with(&name(&cut)));
    let missing = d.join("gone.png");
    assert!(refused(d, &[top.clone(), missing.clone()]).starts_with(&name(&missing)));

    // The image over one of its parts.
    let out = assemble(d, &bottom, &[top.clone(), bottom.clone()]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out).trim(),
        format!(
            "{}: is one of the parts: the image cannot be written over it",
            name(&bottom)
        )
    );
    assert!(Part::parse("").is_err() && image::open(&bottom).unwrap().height() == 34);

    // And the two halves do fit.
    let out = assemble(d, &d.join("ok.png"), &[bottom, top]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn region_flags_that_cannot_work_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene_file = d.join("scene.xml");
    fs::write(&scene_file, rayoflight::EXAMPLE_SCENE.replace("600", "64")).unwrap();
    let s = scene_file.to_str().unwrap();
    for (args, expected) in [
        (
            vec![s, "--region", "0,0,65,10", "-out", "p.png"],
            "--region 0,0,65,10 is outside the 64×64 image",
        ),
        (
            vec![s, "--region", "0,0,10", "-out", "p.png"],
            "--region expects X0,Y0,X1,Y1",
        ),
        (vec![s, "--region", "5,0,5,10", "-out", "p.png"], "is empty"),
        (
            vec![s, "--region", "0,0,8,8", "-out", "p.jpg"],
            "-out must end in .png",
        ),
        (
            vec![s, "--region", "0,0,8,8"],
            "--region needs -out PART.png",
        ),
        (
            vec![s, "--region", "-1,0,8,8", "-out", "p.png"],
            "--region expects X0,Y0,X1,Y1",
        ),
        (vec!["split", s, "--tasks", "-1"], "--tasks expects"),
        (
            vec![s, "--region", "0,0,8,8", "--pass", "depth", "-out", "p.png"],
            "cannot be used with --pass",
        ),
        (
            vec!["assemble", "-out", "x.jpg", "p.png"],
            "-out must end in .png",
        ),
        (vec!["assemble", "p.png"], "missing argument"),
        (vec!["split", s, "--tasks", "0"], "--tasks expects"),
        (
            vec!["split", s, "--tasks", "4097"],
            "cannot split into 4097 tasks",
        ),
    ] {
        let out = rayoflight(d, &args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(expected),
            "{args:?}: {}",
            stderr(&out)
        );
    }
    let out = rayoflight(d, &["split", s, "--tasks", "4097"]);
    assert!(
        stderr(&out).ends_with("see 'rayoflight split --help'\n"),
        "{}",
        stderr(&out)
    );
    // A list that cannot be written whole is an error, never a short list.
    #[cfg(target_os = "linux")]
    {
        let full = fs::File::create("/dev/full").unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_rayoflight"))
            .args(["split", s, "--tasks", "3"])
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        assert!(
            stderr(&out).contains("cannot write to stdout"),
            "{}",
            stderr(&out)
        );
    }
    assert_eq!(common::files_in(d), ["scene.xml"], "nothing written");
}

/// Two grey mirror spheres on the left, a small matte one on the right,
/// sky between and around them: the sky costs no ray (its tiles are
/// filled without tracing), the mirrors several a pixel.
const LOPSIDED: &str = r#"<scene>
  <sphere><color red="0.3" green="0.3" blue="0.35"/><material ka="0.1" kd="0.1" ks="0.9" m="60"/>
    <transformation><translate x="-3.0" y="0" z="0"/></transformation></sphere>
  <sphere><color red="0.35" green="0.3" blue="0.3"/><material ka="0.1" kd="0.1" ks="0.9" m="60"/>
    <transformation><translate x="-0.9" y="0" z="0"/></transformation></sphere>
  <sphere><color red="0.8" green="0.2" blue="0.2"/><material ka="0.3" kd="0.7" ks="0" m="1"/>
    <transformation><scale factor="0.6"/><translate x="2.6" y="0" z="0"/></transformation></sphere>
  <light x="0" y="-5" z="-4"/>
  <camera width="320" height="240" eyeDistance="2.5">
    <transformation><translate z="-6"/></transformation>
  </camera>
  <model type="whitted" depth="30"/>
</scene>
"#;

#[test]
fn split_covers_the_image_once_and_evens_out_the_rays_traced() {
    let scene = scene::parse(LOPSIDED, Path::new("lopsided.xml")).unwrap();
    let options = RenderOptions::default();
    let rays_in = |region: Region| {
        let (_, stats) = render::render_with_stats(
            &scene,
            &RenderOptions {
                region: Some(region),
                ..options.clone()
            },
        )
        .unwrap();
        stats.rays as f64
    };
    // Max over mean of the rays each task traces.
    let spread = |regions: &[Region]| {
        let rays: Vec<f64> = regions.iter().map(|&r| rays_in(r)).collect();
        let mean = rays.iter().sum::<f64>() / rays.len() as f64;
        rays.iter().fold(0.0_f64, |m, &r| m.max(r)) / mean
    };
    let tasks = 6;
    let regions = split::plan(&scene, &options, tasks).unwrap();
    assert_eq!(regions.len(), tasks);
    let mut covered = vec![0u8; 320 * 240];
    for r in &regions {
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                covered[(y * 320 + x) as usize] += 1;
            }
        }
    }
    assert!(covered.iter().all(|&c| c == 1), "{regions:?}");
    // Equal areas: six columns of 320/6 pixels.
    let columns: Vec<Region> = (0..tasks as u32)
        .map(|k| Region::new(k * 320 / 6, 0, (k + 1) * 320 / 6, 240).unwrap())
        .collect();
    let (even_cost, even_area) = (spread(&regions), spread(&columns));
    assert!(
        even_area > 1.4,
        "the scene is lopsided: equal columns spread {even_area:.2}"
    );
    assert!(
        // At most half the excess of equal areas (cuts on a 32-pixel grid
        // of a 320×240 image cannot be finer).
        even_cost < 1.25 && even_cost - 1.0 < (even_area - 1.0) / 2.0,
        "split's regions spread {even_cost:.2} (equal areas {even_area:.2}): {regions:?}"
    );
    let areas: Vec<u64> = regions.iter().map(Region::area).collect();
    assert!(
        areas.iter().max() >= Some(&(2 * areas.iter().min().unwrap())),
        "not equal areas: {areas:?}"
    );
}

#[test]
fn split_prints_one_region_a_line_for_each_task() {
    let dir = tempfile::tempdir().unwrap();
    let scene_file = dir.path().join("lopsided.xml");
    fs::write(&scene_file, LOPSIDED).unwrap();
    let s = scene_file.to_str().unwrap();
    let out = rayoflight(dir.path(), &["split", s, "--tasks", "5"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines: Vec<Region> = stdout(&out)
        .lines()
        .map(|l| Region::parse(l).expect("a region a line"))
        .collect();
    assert_eq!(lines.len(), 5);
    let scene = scene::parse(LOPSIDED, Path::new("l.xml")).unwrap();
    assert_eq!(
        lines,
        split::plan(&scene, &RenderRequest::default().options(&scene), 5).unwrap()
    );
    // The render's --set and --aa change the estimate, not the rules.
    let out = rayoflight(
        dir.path(),
        &["split", s, "-n", "3", "--set", "model.depth=1", "--aa", "2"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(stdout(&out).lines().count(), 3);
}

#[test]
fn sheet_lays_the_renders_of_a_sweep_side_by_side() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene_file = d.join("scene.xml");
    fs::write(&scene_file, rayoflight::EXAMPLE_SCENE.replace("600", "48")).unwrap();
    let s = scene_file.to_str().unwrap();
    let mut images = Vec::new();
    for ka in ["0.1", "0.5", "0.9"] {
        let name = format!("ka={ka}.png");
        let set = format!("object[1].material.ka={ka}");
        let out = rayoflight(d, &[s, "--set", &set, "-out", &name, "-q"]);
        assert!(out.status.success(), "{}", stderr(&out));
        images.push(name);
    }
    let mut args = vec!["sheet", "-out", "sheet.png", "--columns", "3"];
    args.extend(images.iter().map(String::as_str));
    let out = rayoflight(d, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let sheet = image::open(d.join("sheet.png")).unwrap().to_rgb8();
    let gap = rayoflight::cluster::sheet::GAP;
    // Cells are at least MIN_CELL_WIDTH wide, the picture centred.
    let cell = rayoflight::cluster::sheet::MIN_CELL_WIDTH + gap;
    let inset = (rayoflight::cluster::sheet::MIN_CELL_WIDTH - 48) / 2;
    assert_eq!(
        sheet.dimensions(),
        (
            3 * cell + gap,
            48 + rayoflight::cluster::sheet::LABEL_HEIGHT + 2 * gap
        )
    );
    // Each picture where it belongs, as rendered.
    for (k, name) in images.iter().enumerate() {
        let picture = image::open(d.join(name)).unwrap().to_rgb8();
        let placed = image::imageops::crop_imm(&sheet, gap + k as u32 * cell + inset, gap, 48, 48);
        assert!(placed.to_image() == picture, "{name}");
    }
    // Not over one of its own images.
    let before = fs::read(d.join(&images[1])).unwrap();
    let out = rayoflight(d, &["sheet", "-out", &images[1], &images[0], &images[1]]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out).trim(),
        format!(
            "{}: is one of the images: the sheet cannot be written over it",
            images[1]
        )
    );
    assert_eq!(fs::read(d.join(&images[1])).unwrap(), before);
    // A file that is not an image: exit 1, named, nothing written.
    fs::write(d.join("notes.png"), "text").unwrap();
    let out = rayoflight(d, &["sheet", "-out", "bad.png", "notes.png"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).starts_with("notes.png: "), "{}", stderr(&out));
    assert!(!d.join("bad.png").exists());
}

#[cfg(unix)]
#[test]
fn an_interrupted_assembly_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A large, empty image: quick to render, long enough to assemble to
    // be caught in the middle.
    let scene_file = d.join("sky.xml");
    fs::write(
        &scene_file,
        r#"<scene><camera width="12000" height="12000" eyeDistance="2"/><model type="ambient"/></scene>"#,
    )
    .unwrap();
    let quarters = [
        Region::new(0, 0, 12000, 3000).unwrap(),
        Region::new(0, 3000, 12000, 6000).unwrap(),
        Region::new(0, 6000, 12000, 9000).unwrap(),
        Region::new(0, 9000, 12000, 12000).unwrap(),
    ];
    let parts = render_parts(d, &scene_file, &quarters, &[]);
    let out_dir = d.join("out");
    fs::create_dir(&out_dir).unwrap();
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .arg("assemble")
        .arg("-out")
        .arg(out_dir.join("sky.png"))
        .args(&parts)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt it once its temporary file exists.
    let start = std::time::Instant::now();
    while common::files_in(&out_dir).is_empty() {
        assert!(start.elapsed().as_secs() < 30, "no temporary file appeared");
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let pid = child.id().to_string();
    let killed = std::process::Command::new("kill")
        .args(["-TERM", &pid])
        .status();
    assert!(killed.unwrap().success());
    let out = child.wait_with_output().unwrap();
    // 128 + SIGTERM, as for every command a signal stops.
    assert_eq!(out.status.code(), Some(143), "{}", stderr(&out));
    assert_eq!(
        stderr(&out).trim(),
        format!(
            "{}: interrupted: nothing was written",
            out_dir.join("sky.png").display()
        )
    );
    assert!(
        common::files_in(&out_dir).is_empty(),
        "{:?}",
        common::files_in(&out_dir)
    );
}

/// CRC-32 of PNG chunks (ISO 3309), to add a chunk to a part by hand.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// `png` with a tEXt chunk `keyword`, `text` inserted at byte `at`.
fn with_text_chunk(png: &[u8], at: usize, keyword: &str, text: &str) -> Vec<u8> {
    let mut data = keyword.as_bytes().to_vec();
    data.push(0);
    data.extend_from_slice(text.as_bytes());
    let mut chunk = (data.len() as u32).to_be_bytes().to_vec();
    let typed: Vec<u8> = b"tEXt".iter().chain(&data).copied().collect();
    chunk.extend_from_slice(&typed);
    chunk.extend_from_slice(&crc32(&typed).to_be_bytes());
    let mut out = png[..at].to_vec();
    out.extend_from_slice(&chunk);
    out.extend_from_slice(&png[at..]);
    out
}

/// A part with two "RayOfLight part" records is refused, naming the file:
/// which one would be the part's? Both before its pixels, or both after
/// them.
#[test]
fn a_part_with_two_records_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene_file = d.join("scene.xml");
    fs::write(&scene_file, rayoflight::EXAMPLE_SCENE.replace("600", "16")).unwrap();
    let halves = [
        Region::new(0, 0, 16, 8).unwrap(),
        Region::new(0, 8, 16, 16).unwrap(),
    ];
    let parts = render_parts(d, &scene_file, &halves, &[]);
    let png = fs::read(&parts[1]).unwrap();
    // The record of the other half: a file that claims to be either.
    let other = fs::read(&parts[0]).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(&other));
    let reader = decoder.read_info().unwrap();
    let record = reader.info().uncompressed_latin1_text[0].text.clone();
    let after_header = 8 + 25;
    let before_end = png.len() - 12;
    for (name, at) in [("before.png", after_header), ("after.png", before_end)] {
        let twice = d.join(name);
        fs::write(&twice, with_text_chunk(&png, at, part::KEYWORD, &record)).unwrap();
        assert_eq!(
            refused(d, &[parts[0].clone(), twice.clone()]),
            format!(
                "{}: holds two '{}' records: a part has one",
                twice.display(),
                part::KEYWORD
            ),
            "{name}"
        );
    }
}
