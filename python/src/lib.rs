//! `socnav._socnav`: the batch of environments as the Python class `Batch`, whose output
//! buffers numpy sees without copies (each array keeps the `Batch` alive and is overwritten by
//! the next `step` or `reset`), and the exception tree every core error maps to.
//!
//! The gymnasium environments (`socnav.make_vec`, `socnav.make`) are written in Python on top
//! of this class; everything about shapes comes from here, which takes it from the core's
//! `spec` module, so no shape is written twice.

// A user's input never panics: every internal invariant that would is marked with
// `#[expect(clippy::..., reason = "...")]` saying why it holds (clippy.toml lets unit tests).
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod aligned;
mod orca;
mod stepper;
mod viewer;

/// Large blocks 64-byte aligned, so that JAX takes the output buffers without a copy.
#[global_allocator]
static ALLOCATOR: aligned::CacheLineAligned = aligned::CacheLineAligned;

use stepper::{Job, OwnedActions, SendState, Stepper};

use ndarray::{ArrayView, Dimension, IxDyn};
use numpy::{
    Element, PyArray, PyArrayDyn, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use socnav::config::Kinematics;
use socnav::episodes::TABLE_KEYS;
use socnav::spec::{
    BOOL_INFO_KEYS, DISCRETE_ACTIONS, ENTITY_KEYS, EPISODE_KEYS, EVENT_KEYS, INFO_KEYS,
    INT_INFO_KEYS, INTERACTION_KEYS, OUTCOME_KEYS, RECORD,
};
use socnav::state::BatchState;
use socnav::{Actions, AutoresetMode, BatchEnv, Config, EnvOptions, SimError};
use std::sync::{Mutex, MutexGuard, TryLockError};

create_exception!(
    _socnav,
    SocNavError,
    PyException,
    "Base class of every socnav error."
);
create_exception!(
    _socnav,
    ConfigError,
    SocNavError,
    "An invalid configuration; the message lists every problem."
);
create_exception!(
    _socnav,
    ScenarioError,
    SocNavError,
    "A scenario could not be generated (the room is too crowded)."
);
create_exception!(
    _socnav,
    BackendUnavailableError,
    SocNavError,
    "The requested backend cannot run on this machine."
);
create_exception!(
    _socnav,
    DisplayError,
    SocNavError,
    "No window can be opened here (no display, or the display refused it)."
);
create_exception!(
    _socnav,
    SngnnError,
    SocNavError,
    "The SNGNN-v2 weights are missing or invalid; the message says how to install them."
);

create_exception!(
    _socnav,
    DeviceError,
    SocNavError,
    "The GPU failed during a run (lost, out of memory, a failed transfer); make a new batch."
);
create_exception!(
    _socnav,
    InternalError,
    SocNavError,
    "A bug in socnav (a broken internal invariant, caught); drop the batch and report the message."
);
create_exception!(
    _socnav,
    UsageError,
    SocNavError,
    "A call that does not fit the object it was made on (out of order, or missing what it needs)."
);

/// Exceptions that are socnav errors and also the builtin a Python caller expects (numpy's
/// `AxisError` is a `ValueError` and an `IndexError` the same way): made once, on first use.
struct DualErrors {
    shape: Py<PyType>,
    action: Py<PyType>,
    env_index: Py<PyType>,
}

static DUAL: PyOnceLock<DualErrors> = PyOnceLock::new();

fn dual_errors(py: Python<'_>) -> PyResult<&DualErrors> {
    DUAL.get_or_try_init(py, || {
        let base = py.get_type::<SocNavError>();
        let make =
            |name: &str, builtins: &[Bound<'_, PyType>], doc: &str| -> PyResult<Py<PyType>> {
                let mut bases = vec![base.clone()];
                bases.extend(builtins.iter().cloned());
                let dict = PyDict::new(py);
                dict.set_item("__doc__", doc)?;
                dict.set_item("__module__", "socnav._socnav")?;
                let ty = py
                    .get_type::<PyType>()
                    .call1((name, PyTuple::new(py, bases)?, dict))?;
                Ok(ty.cast_into::<PyType>()?.unbind())
            };
        let value = py.get_type::<PyValueError>();
        let index = py.get_type::<PyIndexError>();
        Ok(DualErrors {
            shape: make(
                "ShapeError",
                std::slice::from_ref(&value),
                "An argument, array or state document has the wrong shape, size or content \
                 (`what` names it). Also a ValueError.",
            )?,
            action: make(
                "ActionError",
                std::slice::from_ref(&value),
                "An invalid action (`env` names the environment, None for the array as a whole). \
                 Also a ValueError.",
            )?,
            env_index: make(
                "EnvIndexError",
                &[index, value],
                "An environment index outside the batch (`env`, `n_envs`). Also an IndexError \
                 and a ValueError.",
            )?,
        })
    })
}

/// `array`'s elements as one slice in C order, refused with `error` (a message naming what was
/// found) unless its shape is `shape` and its elements lie in C order. The flat slice is read as
/// rows, and rust-numpy's `as_slice` also takes a Fortran-ordered array, whose rows it would hand
/// over transposed.
fn c_order<'a, T: Element, D: Dimension>(
    array: &'a PyReadonlyArray<'_, T, D>,
    shape: &[usize],
    error: impl Fn(String) -> SimError,
) -> PyResult<&'a [T]> {
    let tuple = |dims: &[usize]| match dims {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            dims.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    if array.shape() != shape {
        return Err(py_err(error(format!(
            "expected an array of shape {}, got {}",
            tuple(shape),
            tuple(array.shape())
        ))));
    }
    match array.as_slice() {
        Ok(slice) if array.is_c_contiguous() => Ok(slice),
        _ => Err(py_err(error(format!(
            "expected an array in C order (np.ascontiguousarray), got strides {:?} bytes",
            array.strides()
        )))),
    }
}

