//! Asynchronous stepping (`Batch.send_*` / `Batch.recv`): a thread of the batch's own that steps
//! it while Python works, made at the first `send` and kept (a thread per step would cost more
//! than a small batch's step), and the states a batch goes through with it.
//!
//! The thread holds no reference to the batch between steps: each job carries one, dropped when
//! the step is done, so a batch nobody refers to is freed, and its stepper with it (the thread
//! ends when its job queue closes).

use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::mpsc;

use pyo3::prelude::*;
use socnav::{Actions, SimError};

use super::Batch;

/// Where a batch is in the send/recv protocol ([`SendState`]).
const IDLE: u8 = 0;
const SENT: u8 = 1;
const RECEIVING: u8 = 2;

/// Whether a step was sent and not yet received, and whether a `recv` is waiting for it.
#[derive(Debug, Default)]
pub(crate) struct SendState(AtomicU8);

impl SendState {
    /// Why a call other than `recv` must wait, or `None` when nothing is in flight.
    pub(crate) fn busy(&self) -> Option<&'static str> {
        match self.0.load(Ordering::Acquire) {
            IDLE => None,
            SENT => Some(
                "a step was sent (send_*) and not yet received: call recv() before any other \
                 call on the batch",
            ),
            _ => Some("another thread is receiving a sent step (recv) from the batch"),
        }
    }

    /// Mark a step sent (the caller holds the batch, so nothing else is in flight).
    pub(crate) fn sent(&self) {
        self.0.store(SENT, Ordering::Release);
    }

    /// Claim the sent step for one `recv`: `Err` with why not (nothing sent, or another thread
    /// is receiving it).
    pub(crate) fn claim(&self) -> Result<(), &'static str> {
        match self
            .0
            .compare_exchange(SENT, RECEIVING, Ordering::AcqRel, Ordering::Acquire)
        {
            Ok(_) => Ok(()),
            Err(IDLE) => {
                Err("recv() without a step in flight: send_continuous() or send_discrete() first")
            }
            Err(_) => Err("another thread is receiving the sent step (recv)"),
        }
    }

    /// The claimed step was received: the batch is idle again.
    pub(crate) fn received(&self) {
        self.0.store(IDLE, Ordering::Release);
    }
}

/// Actions that a sent step owns while it runs on the stepper's thread.
pub(crate) enum OwnedActions {
    Continuous(Vec<f32>),
    Discrete(Vec<u32>),
}

impl OwnedActions {
    pub(crate) fn as_actions(&self) -> Actions<'_> {
        match self {
            OwnedActions::Continuous(a) => Actions::Continuous(a),
            OwnedActions::Discrete(a) => Actions::Discrete(a),
        }
    }
}

/// One step for the stepper: what to step, and with which actions.
pub(crate) struct Job {
    /// The batch, kept alive while it steps.
    pub(crate) owner: Py<Batch>,
    pub(crate) actions: OwnedActions,
}

impl Job {
    /// Step the batch. It waits for the batch's lock, which `send` lets go of after queueing
    /// the job: calls in between see the batch as sent ([`SendState::busy`]) and let go too.
    fn run(&self) -> Result<(), SimError> {
        let mut inner = self
            .owner
            .get()
            .inner
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        inner.env.step(self.actions.as_actions())
    }
}

/// The thread that runs sent steps, and the channels to it.
pub(crate) struct Stepper {
    jobs: mpsc::Sender<Job>,
    results: mpsc::Receiver<Result<(), SimError>>,
}

impl Stepper {
    /// Start the thread.
    pub(crate) fn start() -> Result<Self, SimError> {
        let (jobs, queue) = mpsc::channel::<Job>();
        let (done, results) = mpsc::channel();
        std::thread::Builder::new()
            .name("socnav-send".into())
            .spawn(move || {
                for job in queue {
                    let result = std::panic::catch_unwind(AssertUnwindSafe(|| job.run()))
                        .unwrap_or_else(|panic| {
                            Err(SimError::Internal(format!(
                                "the thread stepping the batch panicked: {}",
                                panic_message(panic.as_ref())
                            )))
                        });
                    // Without the GIL, pyo3 defers the decrement until it is next held.
                    drop(job);
                    if done.send(result).is_err() {
                        break;
                    }
                }
            })
            .map_err(|e| {
                SimError::Internal(format!("cannot start the thread that steps the batch: {e}"))
            })?;
        Ok(Self { jobs, results })
    }

    /// Queue `job`.
    pub(crate) fn send(&self, job: Job) -> Result<(), SimError> {
        self.jobs
            .send(job)
            .map_err(|_| SimError::Internal("the thread that steps the batch has ended".into()))
    }

    /// Wait for the result of the job queued last.
    pub(crate) fn recv(&self) -> Result<(), SimError> {
        self.results
            .recv()
            .map_err(|_| SimError::Internal("the thread that steps the batch has ended".into()))?
    }
}

fn panic_message(panic: &(dyn std::any::Any + Send)) -> &str {
    panic
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| panic.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("(no message)")
}
