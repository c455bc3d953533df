//! `rayoflight bench`: render times of the bench scenes, against POV-Ray
//! when it is installed, thread scaling, cost against object count, peak
//! memory, encoding, and what splitting a 16000×16000 render into 64
//! regions and assembling them costs. Prints a table on stdout and
//! optionally writes a CSV.
//!
//! Its flags, as clap reads them, are here too ([`BenchFlags`]), resolved
//! into the [`BenchArgs`] it runs with.

use super::failure::Failure;
use super::progress::{self, Steps};
use super::subcommand::Subcommand;
use super::usage::UsageError;
use super::values::{runs, threads};
use clap::Args;
use rayoflight::cluster::part::Part;
use rayoflight::cluster::{assemble, split};
use rayoflight::render::measure::{Csv, Difference, RenderPool, Timed, median_of, render_timed};
use rayoflight::render::request::RenderRequest;
use rayoflight::render::{Cancel, Progress, RenderStats};
use rayoflight::scene::generated;
use rayoflight::scene::{self, Scene};
use rayoflight::study::bench;
use rayoflight::system::files;
use rayoflight::{output, pov};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BenchArgs {
    pub threads: usize,
    pub runs: usize,
    pub csv: Option<PathBuf>,
    pub pov: bool,
    /// No progress bar.
    pub quiet: bool,
    /// The side of the split-and-assemble render (0: skip that section).
    pub split_size: u32,
    /// The width of the one-core-against-all render (0: skip that
    /// section).
    pub cores_size: u32,
    /// Spheres in the big scene (0: skip that section).
    pub big_spheres: usize,
    /// Not the bench: the big section's child, the app without its window
    /// on this file ([`app_document`]).
    pub app_document: Option<PathBuf>,
}

/// Most spheres the big-scene section takes (`--big-spheres`): about
/// 930 MB of XML, under the 1 GiB a scene file may take.
pub const MAX_BIG_SPHERES: usize = 4_000_000;

/// The split section's scene (the bench's dearest) and its task count.
const SPLIT_SCENE: &str = "mirrors";
pub const SPLIT_TASKS: usize = 64;

/// One measured configuration: a CSV row.
struct Row {
    section: &'static str,
    scene: String,
    width: u32,
    height: u32,
    threads: usize,
    objects: usize,
    median: Duration,
    stats: RenderStats,
    pov: Option<PovRun>,
    peak_mb: Option<f64>,
    /// The app's render time for the same scene (scenes section, GUI
    /// build).
    app: Option<Duration>,
}

struct PovRun {
    median: Duration,
    within1: f64,
    max_diff: u8,
}

