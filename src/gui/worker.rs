//! The render worker: one background thread that owns all rendering for the
//! app, so the UI thread never traces a ray.
//!
//! Every request gets a generation number. A newer request cancels the older
//! one within a pixel (the [`Cancel`] token is checked before every pixel),
//! and requests that queued up while a render ran are skipped for the
//! newest, so dragging a slider never stacks renders behind each other.
//! Each request is rendered coarse to fine (1/8, 1/4, then full
//! resolution for large images) and every finished tile is sent to the UI
//! at once, with a wake-up call so it repaints. The request is resolved
//! here (`auto` looks at every object) and the scene prepared once for all
//! its passes; the next request reuses that prepared scene when only the
//! camera or the anti-aliasing changed, and the app picks objects in it
//! ([`Worker::prepared`]).
//!
//! The worker also runs the study of the current scene ([`Worker::study`]):
//! it is a request like a render, with a generation, cancelled the same way
//! (by a newer request or [`Worker::cancel`]), reporting each row as it is
//! measured.

use crate::render::{self, Cancel, Prepared, RenderOptions, Tile};
use crate::request::RenderRequest;
use crate::scene::Scene;
use crate::study::{self, Row, StudyError, StudyScene, chart};
use image::RgbImage;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Below this many pixels the image is rendered in one full-resolution pass.
const SINGLE_PASS_PIXELS: u64 = 256 * 256;

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
        /// render time, as [`crate::measure`] defines it.
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
    },
    Study {
        generation: u64,
        scene: Box<StudyScene>,
        runs: usize,
    },
    Quit,
}

/// The scene the worker prepared last, the options it was prepared with,
/// and the prepared scene. The next request reuses it when only the camera
/// or the anti-aliasing changed (orbiting a million spheres prepares them
/// once), and the app picks objects in it rather than preparing again.
type Latest = Arc<Mutex<Option<(Arc<Scene>, RenderOptions, Prepared)>>>;

/// Handle to the worker thread. Dropping it stops the worker promptly.
pub struct Worker {
    newest: Arc<AtomicU64>,
    latest: Latest,
    to_worker: Sender<Message>,
    events: Receiver<Event>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the worker with `threads` render threads; `wake` is called
    /// whenever an event is ready (the app passes `request_repaint`).
    pub fn spawn(threads: usize, wake: impl Fn() + Send + Sync + 'static) -> Worker {
        let newest = Arc::new(AtomicU64::new(0));
        let latest = Latest::default();
        let (to_worker, inbox) = mpsc::channel();
        let (events_tx, events) = mpsc::channel();
        let state = WorkerThread {
            newest: newest.clone(),
            latest: latest.clone(),
            inbox,
            events: events_tx,
            wake: Arc::new(wake),
            pool: rayon::ThreadPoolBuilder::new()
                .num_threads(threads.max(1))
                .thread_name(|i| format!("render-{i}"))
                .build()
                .ok(),
        };
        let thread = std::thread::Builder::new()
            .name("render-worker".into())
            .spawn(move || state.run())
            .ok();
        Worker {
            newest,
            latest,
            to_worker,
            events,
            thread,
        }
    }

    /// The default thread count for the app: one fewer than the cores, at
    /// least one, so the UI thread keeps a core.
    pub fn default_threads() -> usize {
        std::thread::available_parallelism()
            .map(|n| n.get().saturating_sub(1))
            .unwrap_or(1)
            .max(1)
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
        let generation = self.newest.fetch_add(1, Ordering::Relaxed) + 1;
        let _ = self.to_worker.send(Message::Render {
            generation,
            scene,
            request,
            passes,
        });
        generation
    }

    /// Asks for the study of `scene` (every method, `runs` renders each);
    /// cancels any older request. Returns its generation.
    pub fn study(&self, scene: StudyScene, runs: usize) -> u64 {
        let generation = self.newest.fetch_add(1, Ordering::Relaxed) + 1;
        let _ = self.to_worker.send(Message::Study {
            generation,
            scene: Box::new(scene),
            runs,
        });
        generation
    }

    /// Cancels whatever is rendering, without starting anything new.
    pub fn cancel(&self) {
        self.newest.fetch_add(1, Ordering::Relaxed);
    }

    /// `scene` prepared (with the preview's method), if the worker last
    /// prepared it or the same scene seen from another camera: the app
    /// picks objects in it, as preparing a million objects takes a second.
    pub fn prepared(&self, scene: &Scene) -> Option<Prepared> {
        let latest = self.latest.lock().ok()?;
        let (prepared_scene, _, prepared) = latest.as_ref()?;
        prepared_scene
            .same_but_camera(scene)
            .then(|| prepared.with_view(&scene.camera, 1))
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
    latest: Latest,
    inbox: Receiver<Message>,
    events: Sender<Event>,
    wake: Arc<dyn Fn() + Send + Sync>,
    pool: Option<rayon::ThreadPool>,
}

impl WorkerThread {
    fn run(self) {
        while let Ok(mut message) = self.inbox.recv() {
            // Requests that queued up meanwhile: only the newest counts.
            while let Ok(newer) = self.inbox.try_recv() {
                message = newer;
            }
            match message {
                Message::Quit => return,
                Message::Render {
                    generation,
                    scene,
                    request,
                    passes,
                } => {
                    let cancel = Cancel::new(self.newest.clone(), generation);
                    if !cancel.is_cancelled() {
                        // Render time starts with the request resolved, as
                        // crate::measure defines it.
                        let start = Instant::now();
                        let options = request.options(&scene);
                        self.render(generation, &scene, &options, &passes, &cancel, start);
                    }
                }
                Message::Study {
                    generation,
                    scene,
                    runs,
                } => {
                    let cancel = Cancel::new(self.newest.clone(), generation);
                    if !cancel.is_cancelled() {
                        self.study(generation, &scene, runs, &cancel);
                    }
                }
            }
        }
    }

