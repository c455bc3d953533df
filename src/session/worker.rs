//! The render worker: the owner of all rendering for the app — a
//! background thread and its queue, a thread for each export (on its
//! pools) and for each pixel explained ([`Worker::explain`]: a deep
//! whitted tree on a big scene takes a while) — so that the UI thread never
//! renders, explains or prepares a scene. It only picks: one primary ray
//! through the scene the worker prepared ([`Worker::prepared`]).
//!
//! Every request gets a generation number. A newer request cancels the older
//! one within a pixel (the [`Cancel`] token is checked before every pixel),
//! and requests that queued up while a render ran are skipped for the
//! newest, so dragging a slider never stacks renders behind each other.
//! Each request is the core's progressive render
//! ([`measure::progressive_timed`]: resolved here, as `auto` looks at every
//! object, prepared once, traced coarse to fine — 1/8, 1/4, then full
//! resolution for large images — and timed as the command line's render
//! is); every finished tile is sent to the UI at once, with a wake-up call
//! at most once a [`FRAME`] so that the window draws only as often as it
//! can show something new. The next request reuses the prepared scene when
//! only the camera or the anti-aliasing changed, and its geometry when only
//! colours, materials, lights or the model changed (refitted, not built
//! again, when a few objects moved); the app picks objects in it
//! ([`Worker::prepared`]).
//!
//! A render uses every core ([`Worker::default_threads`]); one asked for
//! while the user drags ([`Worker::request_while_dragging`]) runs on a pool
//! of one thread fewer, so that the window keeps a core for the gesture.
//!
//! The worker also runs the study of the current scene ([`Worker::study`]):
//! it is a request like a render, with a generation, cancelled the same way
//! (by a newer request or [`Worker::cancel`]), reporting each row as it is
//! measured.
//!
//! The app's other renders go through it too, each handing its result to
//! a callback: the pass shown in place of the picture
//! ([`Worker::render_pass`]) and the object ids behind the selection's
//! outline ([`Worker::object_ids`]) are jobs of its queue, done after the
//! newest render (a newer one of each kind replacing one not yet begun; a
//! pass is cancelled too by any newer render); an export
//! ([`Worker::export`]) runs beside the preview on a thread of its own, on
//! the worker's pool.

use crate::render::measure::{self, PassTime};
use crate::render::request::RenderRequest;
use crate::render::{
    self, Cancel, LastPrepared, ObjectIds, Pass, PassImage, Prepared, Progress, RenderError,
    RenderOptions, RenderPool, Tile,
};
use crate::scene::Scene;
use crate::study::{self, Row, StudyError, StudyScene, chart};
use image::RgbImage;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The shortest time between two wake-up calls for tiles: the window needs
/// a frame only when tiles arrive, and about 30 a second show a render
/// coming in as well as more would, for far less of the cores it shares.
pub const FRAME: Duration = Duration::from_millis(33);

/// The passes of a render of a `width` × `height` image (the core's
/// [`render::passes`]).
pub use crate::render::passes;

/// What the worker reports, tagged with the request's generation.
#[derive(Debug)]
pub enum Event {
    /// A pass began, at 1/`scale` of the full resolution.
    PassStarted {
        generation: u64,
        scale: u32,
        /// Size of the full image.
        width: u32,
        height: u32,
    },
    /// A finished tile of a pass: row-major RGB8 pixels of the pass's
    /// (scaled-down) image.
    Tile {
        generation: u64,
        scale: u32,
        tile: Tile,
        pixels: Vec<u8>,
    },
    /// The pass is complete.
    PassFinished {
        generation: u64,
        scale: u32,
        /// Time of this pass alone.
        elapsed: Duration,
        /// Time since the worker took the request (all passes so far).
        since_start: Duration,
        /// Time from the request to its first pass: resolving it and
        /// preparing the scene (next to nothing when the last request's
        /// prepared scene served). With `elapsed` of the full-size pass:
        /// render time, as [`crate::render::measure`](mod@crate::render::measure) defines it.
        prepare: Duration,
        /// Rays traced in this pass, primary and reflected (as `RenderStats`).
        rays: u64,
    },
    /// The render could not run (bad options).
    Failed { generation: u64, message: String },
    /// A study began: `total` methods to measure.
    StudyStarted { generation: u64, total: usize },
    /// One method of the study is measured; `failure` is its side-by-side
    /// picture (method, reference, difference) when it failed.
    StudyRow {
        generation: u64,
        row: Row,
        failure: Option<RgbImage>,
    },
    /// The study is complete (every row was sent).
    StudyFinished { generation: u64, elapsed: Duration },
    /// The study stopped before its end: cancelled, or a render failed.
    StudyStopped { generation: u64, message: String },
}