/// Runs the whole bench; the report goes to stdout as it comes, a progress
/// bar (`steps`) to stderr.
fn run_bench(args: &BenchArgs, steps: &Steps) -> Result<(), String> {
    if let Some(path) = &args.app_document {
        return app_document(path, args.threads);
    }
    // The CSV's folder takes it, checked before the minutes of work.
    if let Some(path) = &args.csv {
        files::check_file_target(path).map_err(|e| e.to_string())?;
    }
    let out = |text: &str| steps.print(text);
    let mut done = 0;
    let mut step = |name: &str| {
        steps.step(done, name);
        done += 1;
    };
    let mut rows = Vec::new();
    let pov_version = if args.pov { povray_version() } else { None };
    out(&format!(
        "RayOfLight bench: median of {} runs, {} threads ({} cores here); POV-Ray: {}\n",
        args.runs,
        args.threads,
        rayoflight::render::all_cores(),
        pov_version
            .as_deref()
            .unwrap_or(if args.pov { "not found" } else { "skipped" }),
    ))?;

    out(
        "\nScenes (same image, same thread count as POV-Ray's +WT; app: the app's render worker, coarse to fine, request to full picture, no window)\n",
    )?;
    out(&format!(
        "{:<14} {:>10} {:>10} {:>9} {:>11} {:>7} {:>9} {:>4} {:>10}\n",
        "scene", "size", "ours ms", "Mrays/s", "POV-Ray ms", "ratio", "within 1", "max", "app ms"
    ))?;
    let mut sets: Vec<(String, Scene)> = Vec::new();
    let example = scene::parse(rayoflight::EXAMPLE_SCENE, Path::new("scenes/example.xml"))
        .map_err(|e| e.to_string())?;
    sets.push(("example".into(), example));
    for s in &bench::SCENES {
        sets.push((s.name.into(), s.scene().map_err(|e| e.to_string())?));
    }
    // Powers of two up to the most threads a render may ask for (four per
    // core): past the cores the table shows what oversubscription costs.
    let counts: Vec<usize> = (0..)
        .map(|k| 1usize << k)
        .take_while(|&t| t <= rayoflight::render::max_threads())
        .collect();
    let sizes = [10, 100, 1_000, 10_000, 100_000];
    let formats = ["png", "gif", "jpg", "webp"];
    let split_steps = if args.split_size > 0 {
        SPLIT_TASKS + 3
    } else {
        0
    };
    let big_steps = if args.big_spheres > 0 { 3 } else { 0 };
    let cores_steps = if args.cores_size > 0 { 3 } else { 0 };
    steps.set_total(
        (sets.len()
            + sets.len() * counts.len()
            + sizes.len()
            + 1
            + big_steps
            + formats.len()
            + cores_steps
            + split_steps) as u64,
    );
    for (name, scene) in &sets {
        step(name);
        let (median, stats, image) = time_render(scene, args.threads, args.runs)?;
        let pov = match pov_version {
            Some(_) => Some(pov_render(scene, args.threads, args.runs, &image)?),
            None => None,
        };
        let app = app_time(scene, args.threads, args.runs)?;
        let row = Row {
            app,
            section: "scene",
            scene: name.clone(),
            width: scene.camera.width,
            height: scene.camera.height,
            threads: args.threads,
            objects: scene.objects.len(),
            median,
            stats,
            pov,
            peak_mb: None,
        };
        out(&scene_line(&row))?;
        rows.push(row);
    }
    // The median of the scenes' ratios to POV-Ray (the upper middle one
    // for an even count).
    let mut ratios: Vec<f64> = rows
        .iter()
        .filter_map(|r| {
            r.pov
                .as_ref()
                .map(|p| p.median.as_secs_f64() / r.median.as_secs_f64())
        })
        .collect();
    ratios.sort_by(f64::total_cmp);
    if let Some(median) = ratios.get(ratios.len() / 2) {
        let lowest = ratios[0];
        out(&format!(
            "median ratio to POV-Ray {median:.1}x, lowest {lowest:.1}x\n"
        ))?;
    }

    // The serial share: what of a 1-thread render did not spread over the
    // cores, by Amdahl's law from the speed-up on every core.
    let cores = rayoflight::render::all_cores();
    out(&format!(
        "\nThread scaling (ms, and speed-up over 1 thread; serial: the share of the 1-thread \
         render that did not spread over the {cores} cores, from the speed-up on {cores})\n"
    ))?;
    out(&format!("{:<14}", "scene"))?;
    for &t in &counts {
        out(&format!(
            " {:>16}",
            format!("{t} thread{}", if t == 1 { "" } else { "s" })
        ))?;
    }
    out(&format!(" {:>8}\n", "serial"))?;
    for (name, scene) in &sets {
        out(&format!("{name:<14}"))?;
        let mut one = None;
        let mut serial = None;
        for &t in &counts {
            step(&format!("{name}, {t} threads"));
            let (median, stats, _) = time_render(scene, t, args.runs)?;
            let base = *one.get_or_insert(median);
            if t == cores && t > 1 {
                serial = Some(serial_share(base, median, t));
            }
            out(&format!(
                " {:>16}",
                format!(
                    "{:.1} ({:.2}x)",
                    ms(median),
                    base.as_secs_f64() / median.as_secs_f64()
                )
            ))?;
            rows.push(Row {
                section: "threads",
                scene: name.clone(),
                width: scene.camera.width,
                height: scene.camera.height,
                threads: t,
                objects: scene.objects.len(),
                median,
                stats,
                pov: None,
                peak_mb: None,
                app: None,
            });
        }
        match serial {
            Some(share) => out(&format!(" {:>7.1}%\n", 100.0 * share))?,
            None => out(&format!(" {:>8}\n", "—"))?,
        }
    }

    out("\nCost against object count (n spheres on a floor, 800x600, phong)\n")?;
    out(&format!(
        "{:>8} {:>10} {:>12} {:>14}\n",
        "spheres", "ms", "x n=10", "ms / log2(n)"
    ))?;
    let mut first = None;
    for n in sizes {
        step(&format!("{n} spheres"));
        let text = generated::spheres_on_floor(n, 800, 600);
        let scene = scene::parse(&text, Path::new("generated.xml")).map_err(|e| e.to_string())?;
        let (median, stats, _) = time_render(&scene, args.threads, args.runs)?;
        let base = *first.get_or_insert(median);
        out(&format!(
            "{:>8} {:>10.2} {:>12.2} {:>14.3}\n",
            n,
            ms(median),
            median.as_secs_f64() / base.as_secs_f64(),
            ms(median) / (n as f64).log2()
        ))?;
        rows.push(Row {
            section: "objects",
            scene: format!("spheres-{n}"),
            width: 800,
            height: 600,
            threads: args.threads,
            objects: n + 1,
            median,
            stats,
            pov: None,
            peak_mb: None,
            app: None,
        });
    }

    out("\nPeak memory, 100 000 spheres at 1600x1200 (XML text, parse, prepare, render)\n")?;
    step("peak memory");
    match peak_memory(100_000, 1600, 1200, args.threads)? {
        Some((beyond, image_mb)) => {
            out(&format!(
                "{beyond:.1} MB beyond the image ({image_mb:.1} MB of pixels)\n"
            ))?;
            rows.push(Row {
                section: "memory",
                scene: "spheres-100000".into(),
                width: 1600,
                height: 1200,
                threads: args.threads,
                objects: 100_001,
                median: Duration::ZERO,
                stats: RenderStats::default(),
                pov: None,
                peak_mb: Some(beyond),
                app: None,
            });
        }
        None => out("not measurable here (needs Linux /proc)\n")?,
    }

    if args.big_spheres > 0 {
        big_section(args.big_spheres, args.threads, &mut step, &out, &mut rows)?;
    }

    out("\nEncoding a 4096x4096 render of the example (ms, and against PNG)\n")?;
    let mut example = sets[0].1.clone();
    (example.camera.width, example.camera.height) = (4096, 4096);
    let (_, _, image) = time_render(&example, args.threads, 1)?;
    let mut png = None;
    for ext in formats {
        step(&format!("encode {ext}"));
        let format =
            output::format_for(Path::new(&format!("x.{ext}"))).map_err(|e| e.to_string())?;
        let median = median_of(args.runs, || {
            let start = Instant::now();
            output::encode(&image, format).map_err(|e| e.to_string())?;
            Ok::<_, String>(start.elapsed())
        })?;
        let base = *png.get_or_insert(median);
        out(&format!(
            "{ext:<6} {:>10.1} {:>8.2}x\n",
            ms(median),
            median.as_secs_f64() / base.as_secs_f64()
        ))?;
        rows.push(Row {
            section: "encode",
            scene: format!("example-4096.{ext}"),
            width: 4096,
            height: 4096,
            threads: 1,
            objects: example.objects.len(),
            median,
            stats: RenderStats::default(),
            pov: None,
            peak_mb: None,
            app: None,
        });
    }

    if args.cores_size > 0 {
        cores_section(args, &mut step, &out, &mut rows)?;
    }

    if args.split_size > 0 {
        let (_, scene) = sets
            .iter()
            .find(|(name, _)| name == SPLIT_SCENE)
            .ok_or("the split section's scene is not in the bench")?;
        split_section(scene, args, &mut step, &out, &mut rows)?;
    }

    if let Some(path) = &args.csv {
        files::write_atomic(path, csv(&rows).as_bytes()).map_err(|e| e.to_string())?;
        out(&format!("\nCSV written to {}\n", path.display()))?;
    }
    Ok(())
}