/// An action error about the array as a whole.
fn action_error(message: String) -> SimError {
    SimError::action(None, message)
}

/// The Python exception for a core error, with the error's fields as attributes: `problems` (a
/// list of `(key, message)`, key None when the problem names none) on `ConfigError`, `env` and
/// `entity` on `ScenarioError`, `what` on `ShapeError`, `env` on `ActionError`, `env` and
/// `n_envs` on `EnvIndexError`; I/O errors are the `OSError` subclass of their kind
/// (`FileNotFoundError`, `PermissionError`, ...), with `filename`.
pub(crate) fn py_err(e: SimError) -> PyErr {
    Python::attach(|py| py_err_attached(py, e).unwrap_or_else(|failure| failure))
}

fn py_err_attached(py: Python<'_>, e: SimError) -> Result<PyErr, PyErr> {
    let msg = e.to_string();
    let with = |err: PyErr, attrs: &[(&str, Bound<'_, PyAny>)]| -> Result<PyErr, PyErr> {
        let value = err.value(py);
        for (name, v) in attrs {
            value.setattr(*name, v)?;
        }
        Ok(err)
    };
    let dual = |ty: &Py<PyType>| PyErr::from_type(ty.bind(py).clone(), msg.clone());
    Ok(match e {
        SimError::Config(problems) => {
            let list: Vec<(Option<String>, String)> =
                problems.into_iter().map(|p| (p.key, p.message)).collect();
            with(
                ConfigError::new_err(msg.clone()),
                &[("problems", list.into_pyobject(py)?.into_any())],
            )?
        }
        SimError::Scenario { env, entity, .. } => with(
            ScenarioError::new_err(msg.clone()),
            &[
                ("env", env.into_pyobject(py)?.into_any()),
                ("entity", entity.into_pyobject(py)?.into_any()),
            ],
        )?,
        SimError::Shape { what, .. } => with(
            dual(&dual_errors(py)?.shape),
            &[("what", what.into_pyobject(py)?.into_any())],
        )?,
        SimError::Action { env, .. } => with(
            dual(&dual_errors(py)?.action),
            &[("env", env.into_pyobject(py)?.into_any())],
        )?,
        SimError::EnvIndex { env, n_envs } => with(
            dual(&dual_errors(py)?.env_index),
            &[
                ("env", env.into_pyobject(py)?.into_any()),
                ("n_envs", n_envs.into_pyobject(py)?.into_any()),
            ],
        )?,
        SimError::Io {
            path,
            kind,
            message,
        } => {
            let err = PyErr::from(std::io::Error::new(kind, message.clone()));
            // OSError's str() reads errno and strerror once a filename is set.
            let value = err.value(py);
            value.setattr("errno", posix_errno(kind))?;
            value.setattr("strerror", message)?;
            if let Some(path) = path {
                value.setattr("filename", path)?;
            }
            err
        }
        SimError::OutOfMemory { bytes, device, .. } => with(
            pyo3::exceptions::PyMemoryError::new_err(msg.clone()),
            &[
                ("bytes", bytes.into_pyobject(py)?.into_any()),
                ("device", device.into_pyobject(py)?.into_any()),
            ],
        )?,
        SimError::BackendUnavailable(_) => BackendUnavailableError::new_err(msg),
        SimError::Device(_) => DeviceError::new_err(msg),
        SimError::Usage(_) => UsageError::new_err(msg),
        SimError::Internal(_) => InternalError::new_err(msg),
        SimError::Sngnn(_) => SngnnError::new_err(msg),
        SimError::Display(_) => DisplayError::new_err(msg),
        other => SocNavError::new_err(other.to_string()),
    })
}

/// The POSIX errno of an I/O error kind, for Python's `OSError.errno` (the same numbers on
/// Linux, macOS and Windows' C runtime for these kinds); `None` for the others.
fn posix_errno(kind: std::io::ErrorKind) -> Option<i32> {
    use std::io::ErrorKind as K;
    Some(match kind {
        K::NotFound => 2,
        K::PermissionDenied => 13,
        K::AlreadyExists => 17,
        K::NotADirectory => 20,
        K::IsADirectory => 21,
        K::StorageFull => 28,
        K::ReadOnlyFilesystem => 30,
        _ => return None,
    })
}

fn parse_autoreset(name: &str) -> PyResult<AutoresetMode> {
    match name {
        "next_step" => Ok(AutoresetMode::NextStep),
        "same_step" => Ok(AutoresetMode::SameStep),
        "disabled" => Ok(AutoresetMode::Disabled),
        other => Err(PyValueError::new_err(format!(
            "autoreset_mode must be 'next_step', 'same_step' or 'disabled', got {other:?}"
        ))),
    }
}

/// A batch of environments stepping together.
///
/// One concurrency model: a batch is idle, busy (a call holds it: a step, a reset, a state
/// load, ... while the GIL is released; or a step sent with `send_*` and not yet received with
/// `recv`) or closed. A call that arrives while another is in flight (from another thread, or
/// between `send_*` and `recv`) raises `UsageError` at once instead of waiting or racing; a
/// closed batch raises `UsageError` for every call but `close`. A batch belongs to the process
/// that made it: its worker threads and GPU device do not survive `fork`, so a forked child's
/// calls raise `UsageError`.
#[pyclass(module = "socnav._socnav", frozen)]
struct Batch {
    inner: Mutex<Inner>,
    /// Whether a step was sent (`send_*`) and not yet received (`recv`).
    send_state: SendState,
    /// The thread that runs sent steps, made at the first `send_*`.
    stepper: Mutex<Option<Stepper>>,
    /// The process that made the batch.
    pid: u32,
    n_envs: usize,
}

/// What the lock of a [`Batch`] guards.
struct Inner {
    env: BatchEnv,
    /// The ORCA-driven robot's scratch state, made on its first use.
    orca: socnav::policies::OrcaRobot,
    /// Why the batch is closed (`close()`, or its device was lost), or `None` while usable.
    closed: Option<String>,
}

impl Batch {
    /// The batch, held for one call: `UsageError` if another call holds it, if it is closed, or
    /// in a process forked after it was made.
    fn lock(&self) -> PyResult<MutexGuard<'_, Inner>> {
        self.check_process()?;
        let inner = match self.inner.try_lock() {
            Ok(inner) => inner,
            Err(TryLockError::WouldBlock) => {
                // A sent step may still hold the batch on the stepper's thread: the caller is
                // told about the send, whether or not the step has finished yet.
                let why = self.send_state.busy().unwrap_or(
                    "the batch is busy: another call on it (a step or reset from another thread) \
                     is in flight; calls on one batch must not overlap",
                );
                return Err(UsageError::new_err(why));
            }
            Err(TryLockError::Poisoned(_)) => {
                return Err(InternalError::new_err(
                    "an earlier call on this batch panicked, so its state is unknown; make a new \
                     batch (and please report the panic)",
                ));
            }
        };
        if let Some(why) = &inner.closed {
            return Err(UsageError::new_err(format!("the batch is closed ({why})")));
        }
        // Read while holding the batch: `send` sets it before it lets go of the batch.
        if let Some(why) = self.send_state.busy() {
            return Err(UsageError::new_err(why));
        }
        Ok(inner)
    }

    /// `UsageError` in a process forked after the batch was made.
    fn check_process(&self) -> PyResult<()> {
        let pid = std::process::id();
        if pid != self.pid {
            return Err(UsageError::new_err(format!(
                "this batch was made in process {} and cannot be used in process {pid}, forked \
                 from it: its worker threads and GPU device stay with the parent. Make the batch \
                 in the child, or start workers with the 'spawn' or 'forkserver' method",
                self.pid
            )));
        }
        Ok(())
    }

    /// Start stepping the batch with `actions` on its stepper thread and return: a bad action
    /// is refused here, and the step's own error is `recv`'s.
    fn send(slf: &Bound<'_, Self>, actions: OwnedActions) -> PyResult<()> {
        let batch = slf.get();
        let mut inner = batch.lock()?;
        let checked = inner.env.check_actions(actions.as_actions());
        inner.check(checked)?;
        let mut stepper = batch
            .stepper
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if stepper.is_none() {
            *stepper = Some(Stepper::start().map_err(py_err)?);
        }
        let job = Job {
            owner: slf.clone().unbind(),
            actions,
        };
        if let Some(stepper) = stepper.as_ref() {
            stepper.send(job).map_err(py_err)?;
        }
        // Marked while the batch is held, so every call from here to `recv` is refused; the
        // stepper takes the batch once it is let go of.
        batch.send_state.sent();
        Ok(())
    }

    /// Wait for the sent step (`SendState::claim` first) and return its result.
    fn wait_for_sent(&self, py: Python<'_>) -> PyResult<Result<(), SimError>> {
        let result = py.detach(|| {
            let stepper = self
                .stepper
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            stepper.as_ref().map(Stepper::recv)
        });
        self.send_state.received();
        result.ok_or_else(|| InternalError::new_err("a step was sent without a stepper thread"))
    }
}