impl Event {
    pub fn generation(&self) -> u64 {
        match self {
            Event::PassStarted { generation, .. }
            | Event::Tile { generation, .. }
            | Event::PassFinished { generation, .. }
            | Event::Failed { generation, .. }
            | Event::StudyStarted { generation, .. }
            | Event::StudyRow { generation, .. }
            | Event::StudyFinished { generation, .. }
            | Event::StudyStopped { generation, .. } => *generation,
        }
    }
}

enum Message {
    Render {
        generation: u64,
        scene: Arc<Scene>,
        /// Resolved here, off the UI thread: `auto` looks at every object.
        request: RenderRequest,
        /// The passes, coarsest first, as 1/scale of each side.
        passes: Vec<u32>,
        /// Asked for while the user drags: on the smaller pool.
        dragging: bool,
    },
    Study {
        generation: u64,
        scene: Box<StudyScene>,
        runs: usize,
        progress: Arc<study::StudyProgress>,
    },
    Pass {
        scene: Arc<Scene>,
        request: RenderRequest,
        pass: Pass,
        /// The caller's token, also cancelled by a newer render.
        cancel: Cancel,
        done: Box<dyn FnOnce(PassImage) + Send>,
    },
    Ids {
        scene: Arc<Scene>,
        scale: u32,
        done: Box<dyn FnOnce(ObjectIds) + Send>,
    },
    Quit,
}

/// The messages waiting: the newest render or study, object ids and
/// pass (each replacing an older one of its kind), and whether to quit.
#[derive(Default)]
struct Pending {
    render: Option<Message>,
    ids: Option<Message>,
    pass: Option<Message>,
    quit: bool,
}

impl Pending {
    fn add(&mut self, message: Message) {
        match message {
            Message::Quit => self.quit = true,
            Message::Render { .. } | Message::Study { .. } => self.render = Some(message),
            Message::Ids { .. } => self.ids = Some(message),
            Message::Pass { .. } => self.pass = Some(message),
        }
    }

    fn is_empty(&self) -> bool {
        !self.quit && self.render.is_none() && self.ids.is_none() && self.pass.is_none()
    }

    /// What to do next: quit, else the render, the ids, the pass.
    fn next(&mut self) -> Option<Message> {
        if self.quit {
            return Some(Message::Quit);
        }
        self.render
            .take()
            .or_else(|| self.ids.take())
            .or_else(|| self.pass.take())
    }
}

/// What an export asks the worker to render.
pub struct ExportJob {
    pub scene: Scene,
    /// Resolved on the export's thread (`auto` looks at every object).
    pub request: RenderRequest,
    /// The pass shown, when the file takes it ([`crate::output::takes_pass`]);
    /// `None`: the picture.
    pub pass: Option<Pass>,
    pub progress: Arc<Progress>,
    pub cancel: Cancel,
}

/// What an export rendered.
pub enum Exported {
    Picture(RgbImage),
    Pass(PassImage),
}