/// One render of `scene` at `args.split_size`² against the same image
/// split into [`SPLIT_TASKS`] regions (`split`), each rendered and written
/// as a part, then assembled, all on this machine: what splitting costs
/// beyond the render of the whole and its file.
fn split_section(
    scene: &Scene,
    args: &BenchArgs,
    step: &mut impl FnMut(&str),
    out: &impl Fn(&str) -> Result<(), String>,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    let size = args.split_size;
    let mut scene = scene.clone();
    (scene.camera.width, scene.camera.height) = (size, size);
    out(&format!(
        "\nPast one machine: {SPLIT_SCENE} at {size}x{size}, one render against {SPLIT_TASKS} \
         regions (split, each rendered and written as a part, assemble), {} threads\n",
        args.threads
    ))?;
    let pool = RenderPool::new(Some(args.threads)).map_err(|e| e.to_string())?;
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let error = |e: &dyn std::fmt::Display| e.to_string();
    let row = |scene: String, width, height, median, stats, peak_mb| Row {
        section: "split",
        scene,
        width,
        height,
        threads: args.threads,
        objects: 0,
        median,
        stats,
        pov: None,
        peak_mb,
        app: None,
    };
    let render = |request: &RenderRequest| {
        render_timed(
            &scene,
            request,
            &pool,
            &Cancel::never(),
            &Progress::default(),
        )
        .map_err(|e| error(&e))?
        .ok_or_else(|| "cancelled".to_owned())
    };
    let timed = |work: &mut dyn FnMut() -> Result<(), String>| {
        let start = Instant::now();
        work().map(|()| start.elapsed())
    };

    step("split: the whole image");
    let whole_file = dir.path().join("whole.png");
    let whole = render(&RenderRequest::default())?;
    // Written, and assembled, on the render's threads.
    let whole_write = pool.install(|| {
        timed(&mut || output::save(&whole.image, &whole_file).map_err(|e| error(&e)))
    })?;
    rows.push(row(
        "whole".into(),
        size,
        size,
        whole.elapsed,
        whole.stats,
        None,
    ));
    let whole_stats = whole.stats;
    drop(whole.image);

    step("split: regions");
    let request = RenderRequest::default();
    let mut regions = Vec::new();
    let pre_pass = timed(&mut || {
        let options = request.options(&scene);
        regions = pool
            .install(|| split::plan(&scene, &options, SPLIT_TASKS))
            .map_err(|e| error(&e))?;
        Ok(())
    })?;
    let (mut parts, mut region_times) = (Vec::new(), Vec::new());
    let (mut rendering, mut writing, mut rays) = (Duration::ZERO, Duration::ZERO, 0);
    for (k, region) in regions.iter().enumerate() {
        step(&format!("split: region {}/{}", k + 1, regions.len()));
        let request = RenderRequest {
            region: Some(*region),
            ..RenderRequest::default()
        };
        let part = render(&request)?;
        let path = dir.path().join(format!("part-{k}.png"));
        let record = Part::new(&scene, &request.options(&scene), *region);
        writing += pool.install(|| {
            timed(&mut || {
                rayoflight::cluster::part::save(&part.image, &record, &path).map_err(|e| error(&e))
            })
        })?;
        rendering += part.elapsed;
        rays += part.stats.rays;
        region_times.push(part.elapsed);
        rows.push(row(
            format!("region {region}"),
            region.width(),
            region.height(),
            part.elapsed,
            part.stats,
            None,
        ));
        parts.push(path);
    }

    step("split: assemble");
    let assembled = dir.path().join("assembled.png");
    let assembly = pool.install(|| {
        timed(&mut || {
            assemble::assemble(&parts, &assembled)
                .map(drop)
                .map_err(|e| error(&e))
        })
    })?;
    // Its memory, as a cluster's assembly job runs it: a process of its
    // own (this one has held the whole image).
    let peak_mb = assemble_process_peak_mb(&parts, &dir.path().join("again.png"))?;
    rows.push(row(
        "assemble".into(),
        size,
        size,
        assembly,
        RenderStats::default(),
        peak_mb,
    ));
    let same = std::fs::read(&assembled).map_err(|e| error(&e))?
        == std::fs::read(&whole_file).map_err(|e| error(&e))?;

    let pct = |part: Duration, of: Duration| 100.0 * part.as_secs_f64() / of.as_secs_f64();
    let one = whole.elapsed + whole_write;
    let file_mb = |p: &Path| std::fs::metadata(p).map_or(0.0, |m| m.len() as f64 / 1e6);
    region_times.sort();
    let mean = rendering / region_times.len().max(1) as u32;
    let slowest = region_times.last().copied().unwrap_or_default();
    out(&format!(
        "whole:     render {:.2} s, PNG written {:.2} s ({:.1} MB)\n",
        whole.elapsed.as_secs_f64(),
        whole_write.as_secs_f64(),
        file_mb(&whole_file)
    ))?;
    out(&format!(
        "regions:   split's pre-pass {:.3} s; {} regions rendered {:.2} s in all ({:+.2} %, rays {:+.3} %), \
         parts written {:.2} s\n",
        pre_pass.as_secs_f64(),
        regions.len(),
        rendering.as_secs_f64(),
        pct(rendering, whole.elapsed) - 100.0,
        100.0 * (rays as f64 / whole_stats.rays.max(1) as f64 - 1.0),
        writing.as_secs_f64()
    ))?;
    out(&format!(
        "per region: fastest {:.3} s, median {:.3} s, slowest {:.3} s (slowest / mean {:.2})\n",
        region_times
            .first()
            .copied()
            .unwrap_or_default()
            .as_secs_f64(),
        region_times[region_times.len() / 2].as_secs_f64(),
        slowest.as_secs_f64(),
        slowest.as_secs_f64() / mean.as_secs_f64()
    ))?;
    out(&format!(
        "assemble:  {:.2} s, peak memory of an assemble process {}; the same file as the whole \
         render: {}\n",
        assembly.as_secs_f64(),
        peak_mb.map_or("not measurable here".to_owned(), |m| format!("{m:.1} MB")),
        if same { "yes" } else { "NO" }
    ))?;
    let total = pre_pass + rendering + writing + assembly;
    out(&format!(
        "overhead:  {:+.1} % of the whole render and its file ({:.2} s against {:.2} s): \
         pre-pass {:+.2} %, rendering {:+.2} %, writing {:+.2} %, assembly {:+.1} %\n",
        pct(total, one) - 100.0,
        total.as_secs_f64(),
        one.as_secs_f64(),
        pct(pre_pass, one),
        pct(rendering, one) - pct(whole.elapsed, one),
        pct(writing, one) - pct(whole_write, one),
        pct(assembly, one)
    ))?;
    if !same {
        return Err("the assembled image differs from the whole render".to_owned());
    }
    Ok(())
}