impl Inner {
    /// The batch state (downloaded from a GPU), or the error, which closes the batch when the
    /// device is lost.
    fn state(&mut self) -> PyResult<&BatchState> {
        // Checked first and read again: a reference returned from one branch of a match on it
        // would hold the borrow that `check` needs.
        let downloaded = self.env.state().map(|_| ());
        self.check(downloaded)?;
        self.env.state().map_err(py_err)
    }

    /// `result` as a Python error; a lost device closes the batch (it cannot step again).
    fn check<T>(&mut self, result: Result<T, SimError>) -> PyResult<T> {
        if let Err(SimError::Device(why)) = &result {
            self.closed = Some(format!("its GPU device failed: {why}"));
        }
        result.map_err(py_err)
    }
}

/// An array over `data` with `shape`, owned by the `Batch` object `owner`.
#[expect(
    clippy::expect_used,
    reason = "the output buffers are allocated with the shapes the spec gives them"
)]
fn borrowed<'py, T: Element>(
    owner: &Bound<'py, Batch>,
    data: &[T],
    shape: &[usize],
) -> Bound<'py, PyArrayDyn<T>> {
    let view =
        ArrayView::from_shape(IxDyn(shape), data).expect("output buffer of the stated shape");
    // SAFETY: `data` is an output buffer of the batch that `owner` holds: it is allocated once
    // with the batch and never reallocated, and the array keeps `owner` alive.
    #[allow(
        unsafe_code,
        reason = "zero-copy arrays over the batch's output buffers"
    )]
    unsafe {
        PyArray::borrow_from_array(&view, owner.clone().into_any())
    }
}