    fn send(&self, event: Event) {
        let _ = self.events.send(event);
        (self.wake)();
    }

    fn render(
        &self,
        generation: u64,
        scene: &Arc<Scene>,
        options: &RenderOptions,
        passes: &[u32],
        cancel: &Cancel,
        render_start: Instant,
    ) {
        if let Err(e) = options.validate() {
            self.send(Event::Failed {
                generation,
                message: e.to_string(),
            });
            return;
        }
        let (width, height) = (scene.camera.width, scene.camera.height);
        // The scene is prepared once (or was, for the last request, if only
        // the camera or the anti-aliasing changed); each pass is a view.
        let reused = self.latest.lock().ok().and_then(|latest| {
            let (last, last_options, prepared) = latest.as_ref()?;
            let same_options = RenderOptions {
                aa: options.aa,
                ..last_options.clone()
            } == *options;
            (same_options && last.same_but_camera(scene)).then(|| prepared.clone())
        });
        let prepared = reused.unwrap_or_else(|| {
            // The last one goes first: both may be large.
            if let Ok(mut latest) = self.latest.lock() {
                *latest = None;
            }
            let prepared = render::prepare(scene, options);
            if let Ok(mut latest) = self.latest.lock() {
                *latest = Some((Arc::clone(scene), options.clone(), prepared.clone()));
            }
            prepared
        });
        let prepare = render_start.elapsed();
        for &scale in passes {
            let scale = scale.max(1);
            if cancel.is_cancelled() {
                return;
            }
            self.send(Event::PassStarted {
                generation,
                scale,
                width,
                height,
            });
            let start = Instant::now();
            let mut camera = scene.camera.clone();
            camera.width = width.div_ceil(scale);
            camera.height = height.div_ceil(scale);
            // Coarse passes are previews: one ray per pixel.
            let aa = if scale == 1 { options.aa } else { 1 };
            let prepared = prepared.with_view(&camera, aa);
            // Tiles are sent from the render threads as they finish.
            let (events, wake) = (&self.events, &self.wake);
            let send_tile = |tile: &Tile, pixels: &[u8]| {
                let _ = events.send(Event::Tile {
                    generation,
                    scale,
                    tile: *tile,
                    pixels: pixels.to_vec(),
                });
                wake();
            };
            let progress = render::Progress::default();
            let trace = || {
                render::trace_tiles(
                    &prepared,
                    prepared.frame(),
                    cancel,
                    &progress,
                    None,
                    send_tile,
                )
            };
            let traced = match &self.pool {
                Some(pool) => pool.install(trace),
                None => trace(),
            };
            let Some(rays) = traced else {
                return;
            };
            self.send(Event::PassFinished {
                generation,
                scale,
                elapsed: start.elapsed(),
                since_start: render_start.elapsed(),
                prepare,
                rays,
            });
        }
    }
}

impl WorkerThread {
    /// Runs the study on the worker's pool, one row at a time.
    fn study(&self, generation: u64, scene: &StudyScene, runs: usize, cancel: &Cancel) {
        let methods = render::methods();
        self.send(Event::StudyStarted {
            generation,
            total: methods.len(),
        });
        let start = Instant::now();
        let scenes = std::slice::from_ref(scene);
        let (events, wake) = (&self.events, &self.wake);
        let run = || {
            study::run(
                scenes,
                &methods,
                runs,
                None,
                cancel,
                &mut |row, image, reference| {
                    let _ = events.send(Event::StudyRow {
                        generation,
                        row: row.clone(),
                        failure: row.failed.then(|| chart::side_by_side(image, reference)),
                    });
                    wake();
                },
            )
        };
        let result = match &self.pool {
            Some(pool) => pool.install(run),
            None => run(),
        };
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

/// The passes for an image: full resolution only when small, otherwise
/// 1/8, 1/4 and full. Both previews are coarse enough to be shown at their
/// own size ([`COARSE`](super::preview::COARSE)): a 1/2 pass painted at
/// full size uploaded four screen pixels per pixel traced and held a
/// 4000×4000 render's UI to 20 frames a second while it ran.
pub fn passes(width: u32, height: u32) -> Vec<u32> {
    if u64::from(width) * u64::from(height) <= SINGLE_PASS_PIXELS {
        vec![1]
    } else {
        vec![8, 4, 1]
    }
}