/// The whole process, one core against all: `rayoflight` rendering the
/// example at `cores_size` pixels wide (4:3, whitted) and writing its PNG,
/// then `rayoflight assemble` of 16 parts of that render, each run as a
/// command of its own pinned to the first core (`taskset -c 0`, with
/// `--threads 1`) and on every core, the best of `runs` each, interleaved.
/// What a render spends outside parallel work (loading, preparing,
/// writing) shows here as the gap between the speed-up and the core count.
fn cores_section(
    args: &BenchArgs,
    step: &mut impl FnMut(&str),
    out: &impl Fn(&str) -> Result<(), String>,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    let (width, height) = (args.cores_size, args.cores_size / 4 * 3);
    let cores = rayoflight::render::all_cores();
    out(&format!(
        "\nThe whole process on 1 core and on {cores} (wall ms of the command, best of {}; \
         speed-up)\n",
        args.runs
    ))?;
    if Command::new("taskset").arg("--version").output().is_err() {
        return out("not measured: taskset (util-linux) is not installed\n");
    }
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let scene = dir.path().join("example.xml");
    files::write_new(&scene, rayoflight::EXAMPLE_SCENE.as_bytes()).map_err(|e| e.to_string())?;
    let size = [
        format!("camera.width={width}"),
        format!("camera.height={height}"),
    ];
    let render_args = |threads: usize, out: &Path| -> Vec<std::ffi::OsString> {
        let mut a: Vec<std::ffi::OsString> = vec![
            "--no-gui".into(),
            "-q".into(),
            scene.clone().into(),
            "--threads".into(),
            threads.to_string().into(),
            "-out".into(),
            out.into(),
        ];
        for set in &size {
            a.extend(["--set".into(), set.into()]);
        }
        a
    };
    // The parts, once: the regions split gives, each rendered.
    let mut parts = Vec::new();
    let regions = {
        let mut a: Vec<std::ffi::OsString> = vec![
            "split".into(),
            scene.clone().into(),
            "--tasks".into(),
            "16".into(),
        ];
        for set in &size {
            a.extend(["--set".into(), set.clone().into()]);
        }
        let exe = std::env::current_exe().map_err(|e| e.to_string())?;
        let listed = Command::new(exe)
            .args(&a)
            .output()
            .map_err(|e| e.to_string())?;
        String::from_utf8_lossy(&listed.stdout).into_owned()
    };
    step("cores: the parts");
    for (k, region) in regions.lines().enumerate() {
        let part = dir.path().join(format!("part-{k}.png"));
        let mut a = render_args(args.threads, &part);
        a.extend(["--region".into(), region.into()]);
        process_peak(&a, false)?;
        parts.push(part);
    }
    let assemble_args = || -> Vec<std::ffi::OsString> {
        let mut a: Vec<std::ffi::OsString> = vec![
            "assemble".into(),
            "-out".into(),
            dir.path().join("a.png").into(),
        ];
        a.extend(parts.iter().map(|p| p.clone().into()));
        a
    };
    out(&format!(
        "{:<34} {:>10} {:>10} {:>9}\n",
        "command", "1 core", "all", "speed-up"
    ))?;
    let rendered = dir.path().join("r.png");
    // Each command, with the arguments for one core and for all.
    let commands = [
        (
            "render + PNG",
            render_args(1, &rendered),
            render_args(args.threads, &rendered),
        ),
        ("assemble 16 parts", assemble_args(), assemble_args()),
    ];
    for (name, on_one, on_all) in &commands {
        step(&format!("cores: {name}"));
        let (mut one, mut all) = (Duration::MAX, Duration::MAX);
        for _ in 0..args.runs {
            one = one.min(process_peak(on_one, true)?.0);
            all = all.min(process_peak(on_all, false)?.0);
        }
        let label = format!("{name} ({width}x{height})");
        out(&format!(
            "{label:<34} {:>10.1} {:>10.1} {:>8.2}x\n",
            ms(one),
            ms(all),
            one.as_secs_f64() / all.as_secs_f64()
        ))?;
        for (threads, median) in [(1, one), (args.threads, all)] {
            rows.push(Row {
                section: "cores",
                scene: name.to_string(),
                width,
                height,
                threads,
                objects: 0,
                median,
                stats: RenderStats::default(),
                pov: None,
                peak_mb: None,
                app: None,
            });
        }
    }
    Ok(())
}

/// The peak resident memory (VmHWM) of `rayoflight assemble` on `parts`
/// in a process of its own ([`process_peak`]).
fn assemble_process_peak_mb(parts: &[PathBuf], out: &Path) -> Result<Option<f64>, String> {
    let mut args = vec!["assemble".into(), "-out".into(), out.as_os_str().to_owned()];
    args.extend(parts.iter().map(|p| p.as_os_str().to_owned()));
    process_peak(&args, false).map(|(_, peak)| peak)
}

/// Runs this program with `args` in a process of its own: its wall time
/// and its peak resident memory (VmHWM) in MB, read from /proc while it
/// runs (Linux; `None` elsewhere). The peak only grows, so the last
/// reading is the peak but for the process's last milliseconds.
fn process_peak(
    args: &[std::ffi::OsString],
    first_core: bool,
) -> Result<(Duration, Option<f64>), String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut command = match first_core {
        true => {
            let mut taskset = Command::new("taskset");
            taskset.args(["-c", "0"]).arg(exe);
            taskset
        }
        false => Command::new(exe),
    };
    let start = Instant::now();
    let mut child = command.args(args).spawn().map_err(|e| e.to_string())?;
    let status_file = format!("/proc/{}/status", child.id());
    let mut peak_kb: Option<f64> = None;
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            break status;
        }
        let hwm = std::fs::read_to_string(&status_file).ok().and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
            line.split_whitespace().nth(1)?.parse::<f64>().ok()
        });
        if let Some(kb) = hwm {
            peak_kb = Some(peak_kb.map_or(kb, |p| p.max(kb)));
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let wall = start.elapsed();
    if !status.success() {
        let command = args
            .first()
            .map(|a| a.to_string_lossy())
            .unwrap_or_default();
        return Err(format!("rayoflight {command} failed"));
    }
    Ok((wall, peak_kb.map(|kb| kb / 1e3)))
}