/// Handle to the worker thread. Dropping it stops the worker promptly.
pub struct Worker {
    newest: Arc<AtomicU64>,
    latest: Arc<LastPrepared>,
    /// The render threads, shared with exports.
    pool: Arc<RenderPool>,
    to_worker: Sender<Message>,
    events: Receiver<Event>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the worker with `threads` render threads (one fewer while
    /// the user drags); `wake` is called when an event is ready, for tiles
    /// at most once a [`FRAME`] (the app passes `request_repaint`).
    pub fn spawn(threads: usize, wake: impl Fn() + Send + Sync + 'static) -> Worker {
        let newest = Arc::new(AtomicU64::new(0));
        let latest = Arc::new(LastPrepared::default());
        let threads = threads.max(1);
        // A pool that cannot start renders on the global one.
        let pool = Arc::new(
            RenderPool::named(threads, "render").unwrap_or_else(|_| RenderPool::current()),
        );
        let (to_worker, inbox) = mpsc::channel();
        let (events_tx, events) = mpsc::channel();
        let state = WorkerThread {
            newest: newest.clone(),
            latest: latest.clone(),
            inbox,
            outbox: Outbox {
                events: events_tx,
                wake: Arc::new(wake),
                born: Instant::now(),
                woken: AtomicU64::new(0),
            },
            pool: Arc::clone(&pool),
            dragging_pool: (threads > 1)
                .then(|| RenderPool::named(threads - 1, "render-drag").ok())
                .flatten(),
        };
        let thread = std::thread::Builder::new()
            .name("render-worker".into())
            .spawn(move || state.run())
            .ok();
        Worker {
            newest,
            latest,
            pool,
            to_worker,
            events,
            thread,
        }
    }

    /// The default thread count for the app: every core, as the command
    /// line uses. The window draws a frame only when something changed
    /// (tiles at most once a [`FRAME`]), and a render asked for while the
    /// user drags leaves it a core ([`Worker::request_while_dragging`]).
    pub fn default_threads() -> usize {
        render::all_cores()
    }

    /// Asks for a render, coarse to fine ([`passes`]); cancels any older
    /// one. Returns its generation.
    pub fn request(&self, scene: Arc<Scene>, request: RenderRequest) -> u64 {
        let passes = passes(scene.camera.width, scene.camera.height);
        self.request_passes(scene, request, passes)
    }

    /// Asks for a render in the given passes (1/scale of each side,
    /// coarsest first; `[4]` alone renders only a quarter-size picture, for
    /// while the mouse moves). Cancels any older one; returns its
    /// generation.
    pub fn request_passes(
        &self,
        scene: Arc<Scene>,
        request: RenderRequest,
        passes: Vec<u32>,
    ) -> u64 {
        self.send_render(scene, request, passes, false)
    }

    /// Asks for one pass at 1/`scale` of each side, for while the user
    /// drags: on one thread fewer than the others, so that the window
    /// keeps a core for the gesture. Cancels any older request; returns
    /// its generation.
    pub fn request_while_dragging(
        &self,
        scene: Arc<Scene>,
        request: RenderRequest,
        scale: u32,
    ) -> u64 {
        self.send_render(scene, request, vec![scale], true)
    }

    fn send_render(
        &self,
        scene: Arc<Scene>,
        request: RenderRequest,
        passes: Vec<u32>,
        dragging: bool,
    ) -> u64 {
        let generation = self.newest.fetch_add(1, Ordering::Relaxed) + 1;
        let _ = self.to_worker.send(Message::Render {
            generation,
            scene,
            request,
            passes,
            dragging,
        });
        generation
    }

    /// Asks for the study of `scene` (every method, `runs` renders each);
    /// cancels any older request. Returns its generation.
    pub fn study(
        &self,
        scene: StudyScene,
        runs: usize,
        progress: Arc<study::StudyProgress>,
    ) -> u64 {
        let generation = self.newest.fetch_add(1, Ordering::Relaxed) + 1;
        let _ = self.to_worker.send(Message::Study {
            generation,
            scene: Box::new(scene),
            runs,
            progress,
        });
        generation
    }

    /// Asks for `pass` of `scene` (a full-size render of it), after the
    /// newest render; `done` gets it unless `cancel` or a newer render
    /// request stopped it first (a failed render gives nothing either: the
    /// picture's render says why).
    pub fn render_pass(
        &self,
        scene: Arc<Scene>,
        request: RenderRequest,
        pass: Pass,
        cancel: Cancel,
        done: impl FnOnce(PassImage) + Send + 'static,
    ) {
        let cancel = cancel.or_when(self.newest.clone(), self.newest());
        let _ = self.to_worker.send(Message::Pass {
            scene,
            request,
            pass,
            cancel,
            done: Box::new(done),
        });
    }

    /// Asks for the object seen at each pixel of `scene`'s image at
    /// 1/`scale` of each side ([`render::object_ids`]), after the newest
    /// render, in the scene it prepared when it is this one.
    pub fn object_ids(
        &self,
        scene: Arc<Scene>,
        scale: u32,
        done: impl FnOnce(ObjectIds) + Send + 'static,
    ) {
        let _ = self.to_worker.send(Message::Ids {
            scene,
            scale,
            done: Box::new(done),
        });
    }

    /// Renders `job` at full size on a thread of its own, beside the
    /// preview, on the worker's threads, counting in its progress and
    /// stopping with its token; `done` gets the image (`Ok(None)`:
    /// cancelled) on that thread.
    pub fn export(
        &self,
        job: ExportJob,
        done: impl FnOnce(Result<Option<Exported>, RenderError>) + Send + 'static,
    ) {
        type Done = Box<dyn FnOnce(Result<Option<Exported>, RenderError>) + Send>;
        // `done` is called once: on the thread, or here if none starts.
        let slot: Arc<Mutex<Option<Done>>> = Arc::new(Mutex::new(Some(Box::new(done))));
        let take = |slot: &Mutex<Option<Done>>| slot.lock().ok().and_then(|mut d| d.take());
        let (pool, theirs) = (Arc::clone(&self.pool), Arc::clone(&slot));
        let spawned = std::thread::Builder::new()
            .name("export".into())
            .spawn(move || {
                if let Some(done) = take(&theirs) {
                    done(export(&job, &pool));
                }
            });
        if let Err(e) = spawned
            && let Some(done) = take(&slot)
        {
            done(Err(RenderError::Thread(e)));
        }
    }

    /// Cancels whatever is rendering, without starting anything new.
    pub fn cancel(&self) {
        self.newest.fetch_add(1, Ordering::Relaxed);
    }

    /// `scene` prepared (with the preview's method, seen as its full-size
    /// pass is), if the worker last prepared it or the same scene seen from
    /// another camera: the app picks and explains in it, as preparing a
    /// million objects takes a second.
    pub fn prepared(&self, scene: &Scene) -> Option<Prepared> {
        self.latest.seen_from(scene)
    }

    /// Explains pixel (`x`, `y`) of `prepared` on a thread of its own,
    /// then hands the answer (`None`: outside the picture) to `done`.
    pub fn explain(
        &self,
        prepared: Prepared,
        (x, y): (u32, u32),
        done: impl FnOnce(Option<crate::render::Explanation>) + Send + 'static,
    ) {
        let _ = std::thread::Builder::new()
            .name("explain".to_owned())
            .spawn(move || done(prepared.explain(x, y)));
    }

    /// The newest generation requested.
    pub fn newest(&self) -> u64 {
        self.newest.load(Ordering::Relaxed)
    }

    /// Events ready now, oldest first.
    pub fn events(&self) -> impl Iterator<Item = Event> + '_ {
        self.events.try_iter()
    }