#[pymethods]
impl Batch {
    /// `config`: a shipped config name or a TOML path, or with `toml_text` only a label (the
    /// config is then that TOML text); `overrides`: a JSON object of keys applied on top
    /// (`Config::with_overrides`).
    #[new]
    #[pyo3(signature = (config, num_envs, seed=0, autoreset_mode="next_step", threads=None, overrides=None, toml_text=None, backend="cpu"))]
    #[allow(
        clippy::too_many_arguments,
        reason = "the Python constructor's keyword arguments"
    )]
    fn new(
        config: &str,
        num_envs: usize,
        seed: u64,
        autoreset_mode: &str,
        threads: Option<usize>,
        overrides: Option<&str>,
        toml_text: Option<&str>,
        backend: &str,
    ) -> PyResult<Self> {
        let backend: socnav::backend::BackendChoice = backend
            .parse()
            .map_err(|e: String| pyo3::exceptions::PyValueError::new_err(e))?;
        let mut c = match toml_text {
            Some(text) => Config::from_toml_str(text),
            None => Config::from_name_or_path(config),
        }
        .map_err(py_err)?;
        if let Some(text) = overrides {
            let json: serde_json::Value = serde_json::from_str(text)
                .map_err(|e| py_err(SimError::config([format!("overrides are not JSON: {e}")])))?;
            c = c.with_overrides(&json).map_err(py_err)?;
        }
        let options = EnvOptions {
            n_envs: num_envs,
            seed,
            autoreset: parse_autoreset(autoreset_mode)?,
            threads,
            backend,
        };
        let env = BatchEnv::new(c, options).map_err(py_err)?;
        Ok(Self {
            n_envs: env.n_envs(),
            inner: Mutex::new(Inner {
                env,
                orca: socnav::policies::OrcaRobot::new(),
                closed: None,
            }),
            send_state: SendState::default(),
            stepper: Mutex::new(None),
            pid: std::process::id(),
        })
    }

    /// Close the batch: every later call but `close` raises `UsageError`. Closing twice does
    /// nothing; closing while another thread's call is in flight raises `UsageError`; a step sent
    /// and not received is waited for, and its result dropped.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        if std::process::id() != self.pid {
            return Ok(()); // a forked child's copy: nothing of it is usable anyway
        }
        if self.send_state.claim().is_ok() {
            let _ = self.wait_for_sent(py)?;
        }
        let mut inner = match self.inner.try_lock() {
            Ok(inner) => inner,
            Err(TryLockError::Poisoned(poisoned)) => poisoned.into_inner(),
            Err(TryLockError::WouldBlock) => {
                return Err(UsageError::new_err(
                    "cannot close the batch while another call on it is in flight",
                ));
            }
        };
        inner
            .closed
            .get_or_insert_with(|| "close() was called".to_owned());
        Ok(())
    }

    /// Whether the batch is closed (`close()`, or its GPU device was lost).
    #[getter]
    fn closed(&self) -> bool {
        match self.inner.try_lock() {
            Ok(inner) => inner.closed.is_some(),
            Err(TryLockError::Poisoned(poisoned)) => poisoned.into_inner().closed.is_some(),
            Err(TryLockError::WouldBlock) => false,
        }
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.n_envs
    }

    /// The backend stepping the batch (`"cpu"`).
    #[getter]
    fn backend(&self) -> PyResult<&'static str> {
        Ok(self.lock()?.env.backend_name())
    }

    /// What runs the batch: the CPU threads, or the GPU adapter.
    #[getter]
    fn device(&self) -> PyResult<String> {
        Ok(self.lock()?.env.device())
    }

    /// The time step (s).
    #[getter]
    fn time_step(&self) -> PyResult<f32> {
        Ok(self.lock()?.env.params().dt)
    }

    /// Whether the robot is holonomic (else differential drive: the lateral action must be 0).
    #[getter]
    fn holonomic(&self) -> PyResult<bool> {
        Ok(self.lock()?.env.config().robot.kinematics == Kinematics::Holonomic)
    }

    /// The resolved config as TOML (every key).
    fn config_toml(&self) -> PyResult<String> {
        Ok(self.lock()?.env.config().to_toml_string())
    }

    /// The observation layout: `dim`, `robot` (robot record length), `record` (14), `padded`
    /// (every type padded to its capacity, walls omitted), and per
    /// entity key its `offset` and `capacity` (records), plus the interaction pair capacities.
    fn layout<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let inner = self.lock()?;
        let l = inner.env.layout();
        let d = PyDict::new(py);
        d.set_item("dim", l.dim)?;
        d.set_item("robot", l.robot)?;
        d.set_item("record", RECORD)?;
        d.set_item("padded", inner.env.config().observation.padded)?;
        let entities = PyDict::new(py);
        for (t, key) in ENTITY_KEYS.iter().enumerate() {
            entities.set_item(*key, (l.offset[t], l.capacity[t]))?;
        }
        d.set_item("entities", entities)?;
        let pairs = PyDict::new(py);
        for (k, key) in INTERACTION_KEYS.iter().enumerate() {
            pairs.set_item(*key, l.pairs[k])?;
        }
        d.set_item("pairs", pairs)?;
        Ok(d)
    }

    /// Key names: `info`, `episode`, `events`, `entities`, `interactions` (the orders of the
    /// output columns), `table` (the paper's metrics in the order `socnav run` reports them),
    /// `bool_info` and `int_info` (the info keys 0.1.1 reports as booleans and integers) and
    /// `outcomes` (the episode statistics that are outcome flags).
    #[staticmethod]
    fn keys<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("info", INFO_KEYS.to_vec())?;
        d.set_item("episode", EPISODE_KEYS.to_vec())?;
        d.set_item("events", EVENT_KEYS.to_vec())?;
        d.set_item("entities", ENTITY_KEYS.to_vec())?;
        d.set_item("interactions", INTERACTION_KEYS.to_vec())?;
        d.set_item("table", TABLE_KEYS.to_vec())?;
        d.set_item("bool_info", BOOL_INFO_KEYS.to_vec())?;
        d.set_item("int_info", INT_INFO_KEYS.to_vec())?;
        d.set_item("outcomes", OUTCOME_KEYS.to_vec())?;
        Ok(d)
    }

    /// Reset every environment: with `seed`, environment i plays the episode of seed
    /// `seed + i`; without, each plays the next episode of its seed sequence.
    #[pyo3(signature = (seed=None))]
    fn reset(&self, py: Python<'_>, seed: Option<u64>) -> PyResult<()> {
        let mut inner = self.lock()?;
        let env = &mut inner.env;
        let result = py.detach(|| env.reset(seed));
        inner.check(result)
    }

    /// Name the episode each environment plays at its next reset: one entry per environment, an
    /// int in 0..2**64 (its episode seed) or None (keep its sequence).
    fn set_next_seeds(&self, seeds: Vec<Option<u64>>) -> PyResult<()> {
        let mut inner = self.lock()?;
        let result = inner.env.set_next_seeds(&seeds);
        inner.check(result)
    }

    /// Reset the environments where `mask` is true.
    fn reset_envs(&self, py: Python<'_>, mask: PyReadonlyArray1<'_, bool>) -> PyResult<()> {
        let mask = c_order(&mask, &[self.n_envs], |m| SimError::shape("reset mask", m))?.to_vec();
        let mut inner = self.lock()?;
        let env = &mut inner.env;
        let result = py.detach(|| env.reset_envs(&mask));
        inner.check(result)
    }

    /// One step with continuous actions: float32 `(num_envs, 3)` in [-1, 1] (forward, lateral,
    /// rotation). The GIL is released while the batch steps.
    fn step_continuous(&self, py: Python<'_>, actions: PyReadonlyArray2<'_, f32>) -> PyResult<()> {
        let actions = c_order(&actions, &[self.n_envs, 3], action_error)?;
        let mut inner = self.lock()?;
        let env = &mut inner.env;
        let result = py.detach(|| env.step(Actions::Continuous(actions)));
        inner.check(result)
    }

    /// One step with discrete actions: uint32 `(num_envs,)` in 0..7.
    fn step_discrete(&self, py: Python<'_>, actions: PyReadonlyArray1<'_, u32>) -> PyResult<()> {
        let actions = c_order(&actions, &[self.n_envs], action_error)?;
        let mut inner = self.lock()?;
        let env = &mut inner.env;
        let result = py.detach(|| env.step(Actions::Discrete(actions)));
        inner.check(result)
    }

    /// Start a step with continuous actions (as `step_continuous`) on a thread of the batch's
    /// own and return at once; `recv` waits for it. Until then every other call on the batch
    /// raises `UsageError`, and its output arrays are being written: read them after `recv`.
    fn send_continuous(slf: &Bound<'_, Self>, actions: PyReadonlyArray2<'_, f32>) -> PyResult<()> {
        let n_envs = slf.get().n_envs;
        let actions = c_order(&actions, &[n_envs, 3], action_error)?.to_vec();
        Self::send(slf, OwnedActions::Continuous(actions))
    }

    /// Start a step with discrete actions (as `step_discrete`); see `send_continuous`.
    fn send_discrete(slf: &Bound<'_, Self>, actions: PyReadonlyArray1<'_, u32>) -> PyResult<()> {
        let n_envs = slf.get().n_envs;
        let actions = c_order(&actions, &[n_envs], action_error)?.to_vec();
        Self::send(slf, OwnedActions::Discrete(actions))
    }

    /// Wait for the step `send_*` started (the GIL released) and raise its error, if any; the
    /// output buffers then hold its results. `UsageError` when no step was sent.
    fn recv(&self, py: Python<'_>) -> PyResult<()> {
        // A forked child's copy has no stepper thread to wait for.
        self.check_process()?;
        if let Err(why) = self.send_state.claim() {
            // A closed batch, or one in use by another thread, says so first.
            drop(self.lock()?);
            return Err(UsageError::new_err(why));
        }
        let result = self.wait_for_sent(py)?;
        let mut inner = self.lock()?;
        inner.check(result)
    }

    /// The output buffers as arrays without copies, by name: `obs` `(n, dim)`, `obs_count`
    /// `(n, 5)`, `reward` `(n,)`, `terminated`, `truncated` (uint32 `(n,)`), `info` `(n, 32)`,
    /// `has_final`, `final_obs`, `final_obs_count`, `final_info` (SAME_STEP), `episode_done`,
    /// `episode` `(n, 32)`, `episode_seed_lo`, `episode_seed_hi` (uint32 `(n,)`: the words of the
    /// seed of the episode that ended), `events` `(n, 9)`, `hh_pairs`, `hl_pairs`, `pair_count` and their
    /// `final_*` copies. Overwritten in place by every step and reset.
    fn buffers<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        let py = slf.py();
        let inner = slf.get().lock()?;
        let o = inner.env.outputs();
        let n = inner.env.n_envs();
        let st = &o.strides;
        let d = PyDict::new(py);
        let f32s: [(&str, &[f32], usize); 5] = [
            ("obs", &o.obs, st.layout.dim),
            ("final_obs", &o.final_obs, st.layout.dim),
            ("info", &o.info, st.info()),
            ("final_info", &o.final_info, st.info()),
            ("episode", &o.episode, st.episode()),
        ];
        for (name, data, width) in f32s {
            d.set_item(name, borrowed(slf, data, &[n, width]))?;
        }
        d.set_item("reward", borrowed(slf, &o.reward, &[n]))?;
        let u32s: [(&str, &[u32], usize); 9] = [
            ("obs_count", &o.obs_count, 5),
            ("final_obs_count", &o.final_obs_count, 5),
            ("hh_pairs", &o.hh_pairs, st.hh()),
            ("final_hh_pairs", &o.final_hh_pairs, st.hh()),
            ("hl_pairs", &o.hl_pairs, st.hl()),
            ("final_hl_pairs", &o.final_hl_pairs, st.hl()),
            ("pair_count", &o.pair_count, st.pairs()),
            ("final_pair_count", &o.final_pair_count, st.pairs()),
            ("events", &o.events, st.events()),
        ];
        for (name, data, width) in u32s {
            d.set_item(name, borrowed(slf, data, &[n, width]))?;
        }
        for (name, data) in [
            ("terminated", &o.terminated),
            ("truncated", &o.truncated),
            ("has_final", &o.has_final),
            ("episode_done", &o.episode_done),
            ("episode_seed_lo", &o.episode_seed_lo),
            ("episode_seed_hi", &o.episode_seed_hi),
        ] {
            d.set_item(name, borrowed(slf, data, &[n]))?;
        }
        Ok(d)
    }

    /// The actions of a built-in policy for the current step, float32 `(num_envs, 3)`:
    /// `"goal"` (the go-to-goal controller, from the observations) or `"orca"` (the velocity ORCA
    /// gives the robot toward its goal, from the state; the GPU backend downloads it).
    fn policy_actions<'py>(
        &self,
        py: Python<'py>,
        policy: &str,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f32>>> {
        let n = self.n_envs;
        let mut actions = vec![0.0f32; 3 * n];
        let mut guard = self.lock()?;
        let inner = &mut *guard;
        let (env, orca) = (&inner.env, &mut inner.orca);
        match policy {
            "goal" => socnav::policies::goal_actions(env, &mut actions),
            "orca" => {
                let result = py.detach(|| orca.actions(env, &mut actions));
                inner.check(result)?;
            }
            other => {
                return Err(PyValueError::new_err(format!(
                    "policy must be 'goal' or 'orca', got {other:?}"
                )));
            }
        }
        let array = numpy::ndarray::Array2::from_shape_vec((n, 3), actions)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(numpy::PyArray2::from_owned_array(py, array))
    }

    /// Environment `env` seen from above (`socnav::render`), `size` px on its longer side, with
    /// the robot's `trail` (float32 `(k, 2)`, world metres) drawn: uint8 `(H, W, 3)`.
    #[pyo3(signature = (env, size=400, trail=None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        env: usize,
        size: u32,
        trail: Option<PyReadonlyArray2<'_, f32>>,
    ) -> PyResult<Bound<'py, numpy::PyArray3<u8>>> {
        let trail: Vec<(f32, f32)> = match &trail {
            Some(t) => {
                let view = t.as_array();
                if view.ncols() != 2 {
                    return Err(PyValueError::new_err(format!(
                        "trail must have shape (k, 2) (world x, y in m), got {:?}",
                        view.shape()
                    )));
                }
                view.rows().into_iter().map(|r| (r[0], r[1])).collect()
            }
            None => Vec::new(),
        };
        let mut inner = self.lock()?;
        let params = *inner.env.params();
        let pixmap =
            socnav::render::draw(&params, inner.state()?, env, &trail, size).map_err(py_err)?;
        let (w, h) = (pixmap.width() as usize, pixmap.height() as usize);
        // Every pixel is opaque (the background is painted first): premultiplied RGB is RGB.
        let rgb: Vec<u8> = pixmap
            .data()
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let array = numpy::ndarray::Array3::from_shape_vec((h, w, 3), rgb)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(numpy::PyArray3::from_owned_array(py, array))
    }

    /// The robot's pose of every environment: float32 `(n, 3)`, x and y (m), heading (rad),
    /// world frame (read from the state; the GPU backend downloads it).
    fn robot_poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f32>>> {
        let mut inner = self.lock()?;
        let s = inner.state()?;
        let poses: Vec<f32> = (0..s.n_envs)
            .flat_map(|e| [s.robot_x[e], s.robot_y[e], s.robot_theta[e]])
            .collect();
        let array = numpy::ndarray::Array2::from_shape_vec((s.n_envs, 3), poses)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(numpy::PyArray2::from_owned_array(py, array))
    }

    /// Time every stage of the step (two clock reads per stage and chunk; off by default).
    fn set_stage_timing(&self, on: bool) -> PyResult<()> {
        self.lock()?.env.set_stage_timing(on);
        Ok(())
    }

    /// Deliver only these optional per-step outputs from the next step on (every one by
    /// default; `BatchEnv::set_step_outputs`): `info`, the interactions (`hh_pairs`,
    /// `hl_pairs`, `pair_count`) and `events`. A buffer left out is not kept current.
    #[pyo3(signature = (*, info=true, interactions=true, events=true))]
    fn set_step_outputs(&self, info: bool, interactions: bool, events: bool) -> PyResult<()> {
        self.lock()?
            .env
            .set_step_outputs(socnav::outputs::StepOutputs {
                info,
                interactions,
                events,
            });
        Ok(())
    }

    /// Seconds spent per stage while stage timing was on: `{stage name: seconds}`.
    fn stage_seconds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, seconds) in self.lock()?.env.stage_seconds() {
            d.set_item(name, seconds)?;
        }
        Ok(d)
    }

    /// One environment's state as a JSON document (`BatchEnv::get_state`).
    fn get_state(&self, env: usize) -> PyResult<String> {
        let mut inner = self.lock()?;
        let doc = inner.env.get_state(env);
        Ok(inner.check(doc)?.to_string())
    }

    /// Load one environment's state from a JSON document (`BatchEnv::set_state`).
    fn set_state(&self, env: usize, doc: &str) -> PyResult<()> {
        let doc: serde_json::Value = serde_json::from_str(doc)
            .map_err(|e| PyValueError::new_err(format!("state document is not JSON: {e}")))?;
        let mut inner = self.lock()?;
        let result = inner.env.set_state(env, &doc);
        inner.check(result)
    }
}