/// The big scene: `n` spheres on a floor ([`generated::spheres_on_floor`],
/// 64x48) written to a file, then loaded, checked and prepared as the
/// command line does, against `xmllint --stream --noout` reading the same
/// file (libxml2 checking it is well-formed and building nothing), the
/// best of two runs each; and the command line's whole run in a process
/// of its own, for its time and its peak memory against the file's size.
fn big_section(
    n: usize,
    threads: usize,
    step: &mut impl FnMut(&str),
    out: &impl Fn(&str) -> Result<(), String>,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    const RUNS: usize = 2;
    let error = |e: &dyn std::fmt::Display| e.to_string();
    let dir = tempfile::tempdir().map_err(|e| error(&e))?;
    let path = dir.path().join(format!("spheres-{n}.xml"));
    let size = {
        let text = generated::spheres_on_floor(n, 64, 48);
        std::fs::write(&path, &text).map_err(|e| error(&e))?;
        text.len()
    };
    let size_mb = size as f64 / 1e6;
    out(&format!(
        "\nA big scene: {n} spheres, {size_mb:.0} MB of XML, loaded, checked and prepared \
         against xmllint --stream --noout (best of {RUNS}); the command line at 64x48\n"
    ))?;
    let row = |scene: &str, median: Duration, peak_mb: Option<f64>| Row {
        section: "big",
        scene: format!("spheres-{n} {scene}"),
        width: 64,
        height: 48,
        threads,
        objects: n + 1,
        median,
        stats: RenderStats::default(),
        pov: None,
        peak_mb,
        app: None,
    };
    let best = |times: Vec<Duration>| times.into_iter().min().unwrap_or_default();

    step("big scene: xmllint");
    let mut xmllint = Vec::new();
    for _ in 0..RUNS {
        let start = Instant::now();
        let status = Command::new("xmllint")
            .args(["--stream", "--noout"])
            .arg(&path)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status();
        match status {
            Ok(s) if s.success() => xmllint.push(start.elapsed()),
            Ok(s) => return Err(format!("xmllint refused the big scene ({s})")),
            // Not installed: the anchor is left out.
            Err(_) => break,
        }
    }
    let xmllint = (!xmllint.is_empty()).then(|| best(xmllint));
    match xmllint {
        Some(t) => {
            out(&format!(
                "{:<34} {:>9.0} ms\n",
                "xmllint --stream --noout",
                ms(t)
            ))?;
            rows.push(row("xmllint", t, None));
        }
        None => out(
            "xmllint --stream --noout: not installed (apt-get install libxml2-utils), no anchor\n",
        )?,
    }

    step("big scene: load and prepare");
    let mut runs = Vec::new();
    for _ in 0..RUNS {
        let start = Instant::now();
        let scene = scene::load(&path).map_err(|e| error(&e))?;
        let loaded = start.elapsed();
        let options = RenderRequest::default().options(&scene);
        let start = Instant::now();
        let prepared = rayoflight::render::prepare(&scene, &options);
        runs.push((loaded, start.elapsed()));
        drop(prepared);
    }
    let (load, prepare) = runs
        .into_iter()
        .min_by_key(|(l, p)| *l + *p)
        .unwrap_or_default();
    let total = load + prepare;
    out(&format!("{:<34} {:>9.0} ms\n", "load and check", ms(load)))?;
    out(&format!("{:<34} {:>9.0} ms\n", "prepare", ms(prepare)))?;
    let against = xmllint
        .map(|x| {
            format!(
                "  {:.2}x xmllint's time (goal: 1x)",
                total.as_secs_f64() / x.as_secs_f64()
            )
        })
        .unwrap_or_default();
    out(&format!(
        "{:<34} {:>9.0} ms{against}\n",
        "load, check and prepare",
        ms(total)
    ))?;
    rows.push(row("load", load, None));
    rows.push(row("prepare", prepare, None));

    step("big scene: the command line");
    let image = dir.path().join("big.png");
    let args: Vec<std::ffi::OsString> = vec![
        path.into_os_string(),
        "-out".into(),
        image.into_os_string(),
        "--no-gui".into(),
        "--quiet".into(),
        "--threads".into(),
        threads.to_string().into(),
    ];
    let (wall, peak) = process_peak(&args, false)?;
    let memory = peak
        .map(|p| {
            format!(
                ", peak {p:.0} MB: {:.2}x the file (goal: 1.5x)",
                p / size_mb
            )
        })
        .unwrap_or_else(|| ", peak memory not measurable here (needs Linux /proc)".to_owned());
    out(&format!(
        "{:<34} {:>9.0} ms{memory}\n",
        "command line, whole run",
        ms(wall)
    ))?;
    rows.push(row("command line", wall, peak));

    step("big scene: the app");
    let Some(stages) = app_document_peaks(&dir.path().join(format!("spheres-{n}.xml")), threads)?
    else {
        return Ok(());
    };
    let stages: Vec<String> = stages
        .iter()
        .map(|(stage, mb)| {
            rows.push(row(&format!("app {stage}"), Duration::ZERO, Some(*mb)));
            format!("{mb:.0} MB ({:.2}x) {stage}", mb / size_mb)
        })
        .collect();
    out(&format!(
        "{:<34} peak {} (goal: 2x, with the window: \
         tools/measure-app-memory.sh measures it)\n",
        "the app without its window",
        stages.join(", ")
    ))?;
    Ok(())
}

/// The stages of [`app_document`], each with the app's peak memory after
/// it, in MB: run in a process of its own on `path` (which it edits and
/// saves). `None` in a build without the app.
#[cfg(feature = "session")]
fn app_document_peaks(path: &Path, threads: usize) -> Result<Option<Vec<(String, f64)>>, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let output = Command::new(exe)
        .arg("bench")
        .arg("--app-document")
        .arg(path)
        .arg("--threads")
        .arg(threads.to_string())
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| e.to_string())?;
    if !output.status.success() {
        return Err("rayoflight bench --app-document failed".to_owned());
    }
    let stages = String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|line| {
            let (line, _resident) = line.rsplit_once(' ')?;
            let (stage, peak) = line.rsplit_once(' ')?;
            Some((stage.to_owned(), peak.parse::<f64>().ok()? / 1e3))
        })
        .collect();
    Ok(Some(stages))
}

