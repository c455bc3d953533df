//! Progress bars on stderr for long work: a render (percentage, rays per
//! second, time left) and the steps of `bench` and `study`. A bar shows
//! only when stderr is a terminal, `--quiet` is not given and the work has
//! run for a second (shorter work stays silent), and it is cleared when
//! the work ends. The library only counts ([`render::Progress`]); drawing
//! is this edge's business (indicatif).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayoflight::render::{self, Progress};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Work shorter than this shows no bar.
const QUIET_FOR: Duration = Duration::from_secs(1);

/// How often the bar is redrawn.
const TICK: Duration = Duration::from_millis(100);

/// Whether bars are drawn: stderr is a terminal and `--quiet` was not
/// given.
pub fn wanted(quiet: bool) -> bool {
    !quiet && std::io::stderr().is_terminal()
}

/// Runs `work`, which counts into `progress`, while a bar follows it on
/// stderr (when `show`).
pub fn render<T>(progress: &Progress, show: bool, work: impl FnOnce() -> T) -> T {
    if !show {
        return work();
    }
    let done = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let drawer = scope.spawn(|| follow(progress, &done));
        let result = work();
        done.store(true, Ordering::Relaxed);
        drawer.thread().unpark();
        result
    })
}

/// Draws the bar of a render until `done`.
fn follow(progress: &Progress, done: &AtomicBool) {
    let start = Instant::now();
    if !wait(start, QUIET_FOR, done) {
        return;
    }
    let bar = ProgressBar::with_draw_target(Some(1), ProgressDrawTarget::stderr())
        .with_style(style("{bar:40} {percent:>3}% {msg}"));
    while !done.load(Ordering::Relaxed) {
        let (pixels, total) = progress.pixels();
        let elapsed = start.elapsed();
        bar.set_length(total.max(1));
        bar.set_position(pixels);
        let rays = progress.rays() as f64 / elapsed.as_secs_f64().max(1e-9);
        let left = progress
            .left(elapsed)
            .map_or_else(String::new, |left| format!(" · {} left", seconds(left)));
        bar.set_message(format!("{:.1} Mrays/s{left}", rays / 1e6));
        std::thread::park_timeout(TICK);
    }
    bar.finish_and_clear();
}

/// Waits until `start + quiet`, or less if `done`: whether to draw.
fn wait(start: Instant, quiet: Duration, done: &AtomicBool) -> bool {
    while start.elapsed() < quiet {
        if done.load(Ordering::Relaxed) {
            return false;
        }
        std::thread::park_timeout(TICK.min(quiet.saturating_sub(start.elapsed())));
    }
    !done.load(Ordering::Relaxed)
}

/// A bar over the `total` steps of `bench` or `study`, hidden unless
/// `show`; [`Steps::step`] names the step under way. Lines printed while
/// it shows go through [`Steps::print`], above the bar.
pub struct Steps {
    bar: ProgressBar,
    start: Instant,
    /// Bars are wanted, and the bar is drawn once a second has passed.
    show: bool,
    shown: std::cell::Cell<bool>,
}

impl Steps {
    /// A bar for steps not yet counted ([`Steps::set_total`]).
    pub fn new(show: bool) -> Steps {
        let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::hidden())
            .with_style(style("{bar:30} {pos}/{len} {msg}"));
        Steps {
            bar,
            start: Instant::now(),
            show,
            shown: std::cell::Cell::new(false),
        }
    }

    /// The number of steps, once known.
    pub fn set_total(&self, total: u64) {
        self.bar.set_length(total);
    }

    /// Step `name` begins, `done` steps before it are done.
    pub fn step(&self, done: u64, name: &str) {
        let elapsed = self.start.elapsed();
        // Short runs stay silent: the bar appears after a second.
        if self.show && !self.shown.get() && elapsed >= QUIET_FOR {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown.set(true);
        }
        self.bar.set_position(done);
        let left = render::time_left(elapsed, done, self.bar.length().unwrap_or(done))
            .map_or_else(String::new, |left| format!(" · {} left", seconds(left)));
        self.bar.set_message(format!(
            "{}{left}",
            rayoflight::system::escape::visible(name, false)
        ));
    }

    /// Prints `text` to stdout ([`super::stdout::write`]) without tearing
    /// the bar.
    pub fn print(&self, text: &str) -> Result<(), String> {
        self.bar.suspend(|| super::stdout::write(text))
    }
}

impl Drop for Steps {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar())
}

/// A duration as people read a countdown: "42 s", "3 min 05 s".
fn seconds(d: Duration) -> String {
    let s = d.as_secs_f64().ceil() as u64;
    if s < 60 {
        format!("{s} s")
    } else {
        format!("{} min {:02} s", s / 60, s % 60)
    }
}