/// Write `frames` (uint8 `(H, W, 3)`, all of one size) to `path` as a looping animated GIF,
/// `frame_ms` milliseconds per frame (socnav's GIF writer: one palette per frame).
#[pyfunction]
fn write_gif(
    py: Python<'_>,
    path: std::path::PathBuf,
    frames: Vec<numpy::PyReadonlyArray3<'_, u8>>,
    frame_ms: u32,
) -> PyResult<usize> {
    let Some(first) = frames.first() else {
        return Err(PyValueError::new_err("write_gif needs at least one frame"));
    };
    let shape = first.as_array().shape().to_vec();
    if shape[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "frames must be (H, W, 3) uint8, got {shape:?}"
        )));
    }
    let (h, w) = (shape[0] as u32, shape[1] as u32);
    let mut pixmaps = Vec::with_capacity(frames.len());
    for (i, f) in frames.iter().enumerate() {
        if f.as_array().shape() != shape.as_slice() {
            return Err(PyValueError::new_err(format!(
                "frame {i} has shape {:?}, frame 0 {shape:?}: all frames must have one size",
                f.as_array().shape()
            )));
        }
        let mut pm = socnav::render::Pixmap::new(w, h)
            .ok_or_else(|| PyValueError::new_err(format!("frames of {w}x{h} px")))?;
        let rgb = f.as_array();
        for (px, (y, x)) in pm
            .data_mut()
            .chunks_exact_mut(4)
            .zip((0..h as usize).flat_map(|y| (0..w as usize).map(move |x| (y, x))))
        {
            px.copy_from_slice(&[rgb[[y, x, 0]], rgb[[y, x, 1]], rgb[[y, x, 2]], 255]);
        }
        pixmaps.push(pm);
    }
    py.detach(|| {
        let mut gif = socnav::render::GifWriter::create(&path, w, h, frame_ms)?;
        for pm in &pixmaps {
            gif.push(pm)?;
        }
        let n = gif.frames();
        gif.finish()?;
        Ok::<usize, SimError>(n)
    })
    .map_err(py_err)
}