#[cfg(not(feature = "session"))]
fn app_document_peaks(_: &Path, _: usize) -> Result<Option<Vec<(String, f64)>>, String> {
    Ok(None)
}

#[cfg(not(feature = "session"))]
pub fn app_document(_: &Path, _: usize) -> Result<(), String> {
    Err("--app-document: this build has no app (built without the session feature, which gui includes)".to_owned())
}

/// The app on `path` as a user meets it, less the window: the document
/// opened as the app opens it, the picture from the app's render worker,
/// an edit of one value (journaled, as the app does within a second), its
/// picture, and a save. After each it prints the stage, the process's
/// peak resident memory so far and its resident memory now, in kB (`after
/// an edit 534000 521000`): the child `rayoflight bench --app-document
/// FILE` of the big section.
#[cfg(feature = "session")]
pub fn app_document(path: &Path, threads: usize) -> Result<(), String> {
    use rayoflight::scene::edit::{Edit, Field, Value};
    use rayoflight::session::document::Document;
    use rayoflight::session::journal::{Entry, Job, Writer};

    let error = |e: &dyn std::fmt::Display| e.to_string();
    let say = |stage: &str| {
        let [peak, now] = PeakMemory::read_kb(["VmHWM:", "VmRSS:"]).unwrap_or_default();
        println!("{stage} {peak:.0} {now:.0}");
    };
    let mut doc = Document::open(path).map_err(|e| error(&e))?;
    if let Some(e) = doc.error() {
        return Err(e.to_owned());
    }
    let worker = rayoflight::session::worker::Worker::spawn(threads, || {});
    picture(&worker, doc.scene())?;
    say("after the picture");

    let ka = Field::parse("object[1].material.ka").map_err(|e| error(&e))?;
    let value = match ka.get(doc.scene()) {
        Ok(Value::Number(0.25)) => 0.5,
        _ => 0.25,
    };
    doc.apply(Edit::Set(ka, Value::Number(value)))
        .map_err(|e| error(&e))?;
    doc.end_drag();
    let journal = tempfile::tempdir().map_err(|e| error(&e))?;
    let writer = Writer::start(journal.path().to_owned());
    writer.send(Job::Write {
        entry: Entry::now(path, doc.file_fingerprint(), doc.unsaved_edits()),
        base: Some(doc.file_text_writer()),
    });
    picture(&worker, doc.scene())?;
    writer.flush(Duration::from_secs(600));
    say("after an edit");

    // On a thread of its own, as the app saves (the window goes on).
    let (tx, rx) = std::sync::mpsc::channel();
    doc.save_job()
        .map_err(|e| error(&e))?
        .spawn(move |job, outcome| {
            let _ = tx.send((job, outcome));
        });
    let (job, outcome) = rx
        .recv()
        .map_err(|_| "the save's thread panicked".to_owned())?;
    match doc.save_done(job, outcome).map_err(|e| error(&e))? {
        rayoflight::session::document::SaveStep::Done(_) => {}
        rayoflight::session::document::SaveStep::Again => {
            doc.save().map(|_| ()).map_err(|e| error(&e))?
        }
    }
    say("after a save");
    Ok(())
}

/// The full-size picture of `scene` from the app's worker, as the app
/// asks for it.
#[cfg(feature = "session")]
fn picture(worker: &rayoflight::session::worker::Worker, scene: &Scene) -> Result<(), String> {
    use rayoflight::session::worker::{self, Event};
    let passes = worker::passes(scene.camera.width, scene.camera.height);
    let generation = worker.request_passes(
        std::sync::Arc::new(scene.clone()),
        RenderRequest::default(),
        passes,
    );
    loop {
        match worker.next_event(Duration::from_secs(600)) {
            Some(Event::PassFinished {
                generation: g,
                scale: 1,
                ..
            }) if g == generation => return Ok(()),
            Some(Event::Failed { message, .. }) => return Err(message),
            Some(_) => {}
            None => return Err("the app's worker did not answer".to_owned()),
        }
    }
}

/// The peak resident memory from now on (Linux: /proc/self/clear_refs
/// resets it).
struct PeakMemory {
    before_kb: f64,
}

impl PeakMemory {
    /// The values of `keys` (`VmHWM:`, `VmRSS:`) in kB, from one reading
    /// of the process's status: read apart, a page touched between the
    /// two could show more resident than the peak.
    fn read_kb<const N: usize>(keys: [&str; N]) -> Option<[f64; N]> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let value = |key: &str| {
            let line = status.lines().find(|l| l.starts_with(key))?;
            line.split_whitespace().nth(1)?.parse().ok()
        };
        let mut values = [0.0; N];
        for (v, key) in values.iter_mut().zip(keys) {
            *v = value(key)?;
        }
        Some(values)
    }

    fn start() -> Option<PeakMemory> {
        std::fs::write("/proc/self/clear_refs", "5").ok()?;
        Some(PeakMemory {
            before_kb: Self::read_kb(["VmRSS:"])?[0],
        })
    }

    /// The peak's excess over the resident memory at the start, in MB.
    fn extra_mb(&self) -> Option<f64> {
        Some((Self::read_kb(["VmHWM:"])?[0] - self.before_kb).max(0.0) / 1e3)
    }
}

