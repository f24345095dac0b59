//! The selection of the view ahead that prefetch uploads from (`plan.rs`'s `prefetch`), made off
//! the frame thread. It is a whole selection (the Inn valley at 1280×720: about as much CPU as
//! the frame's own), made once every `PREFETCH_RESELECT_FRAMES` frames: on the frame thread it
//! made every fourth frame the slowest by that much.
//!
//! The protocol keeps the plans independent of the worker's timing: a request made at one
//! reselect is taken at the next, the frame waiting for it if it is not done (it has had the
//! frames between). So the frames after a reselect prefetch from the selection of the inputs
//! the previous reselect sent, looking `prefetch_frames` ahead of that frame — whether it was
//! made on the worker or, with [`AheadSelector::inline`], on the frame thread at the take.
//! The tests run both and compare the plans.
//!
//! The worker looks for requests every [`POLL`] while they come (for [`POLL_FOR`] after its
//! last job), so that sending one wakes no thread: waking it from the frame thread cost that
//! frame 15–30 µs on a virtual machine. Every fourth frame's selection + plan against the mean
//! of its two neighbours, `fly --no-draw` at 1280×720, τ = 1, 4 runs each: Inn manoeuvre +31 →
//! +13 µs, Northern England manoeuvre +29 → +12 µs with the worker looking.

use std::sync::mpsc::{channel, Receiver, Sender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use aerie_terrain::bake::ErrorBake;
use aerie_terrain::camera::Camera;
use aerie_terrain::clipmap::{ClipmapDesc, LevelPlacement};
use aerie_terrain::select::{select_tiles, SelectParams, Selection};

/// Everything one selection of the view ahead reads.
pub struct AheadJob {
    pub bake: Arc<ErrorBake>,
    pub clipmap: ClipmapDesc,
    pub placements: Vec<LevelPlacement>,
    pub camera: Camera,
    pub viewport: (u32, u32),
    pub params: SelectParams,
}

impl AheadJob {
    /// The selection, into `sel` (its allocations and node cache reused).
    fn run(&self, sel: &mut Selection) {
        select_tiles(
            &self.bake,
            &self.clipmap,
            &self.placements,
            &self.camera,
            self.viewport,
            &self.params,
            sel,
        );
    }
}

type Request = (AheadJob, Selection);

/// How long the worker sleeps between two looks for a request, while it looks.
const POLL: Duration = Duration::from_micros(500);

/// How long after its last job the worker keeps looking for the next request before it waits
/// to be woken. A request sent to a waiting worker wakes it from the frame thread: a futex
/// wake of a thread on the other core, 15–30 µs of the frame thread's time on a virtual
/// machine (every fourth frame's `reselect`; the Inn manoeuvre, 1280×720); one that finds it
/// looking costs the frame thread nothing but the send. Requests come every
/// `PREFETCH_RESELECT_FRAMES` frames (133 ms at 30 fps), so a flight keeps the worker looking;
/// a renderer left idle lets it sleep.
pub(crate) const POLL_FOR: Duration = Duration::from_millis(250);

/// The worker thread: a request in, its selection out, until the request side is dropped.
struct Worker {
    /// `None` once dropped: closing it ends the worker's loop.
    requests: Option<Sender<Request>>,
    results: Receiver<Selection>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    fn spawn() -> Option<Self> {
        let (requests, jobs) = channel::<Request>();
        let (done, results) = channel::<Selection>();
        let thread = std::thread::Builder::new()
            .name("aerie-ahead-select".into())
            .spawn(move || {
                let mut last_job = Instant::now();
                loop {
                    let (job, mut sel) = match jobs.try_recv() {
                        Ok(request) => request,
                        Err(TryRecvError::Disconnected) => break,
                        Err(TryRecvError::Empty) if last_job.elapsed() < POLL_FOR => {
                            std::thread::sleep(POLL);
                            continue;
                        }
                        Err(TryRecvError::Empty) => match jobs.recv() {
                            Ok(request) => request,
                            Err(_) => break,
                        },
                    };
                    job.run(&mut sel);
                    if done.send(sel).is_err() {
                        break;
                    }
                    last_job = Instant::now();
                }
            })
            .ok()?;
        Some(Self {
            requests: Some(requests),
            results,
            thread: Some(thread),
        })
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        // Closing the request channel ends the worker's loop once its job (if any) is done.
        drop(self.requests.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Where the selection of the view ahead is made, and the one request in flight.
pub struct AheadSelector {
    /// `None`: inline, or a worker that could not be started or failed (then inline too).
    worker: Option<Worker>,
    wanted_worker: bool,
    /// Inline: the request kept until it is taken.
    pending: Option<Request>,
    in_flight: bool,
}

impl AheadSelector {
    /// Selections made on a worker thread, started at the first request.
    pub fn threaded() -> Self {
        Self {
            worker: None,
            wanted_worker: true,
            pending: None,
            in_flight: false,
        }
    }

    /// Selections made on the frame thread when taken (the same results).
    pub fn inline() -> Self {
        Self {
            wanted_worker: false,
            ..Self::threaded()
        }
    }

    /// One reselect: `current` becomes the selection of the request in flight when `fresh`
    /// (sent by the reselect just before this one), else `job`'s, made now on this thread;
    /// then `job` goes out for the next reselect, into `current`'s old allocations.
    pub fn reselect(&mut self, job: AheadJob, fresh: bool, current: &mut Selection) {
        let buffer = match (self.take(), fresh) {
            (Some(sel), true) => std::mem::replace(current, sel),
            // A stale result (or none): its allocations and node cache serve the next request.
            (stale, _) => {
                job.run(current);
                stale.unwrap_or_default()
            }
        };
        self.request(job, buffer);
    }

    /// Whether the selections are made on a worker thread (one started and still running).
    pub fn on_worker(&self) -> bool {
        self.worker.is_some()
    }

    /// Whether a request waits to be taken.
    pub fn in_flight(&self) -> bool {
        self.in_flight
    }

    /// Asks for `job`'s selection, made into `buffer`. A request still in flight is dropped
    /// first (its result is not wanted).
    pub fn request(&mut self, job: AheadJob, buffer: Selection) {
        if self.in_flight {
            self.take();
        }
        if self.wanted_worker && self.worker.is_none() {
            self.worker = Worker::spawn();
            self.wanted_worker = self.worker.is_some();
        }
        let request = (job, buffer);
        let request = match self.worker.as_ref().and_then(|w| w.requests.as_ref()) {
            Some(requests) => match requests.send(request) {
                Ok(()) => {
                    self.in_flight = true;
                    return;
                }
                // The worker is gone: made inline from now on.
                Err(e) => e.0,
            },
            None => request,
        };
        self.worker = None;
        self.wanted_worker = false;
        self.pending = Some(request);
        self.in_flight = true;
    }

    /// The selection of the request in flight, waiting for it; `None` when there is none (or
    /// the worker died with it: the next request is made inline).
    pub fn take(&mut self) -> Option<Selection> {
        if !std::mem::take(&mut self.in_flight) {
            return None;
        }
        if let Some((job, mut sel)) = self.pending.take() {
            job.run(&mut sel);
            return Some(sel);
        }
        let result = self.worker.as_ref()?.results.recv().ok();
        if result.is_none() {
            self.worker = None;
            self.wanted_worker = false;
        }
        result
    }
}

impl Default for AheadSelector {
    fn default() -> Self {
        Self::threaded()
    }
}