/// A SocNavGym 0.1.1 config (its YAML parsed and given as JSON text) as socnav TOML.
#[pyfunction]
fn socnavgym_config_toml(yaml_json: &str) -> PyResult<String> {
    let yaml: serde_json::Value = serde_json::from_str(yaml_json).map_err(|e| {
        py_err(SimError::config([format!(
            "the SocNavGym config is not JSON: {e}"
        )]))
    })?;
    let c = Config::from_socnavgym(&yaml).map_err(py_err)?;
    Ok(c.to_toml_string())
}

/// A config (a shipped name, a TOML file or a SocNavGym 0.1.1 YAML file) resolved and validated,
/// as socnav TOML with every default written out.
#[pyfunction]
fn config_toml(config: &str) -> PyResult<String> {
    let c = Config::from_name_or_path(config).map_err(py_err)?;
    Ok(c.to_toml_string())
}

/// The SNGNN-v2 weight file socnav would load (`SOCNAV_SNGNN_WEIGHTS`, else the cache; a
/// config's `reward.sngnn_weights` comes between them) and the cache file an install writes.
#[pyfunction]
fn sngnn_paths() -> (String, String) {
    let resolved = socnav::sngnn::weights_path(None).path;
    let cached = socnav::sngnn::cached_weights(&socnav::sngnn::cache_dir());
    (resolved.display().to_string(), cached.display().to_string())
}