/// The share of a render that did not spread over `n` threads, by
/// Amdahl's law from its times on one (`one`) and on `n` (`on_n`):
/// on_n = one × (s + (1 − s) / n), so s = (n × on_n / one − 1) / (n − 1).
/// Below zero (a speed-up past n, from caches) it is 0.
fn serial_share(one: Duration, on_n: Duration, n: usize) -> f64 {
    let n = n as f64;
    let s = (n * on_n.as_secs_f64() / one.as_secs_f64() - 1.0) / (n - 1.0);
    s.max(0.0)
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn scene_line(row: &Row) -> String {
    let mut line = format!(
        "{:<14} {:>10} {:>10.2} {:>9.1}",
        row.scene,
        format!("{}x{}", row.width, row.height),
        ms(row.median),
        row.stats.rays as f64 / row.median.as_secs_f64() / 1e6
    );
    match &row.pov {
        Some(p) => {
            let _ = write!(
                line,
                " {:>11.1} {:>6.1}x {:>8.4}% {:>4}",
                ms(p.median),
                p.median.as_secs_f64() / row.median.as_secs_f64(),
                p.within1 * 100.0,
                p.max_diff
            );
        }
        None => line.push_str("           -       -         -    -"),
    }
    match row.app {
        Some(app) => {
            let _ = write!(line, " {:>10.2}", ms(app));
        }
        None => line.push_str("          -"),
    }
    line.push('\n');
    line
}

fn csv(rows: &[Row]) -> String {
    let mut csv = Csv::new(&[
        "section",
        "scene",
        "width",
        "height",
        "threads",
        "objects",
        "median_ms",
        "rays",
        "mrays_per_s",
        "pov_ms",
        "ratio",
        "within1",
        "max_diff",
        "peak_mb",
        "app_ms",
    ]);
    for r in rows {
        let secs = r.median.as_secs_f64();
        let timed = |text: String| if secs > 0.0 { text } else { String::new() };
        let (pov_ms, ratio, within1, max_diff) = match &r.pov {
            Some(p) => (
                format!("{:.2}", ms(p.median)),
                format!("{:.2}", p.median.as_secs_f64() / secs),
                format!("{:.6}", p.within1),
                p.max_diff.to_string(),
            ),
            None => Default::default(),
        };
        csv.row([
            r.section.to_owned(),
            r.scene.clone(),
            r.width.to_string(),
            r.height.to_string(),
            r.threads.to_string(),
            r.objects.to_string(),
            timed(format!("{:.3}", ms(r.median))),
            r.stats.rays.to_string(),
            timed(format!("{:.2}", r.stats.rays as f64 / secs / 1e6)),
            pov_ms,
            ratio,
            within1,
            max_diff,
            r.peak_mb.map(|m| format!("{m:.1}")).unwrap_or_default(),
            r.app.map(|d| format!("{:.3}", ms(d))).unwrap_or_default(),
        ]);
    }
    csv.into_text()
}

/// Median render time over `runs`, as [`rayoflight::render::measure`] defines it
/// (the CLI's request: `auto`; the pool built before the clock).
fn time_render(
    scene: &Scene,
    threads: usize,
    runs: usize,
) -> Result<(Duration, RenderStats, image::RgbImage), String> {
    let pool = RenderPool::new(Some(threads)).map_err(|e| e.to_string())?;
    let mut last = None;
    let median = median_of(runs, || {
        let timed = render_timed(
            scene,
            &RenderRequest::default(),
            &pool,
            &Cancel::never(),
            &Progress::default(),
        )
        .map_err(|e| e.to_string())?
        .ok_or("cancelled")?;
        let elapsed = timed.elapsed;
        last = Some(timed);
        Ok::<_, String>(elapsed)
    })?;
    let Timed { image, stats, .. } = last.ok_or("no run")?;
    Ok((median, stats, image))
}

/// The app's render time for `scene` with `threads` render threads,
/// median of `runs`: the render worker's own path, as the window asks for
/// a picture (coarse to fine, [`rayoflight::render::passes`]), without a
/// window, from the request to the full picture (every pass, as the user
/// waits for it). A new worker each run: the first render of a scene
/// prepares it, as the command line does.
#[cfg(feature = "session")]
fn app_time(scene: &Scene, threads: usize, runs: usize) -> Result<Option<Duration>, String> {
    use rayoflight::session::worker::{self, Event, Worker};
    let scene = std::sync::Arc::new(scene.clone());
    let passes = worker::passes(scene.camera.width, scene.camera.height);
    median_of(runs, || {
        let worker = Worker::spawn(threads, || {});
        let deadline = Instant::now() + Duration::from_secs(600);
        let generation =
            worker.request_passes(scene.clone(), RenderRequest::default(), passes.clone());
        // Events are taken as the window takes them, once a frame, not as
        // each tile lands: a reader woken by every tile would take a
        // core's share from the render on a small machine.
        while Instant::now() < deadline {
            std::thread::sleep(worker::FRAME);
            while let Some(event) = worker.next_event(Duration::ZERO) {
                match event {
                    Event::PassFinished {
                        generation: g,
                        scale: 1,
                        since_start,
                        ..
                    } if g == generation => return Ok(since_start),
                    Event::Failed { message, .. } => return Err(message),
                    _ => {}
                }
            }
        }
        Err("the app's worker did not answer".to_owned())
    })
    .map(Some)
}

/// Without the app (a headless build), nothing to time.
#[cfg(not(feature = "session"))]
fn app_time(_: &Scene, _: usize, _: usize) -> Result<Option<Duration>, String> {
    Ok(None)
}

fn povray_version() -> Option<String> {
    let out = Command::new("povray").arg("--version").output().ok()?;
    let text =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    text.lines()
        .find(|l| l.contains("POV-Ray"))
        .map(|l| l.trim().to_owned())
}

/// POV-Ray's own "Trace Time" for the exported scene (median of `runs`),
/// and how its image agrees with ours.
fn pov_render(
    scene: &Scene,
    threads: usize,
    runs: usize,
    ours: &image::RgbImage,
) -> Result<PovRun, String> {
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    std::fs::write(dir.path().join("scene.pov"), pov::export(scene)).map_err(|e| e.to_string())?;
    let median = median_of(runs, || {
        let out = Command::new("povray")
            .current_dir(dir.path())
            .args([
                format!("+WT{threads}"),
                "-A".into(),
                "+FN".into(),
                "File_Gamma=1.0".into(),
                "-D".into(),
                format!("+W{}", scene.camera.width),
                format!("+H{}", scene.camera.height),
                "+Iscene.pov".into(),
                "+Oscene.png".into(),
            ])
            .output()
            .map_err(|e| format!("povray: {e}"))?;
        let text = String::from_utf8_lossy(&out.stderr);
        let seconds = text
            .lines()
            .find(|l| l.contains("Trace Time:"))
            .and_then(|l| l.split('(').nth(1))
            .and_then(|l| l.split_whitespace().next())
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| format!("povray gave no trace time: {}", text.trim()))?;
        Ok::<_, String>(Duration::from_secs_f64(seconds))
    })?;
    let theirs = image::open(dir.path().join("scene.png"))
        .map_err(|e| format!("POV-Ray's image: {e}"))?
        .to_rgb8();
    let difference = Difference::between(ours, &theirs);
    Ok(PovRun {
        median,
        within1: difference.within1,
        max_diff: difference.max,
    })
}