    /// Waits up to `timeout` for the next event (for tests and batch use).
    pub fn next_event(&self, timeout: Duration) -> Option<Event> {
        self.events.recv_timeout(timeout).ok()
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        // A generation no request has: the running render stops at its next
        // pixel, then the thread reads Quit.
        self.newest.store(u64::MAX, Ordering::Relaxed);
        let _ = self.to_worker.send(Message::Quit);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

struct WorkerThread {
    newest: Arc<AtomicU64>,
    latest: Arc<LastPrepared>,
    inbox: Receiver<Message>,
    outbox: Outbox,
    pool: Arc<RenderPool>,
    /// One thread fewer, for renders asked for while the user drags (none
    /// with a single thread).
    dragging_pool: Option<RenderPool>,
}

/// Where events go, and the wake-up calls (used from the render threads).
struct Outbox {
    events: Sender<Event>,
    wake: Arc<dyn Fn() + Send + Sync>,
    /// When the worker started, and the last wake-up call, in
    /// milliseconds since then.
    born: Instant,
    woken: AtomicU64,
}

impl WorkerThread {
    fn run(self) {
        let mut pending = Pending::default();
        loop {
            if pending.is_empty() {
                match self.inbox.recv() {
                    Ok(message) => pending.add(message),
                    Err(_) => return,
                }
            }
            // Requests that queued up meanwhile: the newest of each kind.
            while let Ok(newer) = self.inbox.try_recv() {
                pending.add(newer);
            }
            match pending.next() {
                None => {}
                Some(Message::Quit) => return,
                Some(message) => self.handle(message),
            }
        }
    }

    fn handle(&self, message: Message) {
        match message {
            Message::Quit => {}
            Message::Render {
                generation,
                scene,
                request,
                passes,
                dragging,
            } => {
                let cancel = Cancel::new(self.newest.clone(), generation);
                if !cancel.is_cancelled() {
                    let pool = match &self.dragging_pool {
                        Some(pool) if dragging => pool,
                        _ => &*self.pool,
                    };
                    self.render(generation, &scene, &request, &passes, pool, &cancel);
                }
            }
            Message::Study {
                generation,
                scene,
                runs,
                progress,
            } => {
                let cancel = Cancel::new(self.newest.clone(), generation);
                if !cancel.is_cancelled() {
                    self.study(generation, &scene, runs, &cancel, &progress);
                }
            }
            Message::Pass {
                scene,
                request,
                pass,
                cancel,
                done,
            } => {
                if cancel.is_cancelled() {
                    return;
                }
                let options = RenderOptions {
                    threads: None,
                    ..request.options(&scene)
                };
                let rendered = self.pool.install(|| {
                    render::render_pass(&scene, &options, pass, &cancel, &Progress::default())
                });
                if let Ok(Some((image, _))) = rendered {
                    done(image);
                }
            }
            Message::Ids { scene, scale, done } => {
                let prepared = self
                    .latest
                    .seen_from(&scene)
                    .unwrap_or_else(|| render::prepare(&scene, &RenderOptions::default()));
                done(
                    self.pool
                        .install(|| render::object_ids(&prepared, &scene.camera, scale)),
                );
            }
        }
    }

    fn send(&self, event: Event) {
        self.outbox.send(event);
    }

    /// Renders `request` progressively on `pool`, sending each pass's
    /// start, tiles and end (or why it could not run).
    fn render(
        &self,
        generation: u64,
        scene: &Arc<Scene>,
        request: &RenderRequest,
        passes: &[u32],
        pool: &RenderPool,
        cancel: &Cancel,
    ) {
        let (width, height) = (scene.camera.width, scene.camera.height);
        let outbox = &self.outbox;
        let done = measure::progressive_timed(
            scene,
            request,
            passes,
            &self.latest,
            pool,
            cancel,
            &mut |step| {
                outbox.send(match step {
                    PassTime::Started { scale } => Event::PassStarted {
                        generation,
                        scale,
                        width,
                        height,
                    },
                    PassTime::Finished {
                        scale,
                        rays,
                        elapsed,
                        since_start,
                        prepare,
                    } => Event::PassFinished {
                        generation,
                        scale,
                        elapsed,
                        since_start,
                        prepare,
                        rays,
                    },
                })
            },
            &|scale, tile: &Tile, pixels: &[u8]| {
                outbox.send_tile(Event::Tile {
                    generation,
                    scale,
                    tile: *tile,
                    pixels: pixels.to_vec(),
                })
            },
        );
        if let Err(e) = done {
            self.send(Event::Failed {
                generation,
                message: e.to_string(),
            });
        }
    }
}

impl Outbox {
    fn send(&self, event: Event) {
        let _ = self.events.send(event);
        self.woken.store(self.since_born(), Ordering::Relaxed);
        (self.wake)();
    }

    fn since_born(&self) -> u64 {
        u64::try_from(self.born.elapsed().as_millis()).unwrap_or(u64::MAX)
    }

    /// Sends a tile (from a render thread), waking the UI if it was not
    /// woken in the last [`FRAME`]: the tiles between wake-ups are drawn
    /// by the next frame.
    fn send_tile(&self, event: Event) {
        let _ = self.events.send(event);
        let now = self.since_born();
        let last = self.woken.load(Ordering::Relaxed);
        let frame = u64::try_from(FRAME.as_millis()).unwrap_or(u64::MAX);
        if now.saturating_sub(last) >= frame
            && self
                .woken
                .compare_exchange(last, now, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
        {
            (self.wake)();
        }
    }
}

impl WorkerThread {
    /// Runs the study on the worker's pool, one row at a time.
    fn study(
        &self,
        generation: u64,
        scene: &StudyScene,
        runs: usize,
        cancel: &Cancel,
        progress: &study::StudyProgress,
    ) {
        let methods = render::methods();
        self.send(Event::StudyStarted {
            generation,
            total: methods.len(),
        });
        let start = Instant::now();
        let scenes = std::slice::from_ref(scene);
        let outbox = &self.outbox;
        let run = || {
            study::run(
                scenes,
                &methods,
                runs,
                None,
                cancel,
                progress,
                &mut |row, image, reference| {
                    outbox.send(Event::StudyRow {
                        generation,
                        row: row.clone(),
                        failure: row.failed.then(|| chart::side_by_side(image, reference)),
                    });
                },
            )
        };
        let result = self.pool.install(run);
        match result {
            Ok(_) => self.send(Event::StudyFinished {
                generation,
                elapsed: start.elapsed(),
            }),
            Err(StudyError::Cancelled) => self.send(Event::StudyStopped {
                generation,
                message: "cancelled".into(),
            }),
            Err(e) => self.send(Event::StudyStopped {
                generation,
                message: e.to_string(),
            }),
        }
    }
}

/// Renders an export's picture or pass on `pool`.
fn export(job: &ExportJob, pool: &RenderPool) -> Result<Option<Exported>, RenderError> {
    let options = RenderOptions {
        threads: None,
        ..job.request.options(&job.scene)
    };
    pool.install(|| match job.pass {
        Some(pass) => render::render_pass(&job.scene, &options, pass, &job.cancel, &job.progress)
            .map(|done| done.map(|(image, _)| Exported::Pass(image))),
        None => render::render_watched(&job.scene, &options, &job.cancel, &job.progress)
            .map(|done| done.map(|(image, _)| Exported::Picture(image))),
    })
}