/// Copy the SNGNN-v2 weights out of the socnavgym 0.1.1 wheel at `wheel` into `dest`,
/// atomically and checked; returns the number of parameters.
#[pyfunction]
fn sngnn_install_from_wheel(py: Python<'_>, wheel: &str, dest: &str) -> PyResult<usize> {
    let (wheel, dest) = (
        std::path::PathBuf::from(wheel),
        std::path::PathBuf::from(dest),
    );
    py.detach(|| socnav::sngnn::install_from_wheel(&wheel, &dest))
        .map(|w| w.parameters())
        .map_err(py_err)
}

/// The shipped config names.
#[pyfunction]
fn shipped_configs() -> Vec<&'static str> {
    Config::shipped_names().collect()
}

#[pymodule]
fn _socnav(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<Batch>()?;
    m.add_function(wrap_pyfunction!(shipped_configs, m)?)?;
    m.add_function(wrap_pyfunction!(socnavgym_config_toml, m)?)?;
    m.add_function(wrap_pyfunction!(config_toml, m)?)?;
    m.add_function(wrap_pyfunction!(sngnn_paths, m)?)?;
    m.add_function(wrap_pyfunction!(sngnn_install_from_wheel, m)?)?;
    m.add_function(wrap_pyfunction!(write_gif, m)?)?;
    m.add(
        "DISCRETE_ACTIONS",
        DISCRETE_ACTIONS.map(|a| a.to_vec()).to_vec(),
    )?;
    orca::register(m)?;
    viewer::register(m)?;
    m.add("SocNavError", py.get_type::<SocNavError>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("ScenarioError", py.get_type::<ScenarioError>())?;
    m.add(
        "BackendUnavailableError",
        py.get_type::<BackendUnavailableError>(),
    )?;
    m.add("SngnnError", py.get_type::<SngnnError>())?;
    m.add("DisplayError", py.get_type::<DisplayError>())?;
    m.add("DeviceError", py.get_type::<DeviceError>())?;
    m.add("UsageError", py.get_type::<UsageError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    let dual = dual_errors(py)?;
    m.add("ShapeError", dual.shape.bind(py))?;
    m.add("ActionError", dual.action.bind(py))?;
    m.add("EnvIndexError", dual.env_index.bind(py))?;
    Ok(())
}