/// Peak resident memory of loading, preparing and rendering `n` spheres,
/// less the resident memory before and the image itself, in MB. Linux
/// only: the peak is reset through /proc/self/clear_refs.
fn peak_memory(
    n: usize,
    width: u32,
    height: u32,
    threads: usize,
) -> Result<Option<(f64, f64)>, String> {
    let Some(peak) = PeakMemory::start() else {
        return Ok(None);
    };
    let text = generated::spheres_on_floor(n, width, height);
    let scene = scene::parse(&text, Path::new("generated.xml")).map_err(|e| e.to_string())?;
    let (_, _, image) = time_render(&scene, threads, 1)?;
    let image_mb = image.as_raw().len() as f64 / 1e6;
    let extra = peak.extra_mb().unwrap_or(0.0);
    drop(image);
    Ok(Some((extra - image_mb, image_mb)))
}

// ----- the command line -----

/// Time the bench scenes, against POV-Ray when it is installed.
///
/// Also thread scaling, cost against object count and peak memory.
#[derive(Args, Debug)]
#[command(
    override_usage = "rayoflight bench [--threads N] [--runs K] [--csv FILE] [--no-pov] \
                      [--split-size PIXELS]\n                        [--cores-size PIXELS] [--big-spheres N] [--quiet]"
)]
pub(super) struct BenchFlags {
    /// Render threads [default: one per core]
    #[arg(long, value_name = "N", value_parser = threads, allow_negative_numbers = true)]
    threads: Option<usize>,
    /// Runs per measurement; the median is reported.
    #[arg(long, value_name = "K", default_value_t = 3, value_parser = runs, allow_negative_numbers = true)]
    runs: usize,
    /// Also write the results as CSV to FILE (also --out).
    #[arg(long, short = 'o', visible_alias = "out", value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Do not render with POV-Ray, even where it is installed.
    #[arg(long)]
    no_pov: bool,
    /// No progress bar on stderr.
    #[arg(short, long)]
    quiet: bool,
    /// The side of the image split into 64 regions and assembled, in
    /// pixels (0: skip that section).
    #[arg(
        long,
        value_name = "PIXELS",
        default_value_t = 16000,
        value_parser = split_size,
        allow_negative_numbers = true
    )]
    split_size: u32,
    /// The width of the render (4:3) run as a whole process, and then
    /// assembled from 16 parts, pinned to one core and on every core
    /// (0: skip that section).
    #[arg(
        long,
        value_name = "PIXELS",
        default_value_t = 6000,
        value_parser = cores_size,
        allow_negative_numbers = true
    )]
    cores_size: u32,
    /// Spheres in the big scene loaded, checked and prepared against
    /// xmllint's streaming parse of the same file (0: skip that section).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1_000_000,
        value_parser = big_spheres,
        allow_negative_numbers = true
    )]
    big_spheres: usize,
    /// The big section's own child: the app without its window on FILE,
    /// printing its peak memory after each stage.
    #[arg(long, value_name = "FILE", hide = true)]
    app_document: Option<PathBuf>,
}

impl Subcommand for BenchFlags {
    type Args = BenchArgs;

    fn resolve(self, _: &clap::ArgMatches) -> Result<BenchArgs, UsageError> {
        Ok(BenchArgs {
            threads: self.threads.unwrap_or_else(rayoflight::render::all_cores),
            runs: self.runs,
            csv: self.csv,
            pov: !self.no_pov,
            quiet: self.quiet,
            split_size: self.split_size,
            cores_size: self.cores_size,
            big_spheres: self.big_spheres,
            app_document: self.app_document,
        })
    }

    fn prints(_: &BenchArgs) -> bool {
        true
    }

    fn run(args: BenchArgs, _: fn() -> clap::Command) -> Result<(), Failure> {
        let steps = Steps::new(progress::wanted(args.quiet));
        run_bench(&args, &steps).map_err(Failure::Error)
    }
}

/// The bench's section of one core against all: 0 (skipped), or a width
/// from 64 pixels (16 parts of a 64×48 image) to the render's limit.
fn cores_size(text: &str) -> Result<u32, String> {
    let max = (rayoflight::scene::MAX_PIXELS / 3 * 4).isqrt();
    text.parse::<u64>()
        .ok()
        .filter(|&n| n == 0 || (64..=max).contains(&n))
        .and_then(|n| u32::try_from(n).ok())
        .ok_or_else(|| format!("expects 0 (skip the section) or a width from 64 to {max} pixels"))
}

/// The bench's split section: 0 (skipped), or a square image of at least
/// a pixel per task and at most the render's limit of pixels.
fn split_size(text: &str) -> Result<u32, String> {
    let tasks = SPLIT_TASKS as u64;
    let (min, max) = (
        tasks.isqrt() + u64::from(tasks.isqrt().pow(2) < tasks),
        rayoflight::scene::MAX_PIXELS.isqrt(),
    );
    text.parse::<u64>()
        .ok()
        .filter(|&n| n == 0 || (min..=max).contains(&n))
        .and_then(|n| u32::try_from(n).ok())
        .ok_or_else(|| format!("expects 0 (skip the section) or a side from {min} to {max} pixels"))
}

/// The bench's big scene: 0 (skipped), or up to four million spheres
/// (about 930 MB of XML, under the 1 GiB a scene file may take).
fn big_spheres(text: &str) -> Result<usize, String> {
    text.parse::<usize>()
        .ok()
        .filter(|&n| n <= MAX_BIG_SPHERES)
        .ok_or_else(|| {
            format!(
                "expects 0 (skip the section) or a count up to {}",
                MAX_BIG_SPHERES
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_serial_share_is_amdahls() {
        let ms = Duration::from_millis;
        assert!((serial_share(ms(100), ms(55), 2) - 0.1).abs() < 1e-9);
        assert_eq!(serial_share(ms(100), ms(100), 2), 1.0);
        assert_eq!(serial_share(ms(100), ms(50), 2), 0.0);
        assert_eq!(serial_share(ms(100), ms(40), 2), 0.0, "past n: caches");
        // 12x on 16 threads: about 2 % serial.
        let twelve = Duration::from_secs_f64(100.0 / 12.0);
        assert!((serial_share(Duration::from_secs(100), twelve, 16) - 0.0222).abs() < 1e-3);
    }
}
